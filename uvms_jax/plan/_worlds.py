"""A world as data: static obstacles of any primitive in the robot's base frame, and the link
pairs allowed to touch (an allowed collision matrix, as MoveIt and SRDF files give it).

The same :class:`~uvms_jax.plan.Obstacle` describes an obstacle here and in a pick-and-place
scenario (box, cylinder, sphere, capsule, mesh; ``rpy`` or ``quat``). :func:`obstacle_rows`
turns a world into the compiled checker's rows (:mod:`uvms_jax.plan._vector_kernels`) and
:func:`add_obstacles` into MuJoCo geoms for the exact check, so both checkers see one world.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

import mujoco
import numpy as np
from scipy.spatial import ConvexHull

from uvms_jax import frames
from uvms_jax.plan._spec import Obstacle
from uvms_jax.plan._vector_kernels import BOX, CAPSULE, CYLINDER, POLYTOPE, SPHERE, _obstacle_distance

__all__ = ["World", "add_obstacles", "near_obstacles", "obstacle_rows"]

ROW = 20  # floats per obstacle row of the compiled checker
_NEAR_TOL = 1e-9  # [m] added to the reach and the boxes of near_obstacles: far above their float64 round-off


@dataclasses.dataclass(frozen=True)
class World:
    """Static obstacles around one robot, in its base frame, and the link pairs that may touch.

    Attributes:
      obstacles: the obstacles (names unique).
      allowed: link-name pairs whose contact is allowed (an allowed collision matrix), on top of
        the pairs every robot skips (a link and its parent, pairs touching in every pose).
      name: a label for reports.
    """

    obstacles: tuple[Obstacle, ...] = ()
    allowed: frozenset[frozenset[str]] = frozenset()
    name: str = "world"

    def __post_init__(self) -> None:
        names = [o.name for o in self.obstacles]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ValueError(f"world {self.name!r}: obstacle names must be unique, repeated: {twice}")

    def allows(self, a: str, b: str) -> bool:
        return frozenset((a, b)) in self.allowed


def _mesh_vertices(o: Obstacle) -> np.ndarray:
    """``(v, 3)`` vertices of a mesh obstacle (its file's as MuJoCo reads it, scaled), in its frame."""
    if o.vertices:
        return o.hull_vertices()
    spec = mujoco.MjSpec()
    spec.add_mesh(name="m", file=o.file, scale=[o.scale] * 3)
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m")
    model = spec.compile()
    return model.mesh_vert[: model.mesh_vertnum[0]].astype(float)


def obstacle_rows(obstacles: Iterable[Obstacle]) -> tuple[np.ndarray, np.ndarray]:
    """The compiled checker's arrays of ``obstacles``: rows ``(M, 20)`` and the polytopes' face
    equations ``(F, 4)`` (a mesh is its convex hull, as MuJoCo collides with it)."""
    rows, planes = [], []
    for o in obstacles:
        T = o.T_world
        R, c = T[:3, :3], T[:3, 3]
        row = np.zeros(ROW)
        if o.shape == "box":
            half = np.asarray(o.dims) / 2
            row[0], row[1:4], row[4:13], row[13:16] = BOX, c, R.reshape(9), half
            bound = float(np.linalg.norm(half))
        elif o.shape == "sphere":
            row[0], row[1:4], row[4] = SPHERE, c, o.dims[0]
            bound = o.dims[0]
        elif o.shape in ("capsule", "cylinder"):
            radius, length = o.dims
            row[0], row[1:4], row[4:7], row[7], row[8] = (CAPSULE if o.shape == "capsule" else CYLINDER), c, R[:, 2], \
                length / 2, radius
            bound = length / 2 + radius if o.shape == "capsule" else float(np.hypot(length / 2, radius))
        else:
            v = _mesh_vertices(o) @ R.T + c
            eq = ConvexHull(v).equations  # n·x + d ≤ 0 inside, |n| = 1
            row[0], row[1], row[2] = POLYTOPE, len(planes), len(planes) + len(eq)
            planes += list(eq)
            mid = (v.min(0) + v.max(0)) / 2
            c, bound = mid, float(np.max(np.linalg.norm(v - mid, axis=1)))
        row[16:19], row[19] = c, bound
        rows.append(row)
    return np.array(rows, dtype=float).reshape(-1, ROW), np.array(planes, dtype=float).reshape(-1, 4)


def add_obstacles(spec: mujoco.MjSpec, obstacles: Iterable[Obstacle], prefix: str = "obstacle_") -> list[str]:
    """Add ``obstacles`` to ``spec``'s world body as MuJoCo geoms named ``prefix + name``: boxes
    as 8-vertex convex meshes (MuJoCo's primitive capsule–box test misses a capsule whose axis
    crosses a thin box), the other primitives as themselves, meshes from their files or
    vertices. Returns the geom names."""
    names = []
    for o in obstacles:
        T = o.T_world
        name = prefix + o.name
        kw = dict(name=name, pos=T[:3, 3], quat=frames.matrix_quat(T[:3, :3]))
        if o.shape == "box" or o.vertices:
            spec.add_mesh(name="m_" + name, uservert=o.hull_vertices().reshape(-1))
            spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m_" + name, **kw)
        elif o.shape == "mesh":
            spec.add_mesh(name="m_" + name, file=o.file, scale=[o.scale] * 3)
            spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m_" + name, **kw)
        elif o.shape == "sphere":
            spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[o.dims[0], 0, 0], **kw)
        else:
            radius, length = o.dims
            kind = mujoco.mjtGeom.mjGEOM_CAPSULE if o.shape == "capsule" else mujoco.mjtGeom.mjGEOM_CYLINDER
            spec.worldbody.add_geom(type=kind, size=[radius, length / 2, 0], **kw)
        names.append(name)
    return names


def _obstacle_boxes(obstacles) -> np.ndarray:
    """``(M, 6)`` axis-aligned boxes around the obstacle rows ``(M, 20)``: centre, half extents
    [m] (a polytope: its bounding ball's)."""
    out = np.empty((len(obstacles), 6))
    for m, o in enumerate(obstacles):
        c, a = o[1:4], o[4:7]
        if o[0] == BOX:
            half = np.abs(o[4:13].reshape(3, 3)) @ o[13:16]
        elif o[0] == SPHERE:
            half = np.full(3, o[4])
        elif o[0] == CAPSULE:
            half = np.abs(a) * o[7] + o[8]
        elif o[0] == CYLINDER:  # the end discs reach r·sqrt(1 − a_i²) along axis i
            half = np.abs(a) * o[7] + o[8] * np.sqrt(np.clip(1.0 - a * a, 0.0, 1.0))
        else:
            c, half = o[16:19], np.full(3, o[19])
        out[m, :3], out[m, 3:] = c, half
    return out


def near_obstacles(kin, groups, obstacles, planes, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Per group, the obstacles it can meet in some pose, with their boxes grown by its bound:
    ``(start (G + 1,) int64, rows (K, 7))``, group ``g``'s rows ``start[g]:start[g + 1]``, each
    ``[obstacle row, box centre (3), half extents + bound radius + margin + tolerance (3)]``
    [m] (its bound meets the obstacle only with its centre inside that box).

    Joint 0 turns about its body's origin, so that point never moves; a group on body ``b``
    stays within ``|centre| + radius + Σ_{0<i≤b} |offset_i|`` of it (its bound's centre in the
    body's frame, the joints' fixed offsets up the chain; unbounded past a prismatic joint), and
    an obstacle farther than that plus the margin (a polytope's largest face distance, a lower
    bound) never meets it. The base's groups get none: both are fixed."""
    boxes = _obstacle_boxes(obstacles)
    origin = kin[0, 9:12] if len(kin) and kin[0, 15] == 0.0 else None
    start, rows = [0], []
    for g in range(len(groups)):
        b = int(groups[g, 2])
        reach = np.linalg.norm(groups[g, 3:6]) + groups[g, 6] + np.sum(np.linalg.norm(kin[1:b + 1, 9:12], axis=1))
        if origin is None or np.any(kin[:b + 1, 15] != 0.0):
            reach = np.inf
        for m in range(len(obstacles) if b >= 0 else 0):
            if reach < np.inf and _obstacle_distance(*origin, obstacles, m, planes) > reach + margin + _NEAR_TOL:
                continue
            rows.append([m, *boxes[m, :3], *(boxes[m, 3:] + groups[g, 6] + margin + _NEAR_TOL)])
        start.append(len(rows))
    return np.array(start, np.int64), np.array(rows, np.float64).reshape(-1, 7)
