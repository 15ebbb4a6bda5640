"""Side-by-side timing of index functions (used by the surrogate run and the benchmark)."""

from __future__ import annotations

import time
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array


def tile_batch(q: Array, n: int) -> Array:
    """``(n, n_joints)`` float32 timing batch: the configurations ``q: (m, n_joints)`` repeated."""
    q = jnp.asarray(q, jnp.float32)
    if q.ndim != 2 or q.shape[0] == 0:
        raise ValueError(f"q must have shape (m, n_joints) with m > 0, got {q.shape}")
    if n < 1:
        raise ValueError(f"n must be positive, got {n}")
    return jnp.tile(q, (-(-n // q.shape[0]), 1))[:n]


def chunk_for(n: int, chunk: int) -> int | None:
    """The chunk size :func:`time_index_fn` uses for a batch of ``n``: ``chunk`` where ``n`` is a
    larger multiple of it, else None (one call)."""
    return chunk if n > chunk and n % chunk == 0 else None


def time_index_fn(fn: Callable[[Array], Array], q: Array, *, repeats: int = 5, chunk: int | None = None,
                  min_run_seconds: float = 0.02) -> dict:
    """Wall time of ``fn(q)`` for a batch ``q: (N, n_joints)``, compiled once beforehand.

    Each timed run issues as many calls back to back as fill about ``min_run_seconds`` and
    waits once, so a call of a fraction of a millisecond (a GPU at 1e7) is not timed together
    with the host's dispatch and wait.

    Args:
      fn: ``q: (..., n_joints) → (...)`` index function (jitted here).
      q: ``(N, ...)`` inputs, already on the device (configurations, or whatever ``fn`` takes).
      repeats: timed runs; the median is reported.
      chunk: if given, evaluate in chunks of this many rows (``lax.map``) to bound memory.
      min_run_seconds: least length of one timed run [s].

    Returns:
      ``{"seconds": median per call, "min_seconds", "compile_seconds", "per_second": N / median}``.
    """
    n = q.shape[0]
    if chunk is not None and chunk < n:
        if n % chunk:
            raise ValueError(f"batch {n} is not a multiple of chunk {chunk}")
        f = jax.jit(lambda q: jax.lax.map(fn, q.reshape(n // chunk, chunk, -1)).reshape(n))
    else:
        f = jax.jit(fn)
    t0 = time.perf_counter()
    f(q).block_until_ready()
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    f(q).block_until_ready()
    calls = max(1, int(min_run_seconds / max(time.perf_counter() - t0, 1e-9)))
    times = []
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        for _ in range(calls):
            out = f(q)
        out.block_until_ready()
        times.append((time.perf_counter() - t0) / calls)
    med = float(np.median(times))
    return {"seconds": med, "min_seconds": float(np.min(times)), "compile_seconds": compile_s, "per_second": n / med}


def xla_flops_per_sample(fn: Callable[[Array], Array], q: Array) -> float | None:
    """Floating-point operations per sample of ``fn`` on ``q: (N, n_joints)`` from XLA's cost
    analysis (transcendentals not included); None where the backend gives no estimate."""
    try:
        cost = jax.jit(fn).lower(q).compile().cost_analysis()
    except Exception:  # noqa: BLE001 - cost analysis is best-effort and backend-specific
        return None
    if isinstance(cost, (list, tuple)):
        cost = cost[0] if cost else None
    if not cost or "flops" not in cost:
        return None
    return float(cost["flops"]) / q.shape[0]
