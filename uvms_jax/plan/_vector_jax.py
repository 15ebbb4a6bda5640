"""The sphere checker of :mod:`uvms_jax.plan._vector_kernels` in JAX: one state per call, batched
with ``vmap`` (states, motions, problems), so a GPU checks whole batches of problems at once.

The arrays are the compiled checker's own (``kin``, the spheres of each group, the obstacle
rows ``(M, 20)`` and polytope faces ``(F, 4)``, the group pairs of self-collision) in two parts:

* :class:`SphereArm`: the robot at one finger opening, shared by every problem of a batch;
* :class:`SphereWorlds`: the world side of one or of ``B`` problems (leading axes): obstacle
  rows, faces, which of the arm's candidate group pairs the world checks (its allowed
  collision matrix), and the margin. Worlds with fewer obstacles or faces are padded with
  :data:`PAD_ROW` / :data:`PAD_PLANE`, rows that never collide (for both checkers), so a batch
  of different worlds is one array.

The verdicts are the Numba kernel's covering spheres alone (its FREE,
:func:`~uvms_jax.plan._vector_kernels.state_status`; what the spheres cannot tell counts as a
collision here, as a GPU holds no MuJoCo model): a sphere collides with an obstacle when its
signed distance is below its radius plus the margin, and two spheres of a checked pair when their centres are nearer than their radii plus
the margin. The Numba kernel skips far groups by bounding spheres and boxes, and the obstacles
out of a group's reach (:func:`~uvms_jax.plan._worlds.near_obstacles`); these tests only skip
what is farther than the margin (the distances are 1-Lipschitz), so here every sphere is tested
against every row with no broad phase — the same verdicts up to float round-off, with no
branches to diverge on a GPU.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from collections.abc import Sequence
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax.plan._vector import RobotSpheresModel
from uvms_jax.plan._vector_kernels import BOX, CAPSULE, CYLINDER, POLYTOPE, SPHERE, without_exact, without_tables
from uvms_jax.plan._worlds import ROW, World, near_obstacles, obstacle_rows

__all__ = ["PAD_PLANE", "PAD_ROW", "SphereArm", "SphereWorlds", "motion_samples", "numba_model", "sphere_arm",
           "sphere_worlds", "state_free", "states_free"]

#: Distance [m] of the padding rows from the robot's base: farther than any robot reaches.
PAD_FAR = 1.0e4
#: An obstacle row that never collides: a sphere of radius 0 at :data:`PAD_FAR` on every axis.
PAD_ROW = np.zeros(ROW)
PAD_ROW[0], PAD_ROW[1:4], PAD_ROW[16:19] = SPHERE, PAD_FAR, PAD_FAR
#: A polytope face no polytope row refers to (``n = 0``, ``d = PAD_FAR``: outside everywhere).
PAD_PLANE = np.array([0.0, 0.0, 0.0, PAD_FAR])


@functools.partial(jax.tree_util.register_dataclass, meta_fields=["runs"],
                   data_fields=["kin", "body", "centre", "radius", "pair_spheres", "pair_group", "lower", "upper"])
@dataclasses.dataclass(frozen=True)
class SphereArm:
    """The robot's side of the checker, shared by every problem of a batch (a pytree).

    Attributes:
      kin: ``(n, 16)`` joint rows (:mod:`uvms_jax.plan._vector_kernels`).
      body: ``(S,)`` int32, the body each sphere moves with (``-1`` the base).
      runs: static ``(body, first, end)`` of each run of spheres on one body, so that the
        spheres are posed by slices, not gathers.
      centre: ``(S, 3)`` sphere centres in their body's frame [m]; radius: ``(S,)`` [m].
      pair_spheres: ``(K, 2)`` int32, the sphere pairs of the candidate group pairs.
      pair_group: ``(K,)`` int32, the candidate group pair (row of ``candidates``) of each.
      lower, upper: ``(n,)`` joint limits [rad or m].
    """

    kin: jax.Array
    body: jax.Array
    centre: jax.Array
    radius: jax.Array
    pair_spheres: jax.Array
    pair_group: jax.Array
    lower: jax.Array
    upper: jax.Array
    runs: tuple[tuple[int, int, int], ...]


class SphereWorlds(NamedTuple):
    """The world side of one problem (no leading axis) or of a batch (leading ``(B,)``).

    Attributes:
      obstacles: ``(..., M, 20)`` obstacle rows, padded with :data:`PAD_ROW`.
      planes: ``(..., F, 4)`` polytope faces, padded with :data:`PAD_PLANE` (F ≥ 1).
      pair_on: ``(..., P)`` bool, whether each candidate group pair of the arm is checked.
      margin: ``(...)`` safety distance [m].
    """

    obstacles: jax.Array
    planes: jax.Array
    pair_on: jax.Array
    margin: jax.Array


def candidate_pairs(side: RobotSpheresModel) -> list[tuple[int, int]]:
    """``P`` group pairs a world may check: every pair the robot does not skip."""
    return [p for p in itertools.combinations(range(len(side.groups)), 2) if p not in side.skipped]


def sphere_arm(side: RobotSpheresModel, dtype=np.float32) -> SphereArm:
    """:class:`SphereArm` of ``side`` with floats of ``dtype``."""
    groups = side.groups.astype(np.int64)
    body = np.empty(len(side.spheres), np.int32)
    for g in groups:
        body[g[0]:g[1]] = g[2]
    pairs, which = [], []
    for c, (a, b) in enumerate(candidate_pairs(side)):
        for s1, s2 in itertools.product(range(groups[a, 0], groups[a, 1]), range(groups[b, 0], groups[b, 1])):
            pairs.append((s1, s2))
            which.append(c)
    lower, upper = np.asarray(side.robot.lower), np.asarray(side.robot.upper)
    cuts = [0, *(np.flatnonzero(np.diff(body)) + 1), len(body)]
    runs = tuple((int(body[a]), int(a), int(b)) for a, b in zip(cuts[:-1], cuts[1:]))
    return SphereArm(jnp.asarray(side.kin, dtype), jnp.asarray(body), jnp.asarray(side.spheres[:, :3], dtype),
                     jnp.asarray(side.spheres[:, 3], dtype), jnp.asarray(np.array(pairs, np.int32).reshape(-1, 2)),
                     jnp.asarray(np.array(which, np.int32)), jnp.asarray(lower, dtype), jnp.asarray(upper, dtype), runs)


def _padded(rows: np.ndarray, count: int, pad: np.ndarray, label: str) -> np.ndarray:
    if len(rows) > count:
        raise ValueError(f"a world has {len(rows)} {label}, more than the {count} asked for")
    return np.concatenate([rows.reshape(-1, pad.size), np.tile(pad, (count - len(rows), 1))])


def sphere_worlds(side: RobotSpheresModel, worlds: Sequence[World], margin: float = 0.0, dtype=np.float32,
                  n_obstacles: int | None = None, n_planes: int | None = None) -> SphereWorlds:
    """The batch ``(B,)`` of ``worlds`` for the arm ``side``, padded to ``n_obstacles`` rows and
    ``n_planes`` faces (default: the largest of the batch; at least one of each)."""
    if not (np.isfinite(margin) and margin >= 0):
        raise ValueError(f"margin must be finite and >= 0 [m], got {margin}")
    if not worlds:
        raise ValueError("sphere_worlds needs at least one world")
    arrays = [obstacle_rows(w.obstacles) for w in worlds]
    M = max(1, max(len(r) for r, _ in arrays)) if n_obstacles is None else n_obstacles
    F = max(1, max(len(p) for _, p in arrays)) if n_planes is None else n_planes
    cands = candidate_pairs(side)
    rows, planes, on = [], [], []
    for w, (r, p) in zip(worlds, arrays):
        rows.append(_padded(r, M, PAD_ROW, "obstacle rows"))
        planes.append(_padded(p, F, PAD_PLANE, "polytope faces"))
        checked = {tuple(int(v) for v in pair) for pair in side.pairs(w)}
        on.append([c in checked for c in cands])
    return SphereWorlds(jnp.asarray(np.stack(rows), dtype), jnp.asarray(np.stack(planes), dtype),
                        jnp.asarray(np.array(on, bool).reshape(len(worlds), len(cands))),
                        jnp.full(len(worlds), margin, dtype))


def numba_model(side: RobotSpheresModel, world: SphereWorlds, index: int | None = None) -> tuple:
    """The Numba checker's model tuple of one (padded) world of a batch (``index``) or of an
    unbatched one: the same rows, faces and checked pairs, in float64."""
    pick = (lambda a: np.asarray(a)) if index is None else (lambda a: np.asarray(a)[index])
    cands = np.array(candidate_pairs(side), np.int64).reshape(-1, 2)
    rows, planes, margin = pick(world.obstacles).astype(np.float64), pick(world.planes).astype(np.float64), \
        float(pick(world.margin))
    return (side.kin, side.groups, side.spheres, rows, planes, cands[pick(world.pair_on)], margin, side.clusters,
            side.inner, without_exact(len(side.groups), len(rows)), 0, without_tables(int(np.sum(pick(world.pair_on)))),
            near_obstacles(side.kin, side.groups, rows, planes, margin))


_EYE = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


def _mat(a, b):
    """Product of two rotations given as 9 row-major components each."""
    return tuple(a[3 * r] * b[c] + a[3 * r + 1] * b[3 + c] + a[3 * r + 2] * b[6 + c]
                 for r in range(3) for c in range(3))


def _apply(R, t, v):
    """``R v + t``: ``R`` 9 row-major components, ``t`` and ``v`` 3 components."""
    return tuple(R[3 * r] * v[0] + R[3 * r + 1] * v[1] + R[3 * r + 2] * v[2] + t[r] for r in range(3))


def body_poses(kin: jax.Array, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """World poses of the base and the chain's bodies at ``q (n,)``: rotations ``(n + 1, 9)``
    (row-major) and positions ``(n + 1, 3)`` [m], the base first (the identity).

    Written component by component, as the Numba kernel is, so that under ``vmap`` every step
    is elementwise over the batch (XLA fuses it; no batched 3 × 3 products)."""
    R, t = tuple(jnp.asarray(e, kin.dtype) for e in _EYE), (jnp.zeros((), kin.dtype),) * 3
    Rs, ts = [R], [t]
    for i in range(kin.shape[0]):
        k = [kin[i, j] for j in range(16)]
        ax, ay, az = k[12], k[13], k[14]
        revolute = k[15] == 0.0
        c, s = jnp.cos(q[i]), jnp.sin(q[i])
        v = 1.0 - c
        turn = (c + ax * ax * v, ax * ay * v - az * s, ax * az * v + ay * s,
                ay * ax * v + az * s, c + ay * ay * v, ay * az * v - ax * s,
                az * ax * v - ay * s, az * ay * v + ax * s, c + az * az * v)
        M = tuple(jnp.where(revolute, m, e) for m, e in zip(turn, _EYE))
        d = tuple(jnp.where(revolute, 0.0, a * q[i]) for a in (ax, ay, az))
        # Fixed offset then motion (R_pb = F·M, t_pb = F_t + F·d), after the parent's pose.
        t = _apply(R, t, _apply(k[:9], k[9:12], d))
        R = _mat(R, _mat(k[:9], M))
        Rs.append(R)
        ts.append(t)
    return jnp.stack([jnp.stack(r) for r in Rs]), jnp.stack([jnp.stack(p) for p in ts])


def sphere_centres(arm: SphereArm, q: jax.Array) -> jax.Array:
    """``(3, S)`` world centres [m] of the arm's spheres at ``q (n,)``, one row per axis."""
    R, t = body_poses(arm.kin, q)
    return jnp.concatenate([jnp.stack(_apply(R[b + 1], t[b + 1], arm.centre[s0:s1].T)) for b, s0, s1 in arm.runs],
                           axis=1)


def obstacle_distance(x, y, z, o: jax.Array, planes: jax.Array) -> jax.Array:
    """Signed distance [m] of points ``(x, y, z)`` (arrays of one shape) to obstacle rows
    ``o (20, ...)`` (one row per leading index, broadcast against the points), as
    :func:`~uvms_jax.plan._vector_kernels.sphere_obstacle_distance`; ``planes (F, 4)`` the
    polytope faces. Component by component, so XLA fuses it whole."""
    kind = o[0]
    px, py, pz = x - o[1], y - o[2], z - o[3]
    # Box: coordinates along its axes (the columns of the row-major rotation o[4:13]).
    e = [jnp.abs(px * o[4 + a] + py * o[7 + a] + pz * o[10 + a]) - o[13 + a] for a in range(3)]
    out2 = sum(jnp.where(ea > 0.0, ea * ea, 0.0) for ea in e)
    box = jnp.where(out2 > 0.0, jnp.sqrt(jnp.where(out2 > 0.0, out2, 1.0)), jnp.maximum(jnp.maximum(e[0], e[1]), e[2]))
    sphere = jnp.sqrt(px * px + py * py + pz * pz) - o[4]
    # Capsule and cylinder: along the axis o[4:7] and off it.
    along = px * o[4] + py * o[5] + pz * o[6]
    rx, ry, rz = px - along * o[4], py - along * o[5], pz - along * o[6]
    radial = jnp.sqrt(rx * rx + ry * ry + rz * rz)
    a = jnp.clip(along, -o[7], o[7])
    capsule = jnp.sqrt(radial * radial + (along - a) ** 2) - o[8]
    dr, dz = radial - o[8], jnp.abs(along) - o[7]
    corner = (dr > 0.0) & (dz > 0.0)
    cylinder = jnp.where(corner, jnp.sqrt(jnp.where(corner, dr * dr + dz * dz, 1.0)), jnp.maximum(dr, dz))
    # Polytope: the largest distance to its faces [o1, o2).
    polytope = jnp.full(jnp.broadcast_shapes(x.shape, kind.shape), -jnp.inf, x.dtype)
    for f in range(planes.shape[0]):
        face = (f >= o[1]) & (f < o[2])
        d = planes[f, 0] * x + planes[f, 1] * y + planes[f, 2] * z + planes[f, 3]
        polytope = jnp.where(face, jnp.maximum(polytope, d), polytope)
    return jnp.select([kind == BOX, kind == SPHERE, kind == CAPSULE, kind == CYLINDER, kind == POLYTOPE],
                      [box, sphere, capsule, cylinder, polytope], jnp.inf)


def state_free(arm: SphereArm, world: SphereWorlds, q: jax.Array) -> jax.Array:
    """Whether no sphere of the arm at ``q (n,)`` [rad] is nearer than the margin to an obstacle
    of ``world`` (one problem, no leading axis) or to a sphere of a checked pair: a bool ``()``."""
    x, y, z = sphere_centres(arm, q)
    d = obstacle_distance(x[:, None], y[:, None], z[:, None], world.obstacles.T[:, None, :], world.planes)
    hit_world = jnp.any(d < arm.radius[:, None] + world.margin)
    i, j = arm.pair_spheres[:, 0], arm.pair_spheres[:, 1]
    r = arm.radius[i] + arm.radius[j] + world.margin
    d2 = (x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2 + (z[i] - z[j]) ** 2
    hit_self = jnp.any(world.pair_on[arm.pair_group] & (d2 < r * r))
    return ~(hit_world | hit_self)


def states_free(arm: SphereArm, world: SphereWorlds, Q: jax.Array) -> jax.Array:
    """:func:`state_free` of every row of ``Q (..., n)`` in one world: a bool ``(...)``."""
    flat = Q.reshape(-1, Q.shape[-1])
    return jax.vmap(lambda q: state_free(arm, world, q))(flat).reshape(Q.shape[:-1])


def motion_samples(path: jax.Array, count: jax.Array, resolution: float, samples: int):
    """The check samples of a padded path at ``resolution`` [rad], as the CPU path takes them
    (:func:`~uvms_jax.plan._vector_kernels.n_samples` per segment, the end of each included,
    the start of the path not): ``path (W, n)`` [rad] with its first ``count`` rows used.

    Returns:
      ``(Q (samples, n), segment (samples,) int, used (samples,) bool, fits ())``: the
      samples in path order (the unused tail repeats the last waypoint), the segment ``k``
      (``path[k] → path[k + 1]``) of each, which are used, and whether every sample of the
      path fit in ``samples``.
    """
    W = path.shape[0]
    seg = jnp.arange(W - 1)
    delta = path[1:] - path[:-1]
    steps = jnp.maximum(1, jnp.ceil(jnp.max(jnp.abs(delta), axis=-1) / resolution - 1e-12).astype(jnp.int32))
    steps = jnp.where(seg < count - 1, steps, 0)
    ends = jnp.cumsum(steps)
    j = jnp.arange(samples)
    k = jnp.minimum(jnp.searchsorted(ends, j, side="right"), W - 2)
    i = j - (ends[k] - steps[k]) + 1
    used = j < ends[-1]
    f = (i / jnp.maximum(steps[k], 1)).astype(path.dtype)
    Q = jnp.where(used[:, None], path[k] + f[:, None] * delta[k], path[jnp.maximum(count - 1, 0)])
    return Q, k, used, ends[-1] <= samples
