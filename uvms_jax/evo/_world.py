"""The planner's collision world in JAX: the arm as spheres, the scene as boxes and polytopes.

Docking tests its IK solutions in the same world the planner plans in. The planner's compiled
checker (:class:`uvms_jax.plan.SphereChecker`) reads the arm's geoms from the scene's MuJoCo
model as spheres fixed to its bodies (a capsule as spheres along its axis that together
contain it, a mesh as one sphere per grid cell fitted to the cell's piece of its hull), the scene
as boxes, half-spaces and convex polytopes, and takes its pairs from MuJoCo's collision
filters in each context. :func:`uvms_jax.plan.docking_world` turns that model into a
:class:`SphereWorld`, and :func:`world_collides` answers the planner's question for whole
populations of configurations in one jitted call:

* a sphere hits a box when its exact distance is at most ``radius + margin`` (the squared
  distance of the sphere's centre to the box, no square root), a polytope when its largest
  signed face distance is (a lower bound of the distance: both are the planner's tests);
* two capsules of the arm by the exact distance of their axes, any other pair of arm geoms
  by their spheres; fixed spheres (the base link, sphere and capsule obstacles) likewise.

Frames (written once): the spheres sit in their body's frame (slot 0 the arm's base, slot
``b + 1`` the body moved by joint ``b``, :func:`uvms_jax.kin.kinematics`'s ``T_base_joint``);
obstacles fixed to the vehicle (its hull, the arm's mount) in the arm's base frame B, the
scene's in the world W. Everything is tested in B: the scene's obstacles are moved there once
per vehicle pose. Metres.

A docking target is reached in several contexts of the planner (the object ignored on the way
down, held on the way up, …); its row of the world holds the union of those contexts' pairs,
so a configuration free in its row is free in each of its contexts.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from uvms_jax import kin
from uvms_jax.robot import capsule_spheres
from uvms_jax.evo import _world_gpu
from uvms_jax.evo._geometry import (
    SLACK,
    SphereWorld,
    WorldRows,
    box_gap2,
    dot,
    make_sphere_world,
    plane,
    segment_distance,
)

_EXACT = jax.lax.Precision.HIGHEST  # full float32 products on GPUs (TF32 moves points by ~1e-3)


def _row_hits(row: WorldRows, frames: Array, box_c: Array, box_R: Array, box_half: Array, faces: Array,
              balls: Array, margin: Array, n_faces: tuple[int, ...]) -> Array:
    """Whether configurations collide in one row (one target).

    The configurations are the trailing axes ``(P, S)`` of every array (vehicle poses, seeds), so
    each test's reduction runs over the leading sphere and obstacle axes: a column reduction,
    one loop per configuration (with the configurations first, XLA's GPU reduction emitter
    turned the short rows of a few spheres × obstacles into kernels that took minutes to compile).

    Args:
      row: the target's spheres and pairs (:class:`WorldRows` without its leading axis).
      frames: ``(n + 1, 3, 4, P, S)`` the base and body frames in B.
      box_c, box_R: ``(B, 3, P, 1)``, ``(B, 3, 3, P, 1)``; box_half ``(B, 3)``.
      faces: ``(Q, F, 4, P, 1)`` polytopes; balls: ``(M, 4, P, 1)`` fixed spheres; in B.
      margin: safety distance plus slack [m]; n_faces: each polytope's unpadded face count.

    Returns:
      ``(P, S)`` bool.
    """
    # Products written out as sums of broadcast terms (no dot products): XLA then fuses each
    # test into one loop over spheres × obstacles instead of materialising its operands.
    config = (None, None)  # the two trailing configuration axes
    F = frames[row.body]  # (N, 3, 4, P, S)
    X = F[:, :, 3] + sum(F[:, :, j] * row.centre[:, j, None, None, None] for j in range(3))  # (N, 3, P, S)
    reach = (row.radius + margin)[(...,) + config]  # (N, 1, 1)
    x = [X[:, j] for j in range(3)]  # (N, P, S) each
    at = [x_j[:, None] for x_j in x]  # (N, 1, P, S): the spheres against an obstacle axis
    gap2 = box_gap2(at, [box_c[:, j] for j in range(3)], [[box_R[:, j, i] for i in range(3)] for j in range(3)],
                     [box_half[:, i, None, None] for i in range(3)])  # (N, B, P, S)
    hit = jnp.any((gap2 <= (reach * reach)[:, None]) & row.box_on[(...,) + config], axis=(0, 1))
    # The largest face distance as a chain of maxima, not a reduction over a few dozen faces
    # (the same emitter trouble); each polytope's own faces only.
    for p, n in enumerate(n_faces):
        face = functools.reduce(jnp.maximum, (plane(x, faces[p, i]) for i in range(n)))
        hit |= jnp.any((face <= reach) & row.face_on[:, p, None, None], axis=0)
    gap = [at[j] - balls[:, j] for j in range(3)]  # (N, M, P, S) each
    both = reach[:, None] + balls[:, 3]
    hit |= jnp.any((dot(gap, gap) <= both * both) & row.ball_on[(...,) + config], axis=(0, 1))
    a, b = row.pair_a, row.pair_b  # a dense block of pairs: no gather per pair
    d = [x_j[a][:, None] - x_j[b] for x_j in x]  # (A, A', P, S) each
    both = reach[a][:, None] + row.radius[b][(None, slice(None)) + config]
    hit |= jnp.any((dot(d, d) <= both * both) & row.pair_on[(...,) + config], axis=(0, 1))
    G = frames[row.cap_body]  # (C, 2, 3, 4, P, S)
    ends = [[[G[:, g, i, 3] + sum(G[:, g, i, j] * row.cap_ends[:, g, e, j, None, None] for j in range(3))
              for i in range(3)] for e in range(2)] for g in range(2)]  # 3 components of (C, P, S) each
    dist = segment_distance(ends[0][0], ends[0][1], ends[1][0], ends[1][1])  # (C, P, S)
    return hit | jnp.any((dist <= (row.cap_reach + margin)[(...,) + config]) & row.cap_on[(...,) + config], axis=0)


def obstacles_in_base(world: SphereWorld, T_world_base: Array) -> tuple[Array, Array, Array, Array, Array]:
    """The world's obstacles in the arm's base frame for base poses ``T_world_base (..., 4, 4)``:
    box centres ``(..., B, 3)``, axes ``(..., B, 3, 3)``, half extents ``(B, 3)``, polytopes
    ``(..., P, F, 4)`` and fixed spheres ``(..., M, 4)``."""
    R, p = T_world_base[..., :3, :3], T_world_base[..., :3, 3]  # (..., 3, 3), (..., 3)
    nb, nf = world.n_base_boxes, world.n_base_faces
    batch = T_world_base.shape[:-2]
    to_base = lambda x: jnp.einsum("...ji,...kj->...ki", R, x - p[..., None, :], precision=_EXACT)  # noqa: E731  Rᵀ (x − p)
    fixed = lambda x: jnp.broadcast_to(x, batch + x.shape)  # noqa: E731
    c = jnp.concatenate([fixed(world.box_c[:nb]), to_base(world.box_c[nb:])], axis=-2)
    axes = jnp.concatenate([fixed(world.box_R[:nb]), jnp.einsum("...ji,bjk->...bik", R, world.box_R[nb:], precision=_EXACT)],
                           axis=-3)
    # n·x + d with x = R y + p: (Rᵀ n)·y + (n·p + d)
    n_w, d_w = world.faces[nf:, :, :3], world.faces[nf:, :, 3]
    n_b = jnp.einsum("...ji,pfj->...pfi", R, n_w, precision=_EXACT)
    d_b = d_w + jnp.einsum("pfj,...j->...pf", n_w, p, precision=_EXACT)
    faces = jnp.concatenate([fixed(world.faces[:nf]), jnp.concatenate([n_b, d_b[..., None]], axis=-1)], axis=-3)
    balls = jnp.concatenate([to_base(world.balls[:, :3]), fixed(world.balls[:, 3:])], axis=-1)
    return c, axes, world.box_half, faces, balls


#: Elements of the tests' blocks (sphere × obstacle face or box, sphere pairs) one chunk of
#: :func:`world_collides` may hold at once (about 1 GB of float32 per array).
TEST_BUDGET = 2**28


def world_collides(world: SphereWorld, group: Array, T_world_base: Array, T_base_joint: Array) -> Array:
    """Collision of arm configurations in the planner's world (traceable).

    Args:
      world: the world (its rows indexed by ``group``).
      group: ``(k,)`` the row (target) of each demanded tool pose.
      T_world_base: ``(..., 4, 4)`` the arm's base in W, one per vehicle pose.
      T_base_joint: ``(..., k, S, n, 4, 4)`` the body frames in B of ``S`` configurations per
        tool pose (:func:`uvms_jax.kin.kinematics`).

    Returns:
      ``(..., k, S)`` True where a tested pair is nearer than the margin (plus :data:`SLACK`).
    """
    if _world_gpu.applies(T_base_joint):  # on a GPU, one thread per configuration (the same tests)
        return _world_gpu.world_collides_kernel(world, group, T_world_base, T_base_joint)
    batch = T_world_base.shape[:-2]
    k, S, n = T_base_joint.shape[-5:-2]
    rows = jax.tree_util.tree_map(lambda a: a[group], world.rows)
    obstacles = obstacles_in_base(world, T_world_base.reshape((-1, 4, 4)))
    eye = jnp.broadcast_to(jnp.eye(4, dtype=T_base_joint.dtype), T_base_joint.shape[:-3] + (1, 4, 4))
    frames = jnp.concatenate([eye, T_base_joint], axis=-3).reshape((-1, k, S, n + 1, 4, 4))
    margin = world.margin + SLACK
    c, R, half, faces, balls = obstacles
    per_target = jax.vmap(lambda row, F, *obs: _row_hits(row, F, *obs[:2], half, *obs[2:], margin, world.n_faces),
                          in_axes=(0, 0, None, None, None, None))

    def hits_of(frames, c, R, faces, balls):
        """``(P, k, S)`` for P vehicle poses: the configurations moved to the trailing axes."""
        last = lambda x: jnp.moveaxis(x, 0, -1)[..., None]  # noqa: E731  (P, ...) → (..., P, 1)
        F = jnp.moveaxis(frames[..., :3, :], (0, 2), (-2, -1))  # (k, n + 1, 3, 4, P, S)
        return jnp.moveaxis(per_target(rows, F, last(c), last(R), last(faces), last(balls)), 0, 1)

    # XLA materialises each test's (spheres × obstacles) and (sphere pairs) block per
    # configuration: a mesh arm's thousand spheres make megabytes each, so the vehicle poses go
    # through in chunks that keep a call's blocks under TEST_BUDGET elements.
    N = rows.radius.shape[-1]
    per_config = N * (half.shape[0] + sum(world.n_faces) + balls.shape[-2]) + rows.pair_on[0].size
    chunk = max(1, TEST_BUDGET // (k * S * per_config))
    poses = frames.shape[0]
    if chunk >= poses:
        hits = hits_of(frames, c, R, faces, balls)
    else:  # whole chunks (the last padded with copies of the first pose), one after another
        n_chunks = -(-poses // chunk)
        pad = n_chunks * chunk - poses
        split = lambda x: jnp.concatenate([x, jnp.broadcast_to(x[:1], (pad,) + x.shape[1:])]).reshape(  # noqa: E731
            (n_chunks, chunk) + x.shape[1:])
        hits = jax.lax.map(lambda a: hits_of(*a), tuple(map(split, (frames, c, R, faces, balls))))
        hits = hits.reshape((n_chunks * chunk, k, S))[:poses]
    return hits.reshape(batch + (k, S))


def capsule_world(chain: kin.Chain, link_radius: float, T_vehicle_base, vehicle_boxes, scene_boxes, n_rows: int,
                  spacing: float, dtype=None) -> SphereWorld:
    """The world of an arm without a planning scene: its links as capsules of ``link_radius``
    [m] between consecutive joint origins (the base origin to the first joint, the last joint
    to the tool point, as the arm's MuJoCo model has them), as spheres ``spacing`` [m] apart
    that contain them, against the vehicle's and the scene's boxes; no self-collision, no
    margin. The base's capsule is tested against the scene only (it is fixed to the vehicle).

    Args:
      chain: the arm; link_radius: its capsules' radius [m].
      T_vehicle_base: ``(4, 4)`` the mount [m].
      vehicle_boxes, scene_boxes: ``(T (m, 4, 4), half (m, 3))`` in V and in W [m].
      n_rows: rows (targets); every row is the same.
      spacing: sphere spacing along the capsules [m].
      dtype: float dtype.
    """
    T0 = np.asarray(chain.T_base_joint0, dtype=np.float64)
    ends = np.concatenate([T0[:, :3, 3], np.asarray(chain.T_base_tool0, dtype=np.float64)[None, :3, 3]])
    body, centre, radius, scene_only = [], [], [], []
    for b in range(-1, chain.n_joints):
        T_b = np.eye(4) if b < 0 else T0[b]
        a, e = T_b[:3, 3], ends[b + 1]
        if np.linalg.norm(e - a) < 1e-9:
            c, r = a[None], np.array([link_radius])
        else:
            z = (e - a) / np.linalg.norm(e - a)
            x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
            R = np.stack([x / np.linalg.norm(x), np.cross(z, x / np.linalg.norm(x)), z], axis=-1)
            c, r = capsule_spheres((a + e) / 2, R, link_radius, np.linalg.norm(e - a) / 2, spacing)
        c_body = (c - T_b[:3, 3]) @ T_b[:3, :3]  # into the body's frame
        body += [b + 1] * len(r)
        centre += list(c_body)
        radius += list(r)
        scene_only += [b < 0] * len(r)
    T_vb = np.asarray(T_vehicle_base, dtype=np.float64)
    T_bv = np.linalg.inv(T_vb)
    Tv, hv = (np.asarray(x, dtype=np.float64).reshape(-1, *s) for x, s in zip(vehicle_boxes, ((4, 4), (3,))))
    Ts, hs = (np.asarray(x, dtype=np.float64).reshape(-1, *s) for x, s in zip(scene_boxes, ((4, 4), (3,))))
    Tv = T_bv @ Tv  # the vehicle's boxes in B
    T_all = np.concatenate([Tv, Ts])
    N, B = len(radius), len(T_all)
    box_on = np.ones((N, B), bool)
    box_on[np.asarray(scene_only), : len(Tv)] = False
    tile = lambda x: np.broadcast_to(np.asarray(x), (n_rows,) + np.shape(x))  # noqa: E731
    rows = {"body": tile(body), "centre": tile(centre), "radius": tile(radius), "box_on": tile(box_on),
            "face_on": np.zeros((n_rows, N, 0), bool), "ball_on": np.zeros((n_rows, N, 0), bool),
            "pair_a": np.zeros((n_rows, 0), int), "pair_b": np.zeros((n_rows, 0), int),
            "pair_on": np.zeros((n_rows, 0, 0), bool),
            "cap_body": np.zeros((n_rows, 0, 2), int), "cap_ends": np.zeros((n_rows, 0, 2, 2, 3)),
            "cap_reach": np.zeros((n_rows, 0)), "cap_on": np.zeros((n_rows, 0), bool)}
    boxes = {"c": T_all[:, :3, 3], "R": T_all[:, :3, :3], "half": np.concatenate([hv, hs]),
             "vehicle": np.arange(B) < len(Tv)}
    return make_sphere_world(rows, boxes, np.zeros((0, 1, 4)), np.zeros((0, 4)), 0.0, len(Tv), 0, dtype)
