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
from uvms_jax.plan._vector_kernels import BOX, CAPSULE, CYLINDER, POLYTOPE, SPHERE

__all__ = ["World", "add_obstacles", "obstacle_rows"]

ROW = 20  # floats per obstacle row of the compiled checker


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
