"""Dense grid search: the brute-force reference optimum of the docking problem.

The grid is never materialised: candidates are decoded from their flat index chunk by chunk
(``chunk_size`` candidates each), so memory is bounded by one chunk whatever the grid size (1e6
on a laptop CPU, 1e8+ on a GPU).

The grid search and the zoom stages evaluate the fitness through one compiled program,
:func:`_fitness_of` on ``(chunk_size, m)`` points, called chunk by chunk from Python (the calls
are queued asynchronously; nothing waits for the device between them). A fitness such as the
arm's docking fitness (numerical IK and a collision world) takes seconds to compile on a CPU:
the two searches share that compile, where a loop inside each search's own jitted program would
compile the fitness once per search. What surrounds it (decoding a chunk, keeping the best) are
small programs of their own.
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
      top_x, top_fitness: ``(keep, m)`` and ``(keep,)`` the ``keep`` best points, best first
        (``keep = 1``: ``x`` and ``fitness`` alone).
    """

    x: Array
    fitness: Array
    n_candidates: int
    low: Array
    high: Array
    top_x: Array | None = None
    top_fitness: Array | None = None


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


@jax.jit
def _fitness_of(problem: Any, x: Array) -> Array:
    """``(n,)`` fitness of points ``x (n, m)``, NaN as −inf: the one compiled evaluation of a
    problem (per chunk shape) that the grid search and the zoom stages share."""
    f = problem.fitness(x)
    return jnp.where(jnp.isnan(f), -jnp.inf, f)


@partial(jax.jit, static_argnames=("chunk_size",))
def _chunk_points(c: Array, low: Array, step: Array, counts: Array, chunk_size: int) -> Array:
    """``(chunk_size, m)`` grid points of chunk ``c`` (past the grid's end: its first point)."""
    flat = c * chunk_size + jnp.arange(chunk_size, dtype=counts.dtype)
    return _grid_point(jnp.where(flat < jnp.prod(counts), flat, 0), low, step, counts)


@partial(jax.jit, static_argnames=("keep",))
def _keep_best(best: tuple[Array, Array], x: Array, f: Array, c: Array, counts: Array, keep: int):
    """The ``keep`` best of ``best = (x (keep, m), f (keep,))`` and chunk ``c``'s points ``x (C, m)``
    with fitness ``f (C,)`` (the points past the grid's end left out); ties keep the earlier."""
    best_x, best_f = best
    f = jnp.where(c * f.shape[0] + jnp.arange(f.shape[0], dtype=counts.dtype) < jnp.prod(counts), f, -jnp.inf)
    if keep == 1:
        i = jnp.argmax(f)
        better = f[i] > best_f[0]  # strict: ties keep the lowest flat index
        return jnp.where(better, x[i], best_x), jnp.where(better, f[i], best_f)
    # top_k puts the lower index first among equals: the earlier chunks win ties.
    top_f, i = jax.lax.top_k(jnp.concatenate([best_f, f]), keep)
    return jnp.concatenate([best_x, x])[i], top_f


def _search(problem: Any, low: Array, step: Array, counts: Array, chunk_size: int, keep: int):
    """The grid's ``keep`` best points ``(keep, m)`` and their fitness ``(keep,)``, chunk by chunk."""
    n_chunks = -(-int(np.prod(np.asarray(counts), dtype=np.int64)) // chunk_size)
    low_np = np.asarray(low)  # the start made on the host: no compiled program per shape
    best = (np.broadcast_to(low_np, (keep,) + low_np.shape).copy(), np.full((keep,), -np.inf, dtype=low_np.dtype))
    for c in range(n_chunks):
        c = np.int32(c)
        x = _chunk_points(c, low, step, counts, chunk_size)
        best = _keep_best(best, x, _fitness_of(problem, x), c, counts, keep)
    return best


def grid_search(
    problem: Any,
    low,
    high,
    counts: tuple[int, ...],
    periodic: tuple[bool, ...] | None = None,
    chunk_size: int = 16384,
    keep: int = 1,
    shift=None,
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
      keep: how many of the best points to return (``top_x``), ≥ 1.
      shift: None for the lattice through the box's corners; else ``(m,)`` fractions in
        [0, 1): each variable's ``counts[i]`` points sit at ``low + (j + shift[i]) · (high −
        low) / counts[i]``, one per cell of an even split of the box (a lattice moved by a
        random shift samples the box afresh for every seed; 0.5: the cells' centres).

    Returns:
      :class:`GridResult`; ties go to the candidate with the lowest flat (row-major) index.
    """
    counts = tuple(int(c) for c in counts)
    low = jnp.asarray(low)
    high = jnp.asarray(high, dtype=low.dtype)
    if low.shape != (len(counts),) or high.shape != low.shape:
        raise ValueError(f"low/high must have shape ({len(counts)},), got {low.shape} and {high.shape}")
    if any(c < 1 for c in counts) or chunk_size < 1 or keep < 1:
        raise ValueError(f"counts, chunk_size and keep must be positive, got {counts}, {chunk_size} and {keep}")
    n = int(np.prod(counts, dtype=np.int64))
    if n >= 2**31:
        raise ValueError(f"grid of {n} candidates exceeds int32 indexing; split the box")
    periodic = tuple(periodic) if periodic is not None else (False,) * len(counts)
    if shift is None:
        divisions = [(c if per else c - 1) for c, per in zip(counts, periodic)]
        step = jnp.asarray([1.0 / max(k, 1) for k in divisions], dtype=low.dtype) * (high - low)
        # A single point per axis sits at the box centre.
        start = jnp.where(jnp.asarray(counts) == 1, (low + high) / 2, low)
    else:
        shift = jnp.asarray(shift, dtype=low.dtype)
        if shift.shape != low.shape or not bool(jnp.all((shift >= 0) & (shift < 1))):
            raise ValueError(f"shift must be {len(counts)} fractions in [0, 1), got {shift}")
        step = (high - low) / jnp.asarray(counts, dtype=low.dtype)
        start = low + shift * step
    top_x, top_f = _search(problem, start, step, jnp.asarray(counts, dtype=jnp.int32), chunk_size, int(keep))
    return GridResult(x=top_x[0], fitness=top_f[0], n_candidates=n, low=low, high=high, top_x=top_x, top_fitness=top_f)



def _unit_box(counts: tuple[int, ...], dtype) -> np.ndarray:
    """``(P, m)`` a zoom box's points in ``[0, 1]^m``: ``counts[i]`` per variable, edges included
    (a single one at the centre), row-major."""
    axes = [np.linspace(0.0, 1.0, c) if c > 1 else np.full((1,), 0.5) for c in counts]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(counts)).astype(dtype)


@partial(jax.jit, static_argnames=("chunk_size",))
def _zoom_box(x: Array, s: Array, unit: Array, width: Array, low: Array, high: Array, periodic: Array,
              shrink: Array, chunk_size: int) -> tuple[Array, tuple[Array, ...]]:
    """Stage ``s``'s boxes about the best points ``x (k, m)``: their points ``(k, P, m)`` and the
    same in chunks ``(chunk_size, m)`` (the last padded with the first point)."""
    half = width * shrink ** (s + 1) / 2
    # The box around each best point: clipped to the search box, or wrapped along a
    # periodic variable (ψ over a full turn).
    lo = jnp.where(periodic, x - half, jnp.maximum(low, x - half))
    hi = jnp.where(periodic, x + half, jnp.minimum(high, x + half))
    cand = lo[:, None, :] + unit * (hi - lo)[:, None, :]  # (k, P, m)
    cand = jnp.where(periodic, low + jnp.mod(cand - low, high - low), cand)
    flat = cand.reshape(-1, cand.shape[-1])
    n, m = flat.shape
    n_chunks = -(-n // chunk_size)
    padded = jnp.concatenate([flat, jnp.broadcast_to(flat[:1], (n_chunks * chunk_size - n, m))])
    return cand, tuple(padded[i * chunk_size:(i + 1) * chunk_size] for i in range(n_chunks))


@jax.jit
def _zoom_keep(cand: Array, f_chunks: tuple[Array, ...], x: Array, f: Array) -> tuple[Array, Array]:
    """The best of each box ``cand (k, P, m)`` (fitness in chunks, padding last) where it beats
    the box's centre ``x (k, m)`` with fitness ``f (k,)``."""
    k, P = cand.shape[:2]
    fc = jnp.concatenate(f_chunks)[:k * P].reshape(k, P)
    i = jnp.argmax(fc, axis=-1)  # the first maximum: ties keep the lowest index
    f_box = jnp.take_along_axis(fc, i[:, None], axis=-1)[:, 0]
    better = f_box > f
    x = jnp.where(better[:, None], jnp.take_along_axis(cand, i[:, None, None], axis=1)[:, 0], x)
    return x, jnp.where(better, f_box, f)


class ZoomResult(NamedTuple):
    """Zoom stages from K starts (NumPy): ``x (K, m)`` and ``fitness (K,)`` the best points
    (never worse than the starts), ``x_history (stages, K, m)`` and ``fitness_history
    (stages, K)`` the best after each stage."""

    x: np.ndarray
    fitness: np.ndarray
    x_history: np.ndarray
    fitness_history: np.ndarray


def zoom_from(problem: Any, starts, fitness, low, high, counts: tuple[int, ...], stages: int,
              shrink: float = 0.5, periodic=None, width=None, chunk_size: int = 16384) -> ZoomResult:
    """Zoom stages around several start points at once: the local polish of a search.

    Stage s grids a box of ``width · shrink^(s+1)`` (``counts`` points per variable, edges
    included) centred on each start's best point so far, clipped to the search box (wrapped
    along a ``periodic`` variable), and keeps the box's best point when it improves. All K
    boxes of a stage are one evaluation of ``K · prod(counts)`` points, in chunks of the
    compiled fitness the grid search uses too (module docstring). With ``counts = 3`` per variable and ``shrink = 0.5`` a stage
    tries the 3^m − 1 neighbours at half the previous step, diagonals included: a pattern
    search that follows ridges such as the apex where two targets' w meet.

    Args:
      problem: pytree with ``fitness((n, m)) -> (n,)`` (to maximise).
      starts: ``(K, m)`` start points; fitness: ``(K,)`` their fitness.
      low, high: ``(m,)`` the search box.
      counts: points per variable of each stage's box, each ≥ 1; stages: zoom stages, ≥ 0.
      shrink: each stage's box as a fraction of the previous one, in (0, 1].
      periodic: ``(m,)`` whether a variable wraps from ``high`` to ``low``; default none.
      width: ``(m,)`` box size before the first shrink; default ``high − low``.
      chunk_size: points per evaluation at most (memory bound).
    """
    counts = tuple(int(c) for c in counts)
    starts = np.atleast_2d(np.asarray(starts))
    if len(counts) != starts.shape[-1] or min(counts) < 1 or stages < 0 or not 0.0 < shrink <= 1.0 or chunk_size < 1:
        raise ValueError(f"need {starts.shape[-1]} counts >= 1, stages >= 0, shrink in (0, 1] and chunk_size >= 1, "
                         f"got {counts}, {stages}, {shrink}, {chunk_size}")
    low = jnp.asarray(low)
    high = jnp.asarray(high, low.dtype)
    width = high - low if width is None else jnp.asarray(width, low.dtype)
    periodic = jnp.zeros(low.shape, bool) if periodic is None else jnp.asarray(periodic, bool)
    fitness = np.atleast_1d(np.asarray(fitness))
    chunk_size = min(int(chunk_size), len(starts) * int(np.prod(counts)))
    unit = _unit_box(counts, low.dtype)
    x, f, xs, fs = starts.astype(low.dtype), fitness.astype(low.dtype), [], []
    shrink = np.asarray(shrink, low.dtype)
    for stage in range(int(stages)):
        cand, chunks = _zoom_box(x, np.int32(stage), unit, width, low, high, periodic, shrink, chunk_size)
        x, f = _zoom_keep(cand, tuple(_fitness_of(problem, c) for c in chunks), x, f)
        xs.append(x)
        fs.append(f)
    xs = np.stack([np.asarray(v) for v in xs]) if xs else np.zeros((0,) + starts.shape, low.dtype)
    fs = np.stack([np.asarray(v) for v in fs]) if fs else np.zeros((0, len(starts)), low.dtype)
    x, f = (xs[-1], fs[-1]) if stages else (starts, fitness)
    return ZoomResult(x, f, xs, fs)


def refine_grid_search(
    problem: Any,
    result: GridResult,
    counts: tuple[int, ...],
    stages: int,
    shrink: float = 0.25,
    chunk_size: int = 16384,
) -> list[GridResult]:
    """Zoom stages after a global grid search (:func:`zoom_from` from its best point, the box
    never wrapping): a local polish of the reference optimum (the global stage decides the
    basin); one :class:`GridResult` per stage, each at least as good as the previous."""
    zoom = zoom_from(problem, np.asarray(result.x)[None], np.asarray(result.fitness)[None], result.low, result.high,
                     counts, stages, shrink, chunk_size=chunk_size)
    n = int(np.prod(counts))
    return [GridResult(x=jnp.asarray(x[0]), fitness=jnp.asarray(f[0]), n_candidates=n, low=result.low, high=result.high)
            for x, f in zip(zoom.x_history, zoom.fitness_history)]


def distinct_best(x, fitness, k: int, separation) -> np.ndarray:
    """Indices of up to ``k`` best points, each farther than ``separation (m,)`` from every
    point kept before it along some variable (best first): the starts of a multistart
    polish, one per basin rather than k neighbours of one optimum. NaN fitness never counts."""
    x, fitness = np.asarray(x), np.asarray(fitness)
    keep: list[int] = []
    for i in np.argsort(-np.nan_to_num(fitness, nan=-np.inf), kind="stable"):
        if not np.isfinite(fitness[i]):
            break
        if all(np.any(np.abs(x[i] - x[j]) > separation) for j in keep):
            keep.append(int(i))
            if len(keep) == k:
                break
    return np.asarray(keep, dtype=np.int64)
