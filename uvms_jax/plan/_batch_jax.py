"""Many planning problems in one jitted JAX call: a dense lazy roadmap per problem, every state of
every problem checked by the sphere checker of :mod:`uvms_jax.plan._vector_jax` in one vmapped
call, so a GPU plans a whole problem set at once.

Each round, for every problem still worth improving:

1. ``nodes`` random states (part uniform in the joint box, part Gaussian about a random point of
   the straight motion, at scales from :data:`_SIGMA` [rad]); with start and goal they are the
   roadmap's vertices, the colliding ones dropped;
2. every pair of vertices is an edge (the straight motion among them), first checked at
   ``coarse`` of its dense samples, spread along it (a subset of the samples of the final
   check, so an edge dropped here would fail that check);
3. lazily (Bohlen & Kavraki's Lazy PRM, ICRA 2000): the shortest path from start to goal with at
   most ``waypoints - 1`` edges (Bellman–Ford on the dense graph, joint-space lengths) is
   checked at every sample of the CPU path (``resolution`` [rad] on every joint, the samples of
   :func:`~uvms_jax.plan._vector_kernels.n_samples`); its colliding edges are removed and the
   search repeated, ``lazy`` times.

A problem keeps the shortest path found over the rounds; rounds stop when every problem is
solved or after ``rounds``. Shapes are fixed: a path is ``(waypoints, n)`` padded by repeating
the goal, and one that needs more than ``samples`` check samples is not accepted. What this does
not solve (narrow passages beyond a few waypoints) is left to the CPU planner.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from uvms_jax.plan._vector_jax import SphereArm, SphereWorlds, motion_samples, state_free

__all__ = ["BatchPlan", "BatchSettings", "plan_batch"]

_SIGMA = (0.05, 1.5)  # range of the Gaussian samples' scales [rad], drawn log-uniform
_START, _GOAL = 0, 1  # roadmap vertices of the start and the goal


@dataclasses.dataclass(frozen=True)
class BatchSettings:
    """Sizes of :func:`plan_batch` (static: each set compiles once).

    Attributes:
      nodes: random vertices per problem and round.
      rounds: most rounds.
      lazy: shortest-path searches and checks per round.
      waypoints: most rows of a path, start and goal included (≥ 2).
      coarse: samples of the coarse check per edge.
      samples: most check samples of a path.
      resolution: the check's largest joint step between samples [rad].
      uniform: share of the vertices drawn uniformly in the joint box (the rest near the straight
        motion).
      chunk: states per problem checked together (bounds memory: ``B × chunk`` states at once).
    """

    nodes: int = 64
    rounds: int = 8
    lazy: int = 6
    waypoints: int = 8
    coarse: int = 16
    samples: int = 2048
    resolution: float = 0.01
    uniform: float = 0.5
    chunk: int = 4096

    def __post_init__(self) -> None:
        for name in ("nodes", "rounds", "lazy", "coarse", "samples", "chunk"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"BatchSettings.{name} must be >= 1, got {getattr(self, name)}")
        if self.waypoints < 2:
            raise ValueError(f"BatchSettings.waypoints must be >= 2 (start and goal), got {self.waypoints}")
        if not self.resolution > 0:
            raise ValueError(f"BatchSettings.resolution must be > 0 [rad], got {self.resolution}")
        if not 0.0 <= self.uniform <= 1.0:
            raise ValueError(f"BatchSettings.uniform must be in [0, 1], got {self.uniform}")


class BatchPlan(NamedTuple):
    """Result of :func:`plan_batch` for ``B`` problems.

    Attributes:
      path: ``(B, waypoints, n)`` [rad], start first; rows past ``count`` repeat the goal.
      count: ``(B,)`` int, rows of each path used (0 where unsolved).
      solved: ``(B,)`` bool, a path was found and passed the check at every sample.
      length: ``(B,)`` joint-space length of each path [rad] (inf where unsolved).
      endpoints_free: ``(B,)`` bool, start and goal are free (else not attempted).
      rounds: ``()`` int, rounds run.
    """

    path: jax.Array
    count: jax.Array
    solved: jax.Array
    length: jax.Array
    endpoints_free: jax.Array
    rounds: jax.Array


def _free(arm: SphereArm, world: SphereWorlds, Q: jax.Array, chunk: int) -> jax.Array:
    """``(K,)`` bool: :func:`state_free` of the rows of ``Q (K, n)``, ``chunk`` at a time."""
    K = Q.shape[0]
    c = min(chunk, K)
    pad = -K % c
    Qp = jnp.concatenate([Q, jnp.broadcast_to(Q[:1], (pad, Q.shape[1]))]).reshape(-1, c, Q.shape[1])
    out = jax.lax.map(jax.vmap(lambda q: state_free(arm, world, q)), Qp)
    return out.reshape(-1)[:K]


def _vertices(arm: SphereArm, start, goal, key, s: BatchSettings) -> jax.Array:
    """``(nodes + 2, n)``: start, goal, then the round's random states [rad]."""
    n = start.shape[0]
    k1, k2, k3, k4, k5 = jax.random.split(key, 5)
    dt = start.dtype
    uniform = jax.random.uniform(k1, (s.nodes, n), dt, arm.lower, arm.upper)
    along = jax.random.uniform(k2, (s.nodes, 1), dt)
    sigma = jnp.exp(jax.random.uniform(k3, (s.nodes, 1), dt, math.log(_SIGMA[0]), math.log(_SIGMA[1])))
    near = jnp.clip(start + along * (goal - start) + sigma * jax.random.normal(k4, (s.nodes, n), dt),
                    arm.lower, arm.upper)
    pick = jax.random.uniform(k5, (s.nodes, 1)) < s.uniform
    return jnp.concatenate([start[None], goal[None], jnp.where(pick, uniform, near)])


def _n_steps(a: jax.Array, b: jax.Array, resolution: float) -> jax.Array:
    """Samples of the motion ``a → b`` (``(..., n)``) at ``resolution``, as the CPU path counts them."""
    d = jnp.max(jnp.abs(b - a), axis=-1)
    return jnp.maximum(1, jnp.ceil(d / resolution - 1e-12).astype(jnp.int32))


def _edges(X: jax.Array, s: BatchSettings):
    """The edges between the vertices ``X (V, n)``, every pair once: ``(u (E,), v (E,))``, and
    each edge's ``coarse`` check states ``(E, coarse, n)``, a subset of its dense samples."""
    u, v = jnp.triu_indices(X.shape[0], 1)
    a, b = X[u], X[v]
    steps = _n_steps(a, b, s.resolution)
    k = jnp.arange(1, s.coarse + 1)
    i = jnp.ceil(k[None, :] * steps[:, None] / (s.coarse + 1)).astype(jnp.int32)  # in 1 … steps
    f = (i / steps[:, None]).astype(X.dtype)
    return u, v, a[:, None, :] + f[..., None] * (b - a)[:, None, :]


def _graph(arm, world, X, s: BatchSettings) -> tuple[jax.Array, jax.Array]:
    """Check the vertices ``X (V, n)`` and every edge's coarse samples in one call: ``(weights
    (V, V), free (V,))``, the weights the joint-space lengths [rad] of the edges found free
    between free vertices (``inf`` elsewhere)."""
    V, n = X.shape
    u, v, Q = _edges(X, s)
    free = _free(arm, world, jnp.concatenate([X, Q.reshape(-1, n)]), s.chunk)
    ok = jnp.all(free[V:].reshape(u.shape[0], s.coarse), axis=1) & free[u] & free[v]
    w = jnp.where(ok, jnp.sqrt(jnp.sum((X[v] - X[u]) ** 2, axis=-1)), jnp.inf)
    W = jnp.full((V, V), jnp.inf, X.dtype).at[u, v].set(w)
    return jnp.minimum(W, W.T), free[:V]


def _shortest(W: jax.Array, hops: int) -> tuple[jax.Array, jax.Array, jax.Array]:
    """The shortest start → goal path of at most ``hops`` edges in the graph of weights
    ``W (V, V)``: ``(vertices (hops + 1,) int, count, length)``; vertices past ``count``
    repeat the goal; ``length = inf`` where there is none."""
    V = W.shape[0]
    dist = jnp.full(V, jnp.inf, W.dtype).at[_GOAL].set(0.0)

    def relax(d, _):
        via = W + d[None, :]
        arg = jnp.argmin(via, axis=1).astype(jnp.int32)
        best = jnp.take_along_axis(via, arg[:, None], axis=1)[:, 0]
        took = best < d
        return jnp.where(took, best, d), (arg, took)

    dist, (args, took) = jax.lax.scan(relax, dist, None, length=hops)

    def walk(carry, level):
        v, pos, out = carry
        step = took[level, v]
        nxt = jnp.where(step, args[level, v], v)
        out = out.at[pos + 1].set(jnp.where(step, nxt, out[pos + 1]))
        return (nxt, pos + step.astype(jnp.int32), out), None

    out = jnp.full(hops + 1, _GOAL, jnp.int32).at[0].set(_START)
    (_, last, out), _ = jax.lax.scan(walk, (jnp.int32(_START), jnp.int32(0), out), jnp.arange(hops - 1, -1, -1))
    found = jnp.isfinite(dist[_START])
    return out, jnp.where(found, last + 1, 0), dist[_START]


def _lazy(arm, world, X, W, s: BatchSettings):
    """Up to ``lazy`` shortest-path searches, each path checked at every sample and its colliding
    edges removed: ``(vertices (waypoints,), count, length, solved)`` of the first that passed."""
    hops = s.waypoints - 1

    def body(carry, _):
        W, best = carry
        verts, count, length = _shortest(W, hops)
        path = X[verts]
        Q, seg, used, fits = motion_samples(path, count, s.resolution, s.samples)
        hit = used & ~_free(arm, world, Q, s.chunk)
        bad = jnp.zeros(hops, jnp.int32).at[seg].max(hit.astype(jnp.int32)) > 0
        # A path too long to check: drop its longest edge (by samples) so the search moves on.
        steps = jnp.where(jnp.arange(hops) < count - 1, _n_steps(path[:-1], path[1:], s.resolution), 0)
        bad = jnp.where(fits, bad, jnp.arange(hops) == jnp.argmax(steps))
        ok = (count > 0) & fits & ~jnp.any(hit)
        bad &= (count > 0) & ~ok
        a, b = verts[:-1], verts[1:]
        W = W.at[a, b].set(jnp.where(bad, jnp.inf, W[a, b])).at[b, a].set(jnp.where(bad, jnp.inf, W[b, a]))
        new = (verts, count, length, ok)
        keep = best[3]
        best = jax.tree.map(lambda o, n: jnp.where(keep, o, n), best, new)
        return (W, best), None

    empty = (jnp.zeros(hops + 1, jnp.int32), jnp.int32(0), jnp.asarray(jnp.inf, X.dtype), jnp.asarray(False))
    (_, best), _ = jax.lax.scan(body, (W, empty), None, length=s.lazy)
    return best


def _round(arm, world, start, goal, key, s: BatchSettings):
    """One round for one problem: ``(path (waypoints, n), count, length, solved, endpoints
    free)``."""
    X = _vertices(arm, start, goal, key, s)
    W, free = _graph(arm, world, X, s)
    verts, count, length, ok = _lazy(arm, world, X, W, s)
    return X[verts], count, length, ok, free[_START] & free[_GOAL]


@functools.partial(jax.jit, static_argnames="settings")
def plan_batch(arm: SphereArm, worlds: SphereWorlds, starts: jax.Array, goals: jax.Array, key: jax.Array,
               settings: BatchSettings = BatchSettings()) -> BatchPlan:
    """Plan ``starts[b] → goals[b]`` in ``worlds[b]`` for every problem ``b`` of a batch.

    Args:
      arm: the robot's spheres (:func:`~uvms_jax.plan._vector_jax.sphere_arm`).
      worlds: ``B`` worlds (:func:`~uvms_jax.plan._vector_jax.sphere_worlds`).
      starts, goals: ``(B, n)`` joint values [rad], within the limits.
      key: a PRNG key.
      settings: the sizes (:class:`BatchSettings`).

    Returns:
      :class:`BatchPlan`.
    """
    s = settings
    B, n = starts.shape
    dt = arm.centre.dtype
    starts, goals = starts.astype(dt), goals.astype(dt)
    one_round = jax.vmap(lambda w, a, b, k: _round(arm, w, a, b, k, s))

    def cond(c):
        r, _, _, _, solved, endpoints_free = c
        return (r < s.rounds) & jnp.any(endpoints_free & ~solved)

    def body(c):
        r, path, count, length, solved, _ = c
        keys = jax.random.split(jax.random.fold_in(key, r), B)
        p, k, ln, ok, endpoints_free = one_round(worlds, starts, goals, keys)
        better = ok & endpoints_free & (ln < length)
        pick = lambda o, x: jnp.where(better.reshape((B,) + (1,) * (o.ndim - 1)), x, o)  # noqa: E731
        return r + 1, pick(path, p), pick(count, k), pick(length, ln), solved | better, endpoints_free

    path0 = jnp.broadcast_to(goals[:, None, :], (B, s.waypoints, n))
    init = (jnp.int32(0), path0, jnp.zeros(B, jnp.int32), jnp.full(B, jnp.inf, dt), jnp.zeros(B, bool),
            jnp.ones(B, bool))
    r, path, count, length, solved, endpoints_free = jax.lax.while_loop(cond, body, init)
    return BatchPlan(path, count, solved, length, endpoints_free, r)
