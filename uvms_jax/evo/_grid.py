"""Dense grid search: the brute-force reference optimum of the docking problem.

The grid is never materialised: candidates are decoded from their flat index inside a
jitted ``lax.fori_loop`` over chunks of ``chunk_size`` candidates, so memory is bounded by
one chunk whatever the grid size (1e6 on a laptop CPU, 1e8+ on a GPU).
"""

from __future__ import annotations

from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array


class GridResult(NamedTuple):
    """Best candidate of a grid search.

    Attributes:
      x: ``(m,)`` best grid point (a docking pose ``[x, y, z, ψ]``).
      fitness: ``()`` its fitness.
      n_candidates: number of grid points evaluated.
      low, high: ``(m,)`` the box searched.
    """

    x: Array
    fitness: Array
    n_candidates: int
    low: Array
    high: Array


def grid_axes(low, high, counts, periodic) -> list[np.ndarray]:
    """Per-variable grid values: ``counts[i]`` points from ``low[i]`` to ``high[i]`` inclusive,
    or, for a periodic variable, ``high[i]`` excluded (it equals ``low[i]``)."""
    return [
        np.linspace(lo, hi, n, endpoint=not per) if n > 1 else np.array([(lo + hi) / 2])
        for lo, hi, n, per in zip(np.asarray(low), np.asarray(high), counts, periodic)
    ]


def _grid_point(flat: Array, low: Array, step: Array, counts: Array) -> Array:
    """Grid point of flat (row-major) index ``flat (n,)`` → ``(n, m)``; ``counts`` is traced, so
    one compiled search serves every grid size and every refinement box."""
    strides = jnp.cumprod(jnp.concatenate([counts[1:], jnp.ones((1,), counts.dtype)])[::-1])[::-1]
    idx = (flat[:, None] // strides) % counts
    return low + idx.astype(low.dtype) * step


@partial(jax.jit, static_argnames=("chunk_size",))
def _search(problem: Any, low: Array, step: Array, counts: Array, chunk_size: int):
    n = jnp.prod(counts)
    n_chunks = (n + chunk_size - 1) // chunk_size

    def body(c, best):
        best_x, best_f = best
        flat = c * chunk_size + jnp.arange(chunk_size, dtype=counts.dtype)
        inside = flat < n
        x = _grid_point(jnp.where(inside, flat, 0), low, step, counts)
        f = jnp.where(inside, problem.fitness(x), -jnp.inf)
        f = jnp.where(jnp.isnan(f), -jnp.inf, f)
        i = jnp.argmax(f)
        better = f[i] > best_f  # strict: ties keep the lowest flat index
        return jnp.where(better, x[i], best_x), jnp.where(better, f[i], best_f)

    init = (low, jnp.asarray(-jnp.inf, dtype=low.dtype))
    return jax.lax.fori_loop(0, n_chunks, body, init)


def grid_search(
    problem: Any,
    low,
    high,
    counts: tuple[int, ...],
    periodic: tuple[bool, ...] | None = None,
    chunk_size: int = 16384,
) -> GridResult:
    """Exhaustive search of ``problem.fitness`` over a regular grid, in chunks.

    Args:
      problem: pytree with ``fitness((n, m)) -> (n,)`` (to maximise), e.g. a docking problem.
      low, high: ``(m,)`` box corners.
      counts: points per variable; ``prod(counts)`` candidates (must fit int32).
      periodic: per variable, whether ``high`` wraps to ``low`` (then it is not sampled
        twice); default: none.
      chunk_size: candidates per jitted evaluation (memory bound); the compiled search depends
        only on it (and the problem's shapes), not on ``counts`` or the box.

    Returns:
      :class:`GridResult`; ties go to the candidate with the lowest flat (row-major) index.
    """
    counts = tuple(int(c) for c in counts)
    low = jnp.asarray(low)
    high = jnp.asarray(high, dtype=low.dtype)
    if low.shape != (len(counts),) or high.shape != low.shape:
        raise ValueError(f"low/high must have shape ({len(counts)},), got {low.shape} and {high.shape}")
    if any(c < 1 for c in counts) or chunk_size < 1:
        raise ValueError(f"counts and chunk_size must be positive, got {counts} and {chunk_size}")
    n = int(np.prod(counts, dtype=np.int64))
    if n >= 2**31:
        raise ValueError(f"grid of {n} candidates exceeds int32 indexing; split the box")
    periodic = tuple(periodic) if periodic is not None else (False,) * len(counts)
    divisions = [(c if per else c - 1) for c, per in zip(counts, periodic)]
    step = jnp.asarray([1.0 / max(k, 1) for k in divisions], dtype=low.dtype) * (high - low)
    # A single point per axis sits at the box centre.
    low_eff = jnp.where(jnp.asarray(counts) == 1, (low + high) / 2, low)
    x, f = _search(problem, low_eff, step, jnp.asarray(counts, dtype=jnp.int32), chunk_size)
    return GridResult(x=x, fitness=f, n_candidates=n, low=low, high=high)


def refine_grid_search(
    problem: Any,
    result: GridResult,
    counts: tuple[int, ...],
    stages: int,
    shrink: float = 0.25,
    chunk_size: int = 16384,
) -> list[GridResult]:
    """Zoom stages after a global grid search: each stage grids a box ``shrink`` times the
    previous one's size centred on the best point so far (clipped to the original box).

    A local polish of the reference optimum (the global stage decides the basin); returns one
    :class:`GridResult` per stage, each at least as good as the previous.
    """
    out = []
    lo0, hi0 = result.low, result.high
    width = hi0 - lo0
    best = result
    for _ in range(stages):
        width = width * shrink
        lo = jnp.maximum(lo0, best.x - width / 2)
        hi = jnp.minimum(hi0, best.x + width / 2)
        # The zoom box never wraps: ψ is clipped to [−π, π] like the other variables.
        stage = grid_search(problem, lo, hi, counts, None, chunk_size)
        if float(stage.fitness) < float(best.fitness):
            stage = stage._replace(x=best.x, fitness=best.fitness)
        out.append(stage)
        best = stage
    return out
