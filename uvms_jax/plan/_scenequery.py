"""A pick-and-place scene on the query path: the scene in a :class:`Context` as a
:class:`~uvms_jax.plan.World` in the arm's base frame (:func:`scene_world`), the object in the
jaws as a shape fixed to the arm's last body (:func:`held_shapes`), their compiled checker
(:func:`scene_checker`) and one edge planned with :func:`~uvms_jax.plan.plan_query` and
re-checked by the scene's MuJoCo :class:`~uvms_jax.plan.CollisionChecker` (:func:`plan_scene_query`).

The world is read from the scene's MuJoCo model, so that both checkers collide with the same
geometry: every static geom the context leaves on (tables, cage profiles, base plates, objects,
extra obstacles, the mount and a vehicle's hull) becomes an obstacle — a box where its convex
mesh is a box, else a mesh of its vertices, spheres and capsules as themselves — and the
half-spaces (the ceiling, the table under everything) become boxes whose face is their plane
and which reach past everything the arm can reach. The pairs the scene never tests go into the
world's allowed collision matrix: the self-collision pairs it excludes, with the jaws and the
held object on the last link (they are geoms of that link in the scene), and the base link's
pairs that its collision bits keep apart. A world allows link pairs, not a link and an
obstacle: the first link is tested against the mount, which the scene leaves out (the query
path is the stricter there; the two agree state by state on the thesis scenes, see the tests).
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.plan._collision import CollisionChecker
from uvms_jax.plan._planning import PlanResult, check_ends
from uvms_jax.plan._query import plan_query
from uvms_jax.plan._scene import FIRST_BITS, SHOULDER_BITS, Context, Scene
from uvms_jax.plan._settings import PlanSettings
from uvms_jax.plan._spec import Obstacle
from uvms_jax.plan._vector import VectorChecker
from uvms_jax.plan._worlds import World
from uvms_jax.robot import Shape, base_body, card_jaws

__all__ = ["held_shapes", "plan_scene_query", "scene_checker", "scene_world"]

#: How far past the arm's reach [m] a half-space's box extends: more than the jaws, the held
#: object and the links' radius reach beyond :attr:`Robot.max_reach`.
PLANE_SLACK = 1.0
_BOX_TOL = 1e-6  # [m] a convex mesh is a box when its 8 vertices are a box's within this (float32 vertices)
_GEOM = mujoco.mjtGeom


def _pose(pos, quat) -> np.ndarray:
    return frames.pose(frames.quat_matrix(quat), pos)


def _as_box(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(centre (3,), R (3, 3), size (3,))`` of the box whose corners are ``v (8, 3)`` [m],
    in ``v``'s frame; None when they are not a box's."""
    if len(v) != 8:
        return None
    d = np.linalg.norm(v - v[0], axis=1)
    edges = v[np.argsort(d)[1:4]] - v[0]
    size = np.linalg.norm(edges, axis=1)
    if np.min(size) < _BOX_TOL:
        return None
    R = edges / size[:, None]
    if np.max(np.abs(R @ R.T - np.eye(3))) > _BOX_TOL / np.min(size):
        return None
    corners = v[0] + np.array([[a, b, c] for a in (0, 1) for b in (0, 1) for c in (0, 1)]) @ edges
    if np.max(np.min(np.linalg.norm(corners[:, None] - v[None], axis=2), axis=1)) > _BOX_TOL:
        return None
    if np.linalg.det(R) < 0:
        R[2] = -R[2]
    return v.mean(0), R.T, size


def _mesh_vertices(m: mujoco.MjModel, g: int) -> np.ndarray:
    """``(k, 3)`` the vertices of mesh geom ``g`` in the geom's frame [m]."""
    k = m.geom_dataid[g]
    return m.mesh_vert[m.mesh_vertadr[k]: m.mesh_vertadr[k] + m.mesh_vertnum[k]].astype(float)


def _obstacle(scene: Scene, g: int, reach: float) -> Obstacle:
    """World geom ``g`` of the scene as an obstacle in the arm's base frame."""
    m = scene.model
    name, kind = m.geom(g).name, m.geom_type[g]
    T = scene.T_base_world @ _pose(m.geom_pos[g], m.geom_quat[g])
    if kind == _GEOM.mjGEOM_PLANE:  # the half-space under its plane, as far as the arm reaches
        foot = np.linalg.inv(T) @ np.r_[0.0, 0.0, 0.0, 1.0]  # the base's origin in the plane's frame
        T = T @ frames.pose(p=(foot[0], foot[1], -reach))
        return Obstacle(name, "box", tuple(T[:3, 3]), dims=(2 * reach,) * 3, quat=tuple(frames.matrix_quat(T[:3, :3])))
    if kind == _GEOM.mjGEOM_MESH:
        v = _mesh_vertices(m, g)
        box = _as_box(v)
        if box is not None:
            c, R, size = box
            T = T @ frames.pose(R, c)
            return Obstacle(name, "box", tuple(T[:3, 3]), dims=tuple(size), quat=tuple(frames.matrix_quat(T[:3, :3])))
        return Obstacle(name, "mesh", tuple(T[:3, 3]), quat=tuple(frames.matrix_quat(T[:3, :3])),
                        vertices=tuple(v.reshape(-1)))
    quat = tuple(frames.matrix_quat(T[:3, :3]))
    size = m.geom_size[g]
    if kind == _GEOM.mjGEOM_SPHERE:
        return Obstacle(name, "sphere", tuple(T[:3, 3]), dims=(float(size[0]),), quat=quat)
    if kind == _GEOM.mjGEOM_CAPSULE:
        return Obstacle(name, "capsule", tuple(T[:3, 3]), dims=(float(size[0]), 2 * float(size[1])), quat=quat)
    raise ValueError(f"scene geom {name!r}: type {_GEOM(kind).name} has no obstacle on the query path")


def held_shapes(scene: Scene, context: Context) -> tuple[Shape, ...]:
    """The object in the jaws in ``context`` as a mesh shape fixed to the arm's last body, at
    its grasp (the scene's in-hand copy; its link ``held_<name>``); empty when none is held."""
    if context.held is None:
        return ()
    if context.held not in scene.held_geoms:
        raise ValueError(f"unknown held object node {context.held} (objects: {sorted(scene.held_geoms)})")
    m, g = scene.model, scene.held_geoms[context.held]
    T = _pose(m.geom_pos[g], m.geom_quat[g])  # in the last link's frame
    return (Shape(scene.robot.n_joints - 1, "mesh", tuple(T.reshape(16)), vertices=tuple(_mesh_vertices(m, g).reshape(-1)),
                  link=m.geom(g).name),)


def _allowed(scene: Scene, attached: tuple[Shape, ...]) -> frozenset[frozenset[str]]:
    """The link pairs the scene never tests: its excluded self-collision pairs (with the jaws
    and the held object on the last link) and the base link's pairs its bits keep apart."""
    robot = scene.robot
    base = base_body(robot)
    link = {base: robot.base_link} | {name: name for name in robot.link_names}
    on = {name: {name} for name in link.values()}
    for s in card_jaws(robot, scene.spec.jaws_open) + attached:
        on[robot.link_names[s.body] if s.body >= 0 else robot.base_link].add(s.link)
    bits = scene.geom_bits(Context())
    m = scene.model
    apart = {m.body(m.geom_bodyid[g]).name for g in range(m.ngeom) if tuple(bits[:2, g]) in (FIRST_BITS, SHOULDER_BITS)}
    pairs = list(scene.self_collision["always"]) + [(base, b) for b in apart]
    return frozenset(frozenset((x, y)) for a, b in pairs for x in on[link[a]] for y in on[link[b]])


def scene_world(scene: Scene, context: Context) -> World:
    """The scene in ``context`` as a world in the arm's base frame (see the module docstring):
    the static geoms the context leaves on, and the pairs the scene never tests.

    Raises:
      ValueError: an unknown held object or obstacle in ``context``.
    """
    bits = scene.geom_bits(context)
    m = scene.model
    reach = scene.robot.max_reach + PLANE_SLACK
    obstacles = tuple(_obstacle(scene, g, reach) for g in range(m.ngeom) if m.geom_bodyid[g] == 0 and bits[0, g])
    return World(obstacles, _allowed(scene, held_shapes(scene, context)),
                 name=f"scene held={context.held} ignore={list(context.ignore)}")


def scene_checker(scene: Scene, context: Context, margin: float) -> VectorChecker:
    """The compiled checker of the arm in ``scene_world(scene, context)`` with the held object,
    the jaws at the scene's opening and ``margin`` [m]; built once per context and margin and
    kept by the scene."""
    key = ("query_checker", context, float(margin))
    if key not in scene.derived:
        opening = scene.spec.jaws_open if scene.robot.gripper is not None else None  # no jaws: nothing opens
        scene.derived[key] = VectorChecker(scene.robot, scene_world(scene, context), opening, margin,
                                           attached=held_shapes(scene, context))
    return scene.derived[key]


def plan_scene_query(scene: Scene, checker: CollisionChecker, q_start, q_goal, context: Context, planner: str,
                     settings: PlanSettings) -> PlanResult:
    """Plan ``q_start → q_goal`` (``(n,)`` [rad]) in ``context`` with :func:`plan_query` on
    :func:`scene_checker` (``settings``: budget, resolutions, margin, seed, straight shortcut),
    then re-check the path with the scene's ``checker`` at ``recheck_resolution``, margin 0
    (one attempt: a path that fails it is a failed edge). Planning time: the query's budgeted
    part (planning and simplification) and the straight shortcut's check.

    Raises:
      ValueError: an invalid start or goal for the scene's checker (the contacts are named).
    """
    s = settings
    q_start, q_goal = check_ends(checker, q_start, q_goal, context)
    vc = scene_checker(scene, context, s.margin)
    res = plan_query(scene.robot, vc.world, q_start, q_goal, planner=planner, budget_s=s.budget_s,
                     opening=scene.spec.jaws_open, resolution=s.resolution, check_resolution=s.recheck_resolution,
                     seed=s.seed, margin=s.margin, checker=vc)
    n = len(q_start)
    if not res.success:
        return PlanResult(False, np.zeros((0, n)), res.time_s, 1)
    t0 = time.perf_counter()
    path = res.path
    if s.straight_shortcut and len(path) > 2 and vc.motion_free(q_start, q_goal, s.recheck_resolution):
        path = np.stack([q_start, q_goal])
    spent = res.time_s + time.perf_counter() - t0
    ok = checker.path_is_valid(path, context, s.recheck_resolution, margin=0.0)
    # With the shortcut on, every straight path counts as one (RRTConnect returns it at once when it is free).
    return PlanResult(ok, path if ok else np.zeros((0, n)), spent, 1, s.straight_shortcut and ok and len(path) == 2)
