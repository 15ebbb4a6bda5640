"""A compiled RRT-Connect (Kuffner & LaValle, ICRA 2000) and path shortcutting on the compiled
sphere checker (:mod:`uvms_jax.plan._vector_kernels`): a whole query is one Numba call, with no
Python between two checks.

The algorithm is OMPL's ``RRTConnect``: two trees, from the start and from the goal, take
turns to extend towards a uniform sample (at most ``range`` [rad] per step) and the other tree
then connects greedily towards the new node. Before growing any tree the straight motion is
tried. Simplification is OMPL's in kind: shortcuts between random points of the path
(``shortcutPath``), then dropping every waypoint whose neighbours see each other
(``reduceVertices``). Every motion is checked at the caller's resolution.

The wall clock is read every few iterations (``numba.objmode``), so the deadline is hard to
within one iteration.
"""

from __future__ import annotations

import time

import numba
import numpy as np

from uvms_jax.plan import _kernel_cache  # noqa: F401  # the kernels below are cached by content
from uvms_jax.plan._vector_kernels import make_scratch, motion_free

TRAPPED, ADVANCED, REACHED = 0, 1, 2
SOLVED, TIMEOUT, FULL = 0, 1, 2  # outcomes of rrt_connect
_CLOCK_EVERY = 4  # iterations between two reads of the clock (one read costs about a microsecond)


@numba.njit(cache=True)
def _now() -> float:
    with numba.objmode(t="float64"):
        t = time.perf_counter()
    return t


@numba.njit(cache=True)
def _nearest(nodes, count, q) -> int:
    best, arg = np.inf, 0
    n = q.shape[0]
    for i in range(count):
        d = 0.0
        for j in range(n):
            e = nodes[i, j] - q[j]
            d += e * e
        if d < best:
            best, arg = d, i
    return arg


@numba.njit(cache=True)
def _grow(nodes, parent, count, target, step, resolution, model, scratch, new) -> int:
    """One RRT extension of the tree ``nodes[:count[0]]`` towards ``target``: its nearest node
    moves at most ``step`` [rad] along the straight line; the node is added when the motion is
    free. Returns TRAPPED, ADVANCED or REACHED."""
    near = _nearest(nodes, count[0], target)
    d = 0.0
    for j in range(target.shape[0]):
        d += (target[j] - nodes[near, j]) ** 2
    d = np.sqrt(d)
    reach = d <= step
    f = 1.0 if reach else step / d
    for j in range(target.shape[0]):
        new[j] = nodes[near, j] + f * (target[j] - nodes[near, j])
    if not motion_free(nodes[near], new, resolution, model, scratch):
        return TRAPPED
    nodes[count[0]] = new
    parent[count[0]] = near
    count[0] += 1
    return REACHED if reach else ADVANCED


@numba.njit(cache=True)
def _branch(nodes, parent, i):
    """The nodes from the root to node ``i``, root first: ``(k, n)``."""
    k, j = 1, i
    while parent[j] >= 0:
        j = parent[j]
        k += 1
    out = np.empty((k, nodes.shape[1]))
    j = i
    for r in range(k - 1, -1, -1):
        out[r] = nodes[j]
        j = parent[j]
    return out


@numba.njit(cache=True)
def rrt_connect(start, goal, lower, upper, step, resolution, max_nodes, deadline, seed, model):
    """Plan ``start → goal`` (each ``(n,)`` [rad], both free) within the box ``lower``–``upper``.

    Args:
      step: largest extension of a tree per iteration [rad] (OMPL's ``range``).
      resolution: motion-check step [rad].
      max_nodes: capacity of each tree.
      deadline: ``time.perf_counter()`` value at which to give up [s].
      seed: the sampler's seed.
      model: the checker's arrays (:mod:`uvms_jax.plan._vector_kernels`).

    Returns:
      ``(path (k, n), outcome, iterations)``; the path is empty unless ``outcome == SOLVED``.
    """
    n = start.shape[0]
    scratch = make_scratch(model)
    if motion_free(start, goal, resolution, model, scratch):
        out = np.empty((2, n))
        out[0], out[1] = start, goal
        return out, SOLVED, 0
    np.random.seed(seed)
    nodes = (np.empty((max_nodes, n)), np.empty((max_nodes, n)))
    parents = (np.full(max_nodes, -1), np.full(max_nodes, -1))
    counts = (np.ones(1, np.int64), np.ones(1, np.int64))
    nodes[0][0], nodes[1][0] = start, goal
    sample, new, other = np.empty(n), np.empty(n), np.empty(n)
    it = 0
    a = 0  # the tree that extends this iteration: 0 grown from the start, 1 from the goal
    while True:
        if it % _CLOCK_EVERY == 0 and _now() > deadline:
            return np.empty((0, n)), TIMEOUT, it
        if counts[0][0] + 1 >= max_nodes or counts[1][0] + 1 >= max_nodes:
            return np.empty((0, n)), FULL, it
        it += 1
        for j in range(n):
            sample[j] = lower[j] + np.random.random() * (upper[j] - lower[j])
        b = 1 - a
        if _grow(nodes[a], parents[a], counts[a], sample, step, resolution, model, scratch, new) != TRAPPED:
            other[:] = new
            status = ADVANCED
            while status == ADVANCED:
                status = _grow(nodes[b], parents[b], counts[b], other, step, resolution, model, scratch, new)
            if status == REACHED:
                # Both trees' newest nodes are the meeting point: join them without repeating it.
                first = _branch(nodes[0], parents[0], counts[0][0] - 1)
                second = _branch(nodes[1], parents[1], counts[1][0] - 1)
                k1, k2 = first.shape[0], second.shape[0]
                out = np.empty((k1 + k2 - 1, n))
                out[:k1] = first
                for r in range(k2 - 1):
                    out[k1 + r] = second[k2 - 2 - r]
                return out, SOLVED, it
        a = b


@numba.njit(cache=True)
def _reduce(path, resolution, model, scratch):
    """Keep a waypoint only where its neighbours do not see each other: greedily from the
    start, jump to the farthest waypoint reachable by one free motion."""
    k = path.shape[0]
    keep = np.empty(k, np.int64)
    m, i = 1, 0
    keep[0] = 0
    while i < k - 1:
        j = k - 1
        while j > i + 1 and not motion_free(path[i], path[j], resolution, model, scratch):
            j -= 1
        keep[m] = j
        m += 1
        i = j
    return path[keep[:m]].copy()


@numba.njit(cache=True)
def shortcut(path, resolution, deadline, tries, seed, model):
    """A shorter path through the same free space: ``tries`` random shortcuts between points
    on two different segments (kept when the straight motion between them, and what is left of
    the two segments, are free and shorter),
    then :func:`_reduce`; stops at ``deadline`` [s, ``perf_counter``] with the best path so far.
    ``path (k, n)`` [rad] → ``(m, n)``, same ends."""
    scratch = make_scratch(model)
    path = _reduce(path, resolution, model, scratch)
    np.random.seed(seed)
    n = path.shape[1]
    p0, p1 = np.empty(n), np.empty(n)
    for _ in range(tries):
        k = path.shape[0]
        if k < 3 or _now() > deadline:
            break
        i = np.random.randint(0, k - 1)
        j = np.random.randint(0, k - 1)
        if i == j:
            continue
        if i > j:
            i, j = j, i
        u, v = np.random.random(), np.random.random()
        p0[:] = path[i] + u * (path[i + 1] - path[i])
        p1[:] = path[j] + v * (path[j + 1] - path[j])
        old = np.sqrt(np.sum((p0 - path[i + 1]) ** 2)) + np.sqrt(np.sum((path[j] - p1) ** 2))
        for r in range(i + 1, j):
            old += np.sqrt(np.sum((path[r + 1] - path[r]) ** 2))
        if np.sqrt(np.sum((p1 - p0) ** 2)) >= old - 1e-9 or not motion_free(p0, p1, resolution, model, scratch):
            continue
        # The pieces left of the two cut segments are sampled afresh: checked too, so that every
        # segment of the result has passed at its own samples.
        if not (motion_free(path[i], p0, resolution, model, scratch)
                and motion_free(p1, path[j + 1], resolution, model, scratch)):
            continue
        out = np.empty((i + 1 + 2 + k - j - 1, n))
        out[:i + 1] = path[:i + 1]
        out[i + 1], out[i + 2] = p0, p1
        out[i + 3:] = path[j + 1:]
        path = out
    if _now() <= deadline:
        path = _reduce(path, resolution, model, scratch)
    return path


def load(model, lower, upper) -> None:
    """Load (or compile) the planner's kernels for ``model``'s types now, with the joint limits
    ``lower``, ``upper`` (``(n,)`` [rad]) the queries pass (Numba compiles a read-only array
    apart): a first call in a process costs ~0.1 s from Numba's cache, which no query's budget
    should pay."""
    q = np.clip(np.zeros(len(lower)), lower, upper)
    rrt_connect(q, q, lower, upper, 1.0, 1.0, 2, 0.0, 0, model)
    shortcut(np.stack([q, q]), 1.0, 0.0, 0, 0, model)
