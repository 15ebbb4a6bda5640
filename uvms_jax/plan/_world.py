"""A pick-and-place scene as a docking task (:func:`docking_task`), and the planner's collision
model as docking's: a :class:`uvms_jax.evo.SphereWorld` read from the :class:`SphereChecker` of
the scene with the vehicle in it (:func:`docking_world`).

The arm's spheres, the scene's boxes, half-spaces and polytopes and the pairs tested in each
:class:`Context` are the sphere checker's own (its arrays, MuJoCo's collision filters of the
scene's model); only their frames change, since docking moves the vehicle: the obstacles fixed
to it (its hull, the arm's mount) and the base link's spheres go into the arm's base frame,
the rest stays in the world. One row per docking target holds the pairs of the contexts in
which the planner checks that target's configuration (:func:`node_contexts`: the way down
and the way up).
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from uvms_jax import evo, frames
from uvms_jax.plan._collision import CollisionChecker
from uvms_jax.plan._scene import Context, Scene
from uvms_jax.plan._settings import PlanSettings
from uvms_jax.plan._spec import Obstacle, SceneSpec
from uvms_jax.plan._spheres import MESH_CELL, SphereChecker, _pair_filter
from uvms_jax.plan._targets import node_contexts, tool_poses
from uvms_jax.robot import SPHERE_SPACING

__all__ = ["VEHICLE_PREFIX", "docked_scene", "docking_task", "docking_world", "sphere_world", "vehicle_obstacles"]

#: Name prefix of the vehicle's boxes as obstacles of a planning scene (``vehicle0``, …).
VEHICLE_PREFIX = "vehicle"


def vehicle_obstacles(T_world_vehicle, T_vehicle_box, half) -> tuple[Obstacle, ...]:
    """The vehicle's boxes ``(m, 4, 4)``, ``half (m, 3)`` [m] (in V) at its pose
    ``T_world_vehicle (4, 4)``, as planning-scene obstacles ``vehicle0 …`` (world frame)."""
    out = []
    for i, (T, h) in enumerate(zip(np.asarray(T_vehicle_box, dtype=float), np.asarray(half, dtype=float))):
        W = np.asarray(T_world_vehicle, dtype=float) @ T
        out.append(Obstacle(f"{VEHICLE_PREFIX}{i}", "box", tuple(W[:3, 3].tolist()),
                            tuple(frames.matrix_rpy(W[:3, :3]).tolist()), tuple((2 * h).tolist())))
    return tuple(out)


def docked_scene(scenario, problem: evo.ArmDockingProblem, pose) -> tuple[np.ndarray, np.ndarray, SceneSpec]:
    """The planning scene of a docked vehicle: the scenario (a mapping or a :class:`SceneSpec`)
    with the arm's base on the vehicle at ``pose (4,) = [x, y, z, ψ]`` [m, rad] (the docking
    problem's mount) and the vehicle's boxes as obstacles.

    Returns:
      ``(T_world_vehicle (4, 4), T_world_base (4, 4), scene spec)``.
    """
    T_world_vehicle, T_world_base, _ = (np.asarray(a, dtype=float) for a in
                                        evo.arm_tool_poses(problem, np.asarray(pose, problem.pose_low.dtype)))
    spec = scenario if isinstance(scenario, SceneSpec) else SceneSpec.from_mapping(scenario)
    spec = spec.with_base(T_world_base)
    vehicle = vehicle_obstacles(T_world_vehicle, problem.T_vehicle_box, problem.vehicle_half)
    return T_world_vehicle, T_world_base, dataclasses.replace(spec, obstacles=spec.obstacles + vehicle)


def _row(checker: SphereChecker, contexts, polys, static) -> tuple:
    """Geom-level pairs of one row: moving geom × polytope ``(G, P)``, moving × fixed geom
    ``(G, S)`` and moving × moving ``(G, G)`` (upper triangle), each tested in some context."""
    moving = checker._moving
    G = len(moving)
    poly_on = np.zeros((G, len(polys)), bool)
    static_on = np.zeros((G, len(static)), bool)
    self_on = np.zeros((G, G), bool)
    for ctx in contexts:
        checker.reference._enter(ctx)  # the model's bits in this context (rejects an unknown one)
        collides = _pair_filter(checker.reference._m)
        for i, g in enumerate(moving):
            poly_on[i] |= np.array([collides(g, o) for o in polys], dtype=bool)
            static_on[i] |= np.array([collides(g, s) for s in static], dtype=bool)
            for j in range(i + 1, G):
                self_on[i, j] |= collides(g, moving[j])
    return poly_on, static_on, self_on


def sphere_world(checker: SphereChecker, rows: list[tuple[Context, ...]], attached: set[int],
                 dtype=None) -> evo.SphereWorld:
    """The sphere checker's model of its scene as a :class:`~uvms_jax.evo.SphereWorld`.

    Args:
      checker: the scene's sphere checker (its margin is the world's).
      rows: per row, the contexts whose pairs it tests (their union).
      attached: geom ids of the static polytopes that move with the arm's base (the vehicle's
        boxes, the mount; the base link's own are added): they go into the base frame, the rest
        stays in the world.
      dtype: float dtype of the world.

    Raises:
      ValueError: an arm body that is not the robot's link of that number.
    """
    scene = checker.reference.scene
    m = scene.model
    robot = scene.robot
    names = [m.body(b).name for b in range(1, m.nbody) if m.body_weldid[b] == b]
    if names != list(robot.link_names):
        raise ValueError(f"the scene's moving bodies {names} are not the arm's links {list(robot.link_names)}")
    base_geoms = set(scene.base_geoms)
    static = sorted(checker._static)
    attached = set(attached) | base_geoms  # a base link of meshes: polytopes fixed to the base
    o = _obstacles(checker, attached, base_geoms, static)
    built = [_world_row(checker, contexts, o, static, base_geoms) for contexts in rows]
    return evo.make_sphere_world(_pad(built), o.boxes, o.faces, np.reshape(o.balls, (-1, 4)), checker.margin,
                                 o.n_base_boxes, o.n_base_faces, dtype, o.face_sizes)


class _Obstacles(NamedTuple):
    """The scene's fixed obstacles in a sphere world's frames (base-fixed ones first).

    Attributes:
      col: polytope index → ``("box" | "face", column)`` in the masks.
      boxes: ``{"c", "R", "half", "vehicle"}`` lists of the boxes (centre, axes, half extents
        [m], part of the vehicle's body).
      faces: ``(n, F, 4)`` the other polytopes' face planes (repeated to F).
      balls: fixed spheres in the world ``[c, r]`` [m]; ball_of: static geom → their indices.
      n_base_boxes, n_base_faces: how many boxes and polytopes are fixed to the base.
      face_sizes: each polytope's number of faces.
    """

    col: dict
    boxes: dict
    faces: np.ndarray
    balls: list
    ball_of: dict
    n_base_boxes: int
    n_base_faces: int
    face_sizes: list


def _obstacles(checker: SphereChecker, attached: set[int], base_geoms: set[int], static: list[int]) -> _Obstacles:
    """The checker's polytopes (those ``attached`` to the base in its frame, the rest in the
    world) and its fixed spheres not on the base link, in the columns' order."""
    scene = checker.reference.scene
    m = scene.model
    T_base_world = np.linalg.inv(scene.T_world_base)
    R_bw, p_bw = T_base_world[:3, :3], T_base_world[:3, 3]
    polys, starts, ends, _, _, boxes, _ = checker._polytopes
    # Obstacles: the base's first, then the world's (the order of the masks' columns).
    box_cols, face_cols, col = {"base": [], "world": []}, {"base": [], "world": []}, {}
    for k, g in enumerate(polys):
        side = "base" if g in attached else "world"
        (box_cols if boxes[k, 0, 0] > 0 else face_cols)[side].append(k)
    box_order, face_order = box_cols["base"] + box_cols["world"], face_cols["base"] + face_cols["world"]
    c, R, half, vehicle = [], [], [], []
    for j, k in enumerate(box_order):
        H = boxes[k, 2:5]  # rows: axis × half edge
        h = np.linalg.norm(H, axis=1)
        Rk, ck = (H / h[:, None]).T, boxes[k, 1]
        if polys[k] in attached:
            Rk, ck = R_bw @ Rk, R_bw @ ck + p_bw
        c.append(ck)
        R.append(Rk)
        half.append(h)
        vehicle.append(polys[k] in attached and m.geom(polys[k]).name != "mount")
        col[k] = ("box", j)
    F = max([ends[k] - starts[k] for k in face_order], default=1)
    faces = np.zeros((len(face_order), F, 4))
    for j, k in enumerate(face_order):
        eq = checker._faces[starts[k]:ends[k]]
        if polys[k] in attached:  # n·x + d with x = R y + p: (Rᵀ n)·y + (n·p + d), R, p of the base in W
            eq = np.c_[eq[:, :3] @ R_bw.T, eq[:, 3] + eq[:, :3] @ scene.T_world_base[:3, 3]]
        faces[j] = np.concatenate([eq, np.repeat(eq[:1], F - len(eq), axis=0)])  # repeats leave the max alone
        col[k] = ("face", j)
    balls, ball_of = [], {}  # fixed spheres in the world (obstacles), by static geom
    for s in static:
        if s not in base_geoms:
            cs, rs = checker._static[s]
            ball_of[s] = list(range(len(balls), len(balls) + len(rs)))
            balls += [np.r_[ci, ri] for ci, ri in zip(cs, rs)]
    return _Obstacles(col, {"c": c, "R": R, "half": half, "vehicle": vehicle}, faces, balls, ball_of,
                      len(box_cols["base"]), len(face_cols["base"]), [ends[k] - starts[k] for k in face_order])


def _world_row(checker: SphereChecker, contexts, o: _Obstacles, static: list[int], base_geoms: set[int]) -> tuple:
    """One row of the world: the spheres of the moving geoms tested in ``contexts`` (and of
    the base link's fixed ones they meet, in B), and their masks against the obstacles, pairs
    and capsule pairs."""
    scene = checker.reference.scene
    sph_body, centres, radii, g_start, g_end, g_body, _, _, g_seg, g_cap = checker._spheres
    polys = checker._polytopes[0]
    poly_on, static_on, self_on = _row(checker, contexts, polys, static)
    used = poly_on.any(1) | static_on.any(1) | self_on.any(1) | self_on.any(0)
    body, cen, rad, first = [], [], [], {}
    for i in np.flatnonzero(used):
        first[i] = len(rad)
        for q in range(g_start[i], g_end[i]):
            body.append(sph_body[q] + 1)
            cen.append(centres[q])
            rad.append(radii[q])
    base_first = {}
    for si, s in enumerate(static):
        if s in base_geoms and static_on[:, si].any():
            cs, rs = checker._static[s]
            base_first[si] = len(rad)
            body += [0] * len(rs)
            cen += list((cs - scene.T_world_base[:3, 3]) @ scene.T_world_base[:3, :3])  # into B
            rad += list(rs)
    N = len(rad)
    box_on = np.zeros((N, len(o.boxes["c"])), bool)
    face_on = np.zeros((N, len(o.faces)), bool)
    ball_on = np.zeros((N, len(o.balls)), bool)
    pairs, caps = [], []
    spheres_of = lambda i: range(first[i], first[i] + g_end[i] - g_start[i])  # noqa: E731
    for i in first:
        for k in np.flatnonzero(poly_on[i]):
            kind, j = o.col[k]
            (box_on if kind == "box" else face_on)[list(spheres_of(i)), j] = True
        for si in np.flatnonzero(static_on[i]):
            s = static[si]
            if s in base_geoms:
                n_s = len(checker._static[s][1])
                pairs += [(a, b) for a in spheres_of(i) for b in range(base_first[si], base_first[si] + n_s)]
            else:
                ball_on[np.ix_(list(spheres_of(i)), o.ball_of[s])] = True
        for j in np.flatnonzero(self_on[i]):
            if g_cap[i] > 0 and g_cap[j] > 0:  # two capsules: their axes' exact distance
                caps.append((g_body[i] + 1, g_body[j] + 1, g_seg[i], g_seg[j], g_cap[i] + g_cap[j]))
            else:
                pairs += [(a, b) for a in spheres_of(i) for b in spheres_of(j)]
    return body, cen, rad, box_on, face_on, ball_on, pairs, caps

def _pad(built: list) -> dict:
    """The rows' lists as arrays padded to the longest row (padding tests nothing)."""
    r = len(built)
    N = max(len(b[2]) for b in built)
    # Sphere pairs as a block: the spheres that come first in some pair × those that come second.
    firsts = [sorted({a for a, _ in b[6]}) for b in built]
    seconds = [sorted({c for _, c in b[6]}) for b in built]
    A, A2 = max(map(len, firsts)), max(map(len, seconds))
    C = max(len(b[7]) for b in built)
    B, P, M = (built[0][i].shape[1] for i in (3, 4, 5))
    out = {"body": np.zeros((r, N), int), "centre": np.zeros((r, N, 3)), "radius": np.zeros((r, N)),
           "box_on": np.zeros((r, N, B), bool), "face_on": np.zeros((r, N, P), bool), "ball_on": np.zeros((r, N, M), bool),
           "pair_a": np.zeros((r, A), int), "pair_b": np.zeros((r, A2), int), "pair_on": np.zeros((r, A, A2), bool),
           "cap_body": np.zeros((r, C, 2), int),
           "cap_ends": np.zeros((r, C, 2, 2, 3)), "cap_reach": np.zeros((r, C)), "cap_on": np.zeros((r, C), bool)}
    for i, (body, cen, rad, box_on, face_on, ball_on, pairs, caps) in enumerate(built):
        n = len(rad)
        out["body"][i, :n], out["centre"][i, :n], out["radius"][i, :n] = body, np.reshape(cen, (-1, 3)), rad
        out["box_on"][i, :n], out["face_on"][i, :n], out["ball_on"][i, :n] = box_on, face_on, ball_on
        out["pair_a"][i, :len(firsts[i])], out["pair_b"][i, :len(seconds[i])] = firsts[i], seconds[i]
        at_a, at_b = {a: j for j, a in enumerate(firsts[i])}, {c: j for j, c in enumerate(seconds[i])}
        for a, c in pairs:
            out["pair_on"][i, at_a[a], at_b[c]] = True
        for j, (ba, bb, sa, sb, reach) in enumerate(caps):
            out["cap_body"][i, j], out["cap_ends"][i, j], out["cap_reach"][i, j] = (ba, bb), (sa, sb), reach
            out["cap_on"][i, j] = True
    return out


def docking_world(scene: Scene, T_vehicle_base, vehicle_boxes, margin: float, spacing: float = SPHERE_SPACING,
                  cell: float = MESH_CELL, dtype=None) -> evo.SphereWorld:
    """The planner's world of a docking task (:func:`docking_task`'s targets, in its order).

    The scene's arm hangs from a vehicle through the mount ``T_vehicle_base (4, 4)`` [m]; the
    vehicle's boxes ``(T (m, 4, 4), half (m, 3))`` in V [m] join the scene as obstacles (as
    the docked scene has them), and the sphere checker of that scene, with the planner's safety
    ``margin`` [m], ``spacing`` and ``cell`` [m], gives the world: one row per target, the
    pairs of its way down and its way up (:func:`node_contexts`).
    """
    T_world_vehicle = scene.T_world_base @ np.linalg.inv(np.asarray(T_vehicle_base, dtype=float))
    spec = scene.spec
    spec = dataclasses.replace(spec, obstacles=spec.obstacles + vehicle_obstacles(T_world_vehicle, *vehicle_boxes),
                               start_q=tuple(scene.start_q))  # only geometry is read: no start search
    docked = Scene(spec, scene.robot)
    checker = SphereChecker(CollisionChecker(docked, margin), spacing, cell)
    m = docked.model
    on_vehicle = {"mount", *(o.name for o in vehicle_obstacles(T_world_vehicle, *vehicle_boxes))}
    attached = {g for g in range(m.ngeom) if m.geom(g).name in on_vehicle}
    nodes = sorted(docked.objects) + sorted(docked.bases)
    rows = [tuple(node_contexts(docked, n)[step] for step in ("down", "up")) for n in nodes]
    return sphere_world(checker, rows, attached, dtype)


def docking_task(scene: Scene, n_yaw_continuous: int = 8, vehicle: evo.ArmSceneSettings | None = None,
                 margin: float = PlanSettings.margin) -> evo.ArmTask:
    """What a docking optimiser must let the arm reach in this scene: the grasp pose of every
    object and the place pose of every base (one target each, in node order), each symmetric
    yaw of the object an alternative pose of its target; the scene's tables as obstacles.
    World frame, independent of the arm's base pose.

    With ``vehicle`` (the docking scene: the mount and the vehicle's boxes) the task carries the
    planner's world of the arm on that vehicle in this scene (:func:`docking_world`, safety
    ``margin`` [m]), and docking tests its IK solutions there; without, docking falls back to
    the arm's link capsules against the tables (:func:`uvms_jax.evo.capsule_world`).
    """
    nodes = sorted(scene.objects) + sorted(scene.bases)
    poses, group = [], []
    for i, node in enumerate(nodes):
        at = tool_poses(scene, node, n_yaw_continuous)[1]
        poses.append(at)
        group += [i] * len(at)
    names = tuple((scene.objects.get(node) or scene.bases[node]).name for node in nodes)
    tables = scene.spec.tables
    T_box = np.stack([t.T_world_box for t in tables])
    half = np.stack([np.asarray(t.size) / 2 for t in tables])
    world = None
    if vehicle is not None:
        world = docking_world(scene, frames.rpy_pose(vehicle.mount_xyz, vehicle.mount_rpy),
                              evo.boxes(vehicle.vehicle_boxes), margin)
    return evo.ArmTask(np.concatenate(poses), np.asarray(group), names, T_box, half, world)
