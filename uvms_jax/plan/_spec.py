"""What defines a scene, as data (``configs/scenario/*.yaml``): tables, the objects on them and
the bases they go to, extra obstacles, the arm's mount, materials and the grasp geometry
(:class:`SceneSpec`), and the arm a scenario names (:func:`scenario_robot`).

World frame: origin at the centre of the cage floor, z up; metres and radians. Objects and
bases are task-graph nodes: given numbers, or by default the objects 1 … k and the bases
k + 1 … in the file's order; a base's ``fits`` names objects by name or number.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from uvms_jax import frames
from uvms_jax import robot as robots
from uvms_jax.plan._schema import MOUNT_KEYS, check_scenario, node_numbers
from uvms_jax.settings import SettingsError

__all__ = ["MOUNT_KEYS", "Base", "Box", "Item", "Obstacle", "SceneSpec", "box_vertices", "check_start_q", "scenario_robot"]

_CYLINDER_SIDES = 32  # inscribed polygon: radius error r(1 - cos(π/32)) ≈ 0.2 mm for r = 40 mm


@dataclasses.dataclass(frozen=True)
class Box:
    """A box obstacle: centre ``pos`` [m], full ``size`` [m], orientation ``rpy`` [rad] (world)."""

    name: str
    pos: tuple[float, float, float]
    size: tuple[float, float, float]
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def T_world_box(self) -> np.ndarray:
        return frames.pose(frames.rpy_matrix(self.rpy), self.pos)

    @property
    def T_world_top(self) -> np.ndarray:
        """Frame on the centre of the top face, z along the face normal."""
        return self.T_world_box @ frames.pose(p=(0.0, 0.0, self.size[2] / 2.0))


@dataclasses.dataclass(frozen=True)
class Item:
    """A pick object standing on a table.

    Attributes:
      node: task-graph node number (thesis Table 5.1).
      name: label.
      shape: ``box`` (dims = full edges x, y, z), ``cylinder`` (radius, height) or
        ``hex_prism`` (edge, height).
      dims: see ``shape`` [m].
      table: name of the supporting table.
      at: (u, v) position on the table top [m]; yaw [rad] about the top's normal.
    """

    node: int
    name: str
    shape: str
    dims: tuple[float, ...]
    table: str
    at: tuple[float, float]
    yaw: float = 0.0

    def __post_init__(self) -> None:
        need = {"box": 3, "cylinder": 2, "hex_prism": 2}
        if self.shape not in need:
            raise ValueError(f"object {self.name!r}: unknown shape {self.shape!r} (box, cylinder, hex_prism)")
        if len(self.dims) != need[self.shape] or min(self.dims) <= 0:
            raise ValueError(f"object {self.name!r}: {self.shape} needs {need[self.shape]} positive dims, got {self.dims}")

    @property
    def height(self) -> float:
        return self.dims[2] if self.shape == "box" else self.dims[1]

    @property
    def volume(self) -> float:
        if self.shape == "box":
            return float(np.prod(self.dims))
        if self.shape == "cylinder":
            return float(np.pi * self.dims[0] ** 2 * self.dims[1])
        return float(1.5 * np.sqrt(3.0) * self.dims[0] ** 2 * self.dims[1])

    @property
    def symmetry(self) -> float:
        """Yaw period of the shape about its axis [rad] (0 = any yaw)."""
        if self.shape == "box":
            return np.pi / 2 if np.isclose(self.dims[0], self.dims[1]) else np.pi
        return 0.0 if self.shape == "cylinder" else np.pi / 3

    def vertices(self) -> np.ndarray:
        """Convex-hull vertices ``(k, 3)`` in the object frame (centre, z = axis) [m]."""
        if self.shape == "box":
            return box_vertices(self.dims)
        r, h = (self.dims[0], self.dims[1])
        n = _CYLINDER_SIDES if self.shape == "cylinder" else 6
        # Hexagon (edge = circumradius): flats face ±x, so the jaws (opening along x) grip
        # across flats, 69 mm for a 40 mm edge.
        a = np.arange(n) * 2 * np.pi / n + (np.pi / 6 if self.shape == "hex_prism" else 0.0)
        ring = np.stack([r * np.cos(a), r * np.sin(a)], axis=-1)
        return np.concatenate([np.c_[ring, np.full(n, -h / 2)], np.c_[ring, np.full(n, h / 2)]])


@dataclasses.dataclass(frozen=True)
class Base:
    """A destination base plate: full ``size`` [m] on ``table`` at (u, v), yaw; ``fits`` object nodes."""

    node: int
    name: str
    size: tuple[float, float, float]
    table: str
    at: tuple[float, float]
    yaw: float
    fits: tuple[int, ...]


_FLAT = 1e-9  # [m] points spread less than this across a plane are flat: no convex solid
_QUAT_TOL = 1e-6  # |q| − 1 allowed in a given quaternion: files carry 6–17 significant digits
_OBSTACLE_DIMS = {"box": ("size",), "cylinder": ("radius", "height"), "sphere": ("radius",),
                  "capsule": ("radius", "length"), "mesh": ()}


@dataclasses.dataclass(frozen=True)
class Obstacle:
    """A static obstacle of the scenario's ``obstacles`` list (world frame, m, rad).

    Attributes:
      name: label (unique in the scene; a :class:`Context` can ignore it by this name).
      shape: ``box`` (``size``: full edges x, y, z), ``cylinder`` (``radius``, ``height``; axis
        z), ``sphere`` (``radius``), ``capsule`` (``radius``, ``length`` of its axis segment,
        along z) or ``mesh`` (``file``: an STL or OBJ file that MuJoCo reads, path absolute or
        relative to the working directory, times ``scale``; or ``vertices``; MuJoCo collides
        with its convex hull).
      pos, rpy: pose of its centre (the mesh file's origin).
      dims: the numbers of ``shape`` above, in that order.
      quat: its orientation as a unit quaternion ``(w, x, y, z)`` instead of ``rpy`` (None: rpy).
      vertices: a mesh given by its points instead of a file: flat ``(3k,)`` [m] in its frame
        (``scale`` not applied), k >= 4 not all in one plane.
    """

    name: str
    shape: str
    pos: tuple[float, float, float]
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    dims: tuple[float, ...] = ()
    file: str = ""
    scale: float = 1.0
    quat: tuple[float, float, float, float] | None = None
    vertices: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if self.quat is not None and (len(self.quat) != 4 or not np.all(np.isfinite(self.quat))
                                      or abs(np.linalg.norm(self.quat) - 1.0) > _QUAT_TOL):
            raise ValueError(f"obstacle {self.name!r}: quat must be a unit quaternion (w, x, y, z), got {self.quat}")
        if self.quat is not None and any(self.rpy):
            raise ValueError(f"obstacle {self.name!r}: give its orientation as rpy or as quat, not both")
        if self.shape not in _OBSTACLE_DIMS:
            raise ValueError(f"obstacle {self.name!r}: unknown shape {self.shape!r} ({', '.join(_OBSTACLE_DIMS)})")
        n = 3 if self.shape == "box" else len(_OBSTACLE_DIMS[self.shape])
        if len(self.dims) != n or (n and min(self.dims) <= 0):
            raise ValueError(f"obstacle {self.name!r}: a {self.shape} needs {n} positive numbers "
                             f"({', '.join(_OBSTACLE_DIMS[self.shape]) or 'none'}), got {list(self.dims)}")
        if self.vertices and (self.shape != "mesh" or self.file):
            raise ValueError(f"obstacle {self.name!r}: vertices are for a mesh without a file")
        if self.vertices:
            v = np.asarray(self.vertices, dtype=float)
            if v.size % 3 or v.size < 12 or not np.all(np.isfinite(v)) or np.linalg.matrix_rank(
                    v.reshape(-1, 3) - v.reshape(-1, 3).mean(0), tol=_FLAT) < 3:
                raise ValueError(f"obstacle {self.name!r}: vertices must be k >= 4 finite points (x, y, z) "
                                 f"not all in one plane, got {v.size} numbers")
        elif self.shape == "mesh":
            if not self.scale > 0:
                raise ValueError(f"obstacle {self.name!r}: scale must be > 0, got {self.scale}")
            if not Path(self.file).is_file():
                raise ValueError(f"obstacle {self.name!r}: cannot read mesh file {self.file!r} (no such file)")

    @staticmethod
    def from_keys(keys) -> "Obstacle":
        """From an obstacle's checked scenario keys (:class:`uvms_jax.plan._schema.ObstacleKeys`)."""
        dims = [float(x) for k in _OBSTACLE_DIMS[keys.shape] for x in (keys.size if k == "size" else [getattr(keys, k)])]
        return Obstacle(keys.name, keys.shape, keys.pos, keys.rpy, tuple(dims), keys.file or "",
                        1.0 if keys.scale is None else keys.scale, keys.quat)

    @property
    def T_world(self) -> np.ndarray:
        R = frames.rpy_matrix(self.rpy) if self.quat is None else frames.quat_matrix(self.quat)
        return frames.pose(R, self.pos)

    def hull_vertices(self) -> np.ndarray:
        """``(k, 3)`` vertices of the convex mesh standing for a box or a cylinder, or of a mesh
        given by its vertices, in its frame [m]. A cylinder is the prism *around* it
        (circumscribed polygon): never smaller."""
        if self.vertices:
            return np.asarray(self.vertices, dtype=float).reshape(-1, 3)
        if self.shape == "box":
            return box_vertices(self.dims)
        if self.shape == "cylinder":
            r, h = self.dims
            a = np.arange(_CYLINDER_SIDES) * 2 * np.pi / _CYLINDER_SIDES
            ring = np.stack([np.cos(a), np.sin(a)], -1) * r / np.cos(np.pi / _CYLINDER_SIDES)
            return np.concatenate([np.c_[ring, np.full(len(a), -h / 2)], np.c_[ring, np.full(len(a), h / 2)]])
        raise ValueError(f"obstacle {self.name!r}: a {self.shape} has no vertices here (MuJoCo primitive or file)")


@dataclasses.dataclass(frozen=True)
class SceneSpec:
    """Everything that defines the scene (``configs/scenario/*.yaml``); see that file for units.
    ``cage_size`` None: no cage and no ceiling (open water, e.g. the arm under a vehicle).
    ``start_q`` None: the start configuration is computed (:func:`uvms_jax.plan.start_configuration`).
    The arm itself is not part of the spec: :func:`build_scene` receives it."""

    cage_size: tuple[float, float, float] | None
    profile: float
    ceiling_thickness: float
    mount_pos: tuple[float, float, float]
    mount_rpy: tuple[float, float, float]
    mount_size: tuple[float, float, float]
    jaws_open: float
    tables: tuple[Box, ...]
    objects: tuple[Item, ...]
    bases: tuple[Base, ...]
    object_density: float
    water_density: float
    gravity: float
    start_q: tuple[float, ...] | None
    grasp_standoff: float = 0.05
    approach: float = 0.08
    obstacles: tuple[Obstacle, ...] = ()

    @property
    def T_world_base(self) -> np.ndarray:
        """``(4, 4)`` pose of the arm's base link in the world (``mount_pos``, ``mount_rpy``)."""
        return frames.pose(frames.rpy_matrix(self.mount_rpy), self.mount_pos)

    def with_base(self, T_world_base) -> "SceneSpec":
        """The same scene with the arm's base link at ``T_world_base (4, 4)`` (world frame, m).

        The mount plate, the IK targets, the planned motions, the metrics (torques in the base
        frame) and the video all follow the base, e.g. a docking stage placing the arm under a
        vehicle. ``start_q`` stays as given (joint angles, so the start pose moves with the arm).

        Raises:
          ValueError: ``T_world_base`` is not a rigid transform.
        """
        T = np.asarray(T_world_base, dtype=float)
        if T.shape != (4, 4) or not np.all(np.isfinite(T)):
            raise ValueError(f"T_world_base must be a finite (4, 4) pose, got shape {T.shape}")
        R = T[:3, :3]
        if not (np.allclose(R.T @ R, np.eye(3), atol=1e-9) and np.isclose(np.linalg.det(R), 1.0, atol=1e-9)
                and np.allclose(T[3], (0, 0, 0, 1))):
            raise ValueError(f"T_world_base must be a rigid transform (rotation block orthonormal, det +1, last row "
                             f"0 0 0 1), got\n{np.round(T, 6)}")
        rpy = frames.matrix_rpy(R)
        return dataclasses.replace(self, mount_pos=tuple(float(v) for v in T[:3, 3]),
                                   mount_rpy=tuple(float(v) for v in rpy))

    @staticmethod
    def from_mapping(m: Mapping[str, Any], where: str = "scenario") -> "SceneSpec":
        """Build from the scenario mapping (a plain dict, e.g. ``OmegaConf.to_container(cfg)``),
        checked against the scenario schema first (:func:`uvms_jax.plan.check_scenario`).

        Raises:
          SettingsError: every bad key, named by its key path under ``where``, in one message.
        """
        keys = check_scenario(m, where)
        nodes = node_numbers(keys)
        objects = {o.name: nodes[o.name] for o in keys.objects}
        arm, cage = keys.arm, keys.cage
        spec = SceneSpec(
            cage_size=None if cage is None else cage.size,
            profile=0.0 if cage is None else cage.profile,
            ceiling_thickness=0.0 if cage is None else cage.ceiling_thickness,
            mount_pos=_floats(arm["mount_pos"]), mount_rpy=_floats(arm["mount_rpy"]),
            mount_size=_floats(arm["mount_size"]), jaws_open=float(arm["jaws_open"]),
            tables=tuple(Box(b.name, b.pos, b.size, b.rpy) for b in keys.tables),
            objects=tuple(Item(nodes[o.name], o.name, o.shape, _object_dims(o), o.table, o.at, o.yaw)
                          for o in keys.objects),
            bases=tuple(Base(nodes[b.name], b.name, b.size, b.table, b.at, b.yaw,
                             tuple(objects[f] if isinstance(f, str) else f for f in b.fits)) for b in keys.bases),
            object_density=keys.object_density, water_density=keys.water_density, gravity=keys.gravity,
            start_q=keys.start_q, grasp_standoff=keys.grasp.standoff, approach=keys.grasp.approach,
            obstacles=tuple(Obstacle.from_keys(o) for o in keys.obstacles),
        )
        try:
            spec.validate()
        except ValueError as e:
            raise SettingsError(f"{where}: {e}") from None
        return spec

    def validate(self) -> None:
        """Raise ValueError naming the problem for an inconsistent spec."""
        tables = {b.name for b in self.tables}
        names = [b.name for b in self.tables] + [o.name for o in self.obstacles]
        reserved = {"ceiling", "mount", "cage"}
        clash = sorted({n for n in names if names.count(n) > 1 or n in reserved or ":" in n
                        or (n[:1] == "n" and n[1:].isdigit())})
        if clash:
            raise ValueError(f"table/obstacle names must be unique, without ':', not {sorted(reserved)} and not "
                             f"'n<digits>' (node labels); got {clash}")
        nodes = [o.node for o in self.objects] + [b.node for b in self.bases]
        if len(set(nodes)) != len(nodes) or 0 in nodes:
            raise ValueError(f"object/base node numbers must be unique and not 0, got {nodes}")
        for x in (*self.objects, *self.bases):
            if x.table not in tables:
                raise ValueError(f"{x.name!r} stands on unknown table {x.table!r} (tables: {sorted(tables)})")
        objs = {o.node for o in self.objects}
        for b in self.bases:
            if not b.fits or not set(b.fits) <= objs:
                raise ValueError(f"base {b.name!r} fits unknown objects {b.fits} (objects: {sorted(objs)})")
        if self.start_q is not None and not np.all(np.isfinite(self.start_q)):
            raise ValueError(f"start_q must be finite joint values, got {self.start_q}")


def _floats(values) -> tuple[float, ...]:
    return tuple(float(v) for v in values)


def _object_dims(o) -> tuple[float, ...]:
    """An object's dims (:class:`Item`) from its schema keys."""
    return {"box": lambda: o.size, "cylinder": lambda: (o.radius, o.height),
            "hex_prism": lambda: (o.edge, o.height)}[o.shape]()


def box_vertices(size) -> np.ndarray:
    h = np.asarray(size, dtype=float) / 2.0
    return np.array([[sx * h[0], sy * h[1], sz * h[2]] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])


def scenario_robot(scenario: Mapping[str, Any], where: str = "scenario") -> robots.Robot:
    """The arm a scenario names: its ``arm`` mapping less the mount keys (:data:`MOUNT_KEYS`),
    e.g. ``{card: NAME}`` (a shipped arm) or ``{description: my_arm.urdf, tip: tool0, link_radius: 0.05}``;
    the scenario's ``start_q``, if any, is checked against it (:func:`check_start_q`).

    Raises:
      SettingsError: no ``arm`` mapping, an arm that does not load (the loader's reason), or a
        ``start_q`` that does not fit it; named by the key path under ``where``.
    """
    arm = scenario.get("arm")
    if not isinstance(arm, Mapping):
        raise SettingsError(f"{where}.arm: expected a mapping: the arm (card or description) and its mount")
    try:
        robot = robots.robot_from_config({k: v for k, v in arm.items() if k not in MOUNT_KEYS}, f"{where}.arm")
    except ValueError as e:
        message = " ".join(str(e).split())
        raise SettingsError(message if message.startswith(f"{where}.arm") else f"{where}.arm: {message}") from None
    check_start_q(robot, scenario.get("start_q"), f"{where}.start_q")
    return robot


def check_start_q(robot: robots.Robot, start_q: Any, where: str = "scenario.start_q") -> None:
    """Raise :class:`SettingsError` unless ``start_q`` is None or one finite angle per joint of
    ``robot`` [rad], each within its joint's limits; ``where`` is its key path."""
    if start_q is None:
        return
    q = np.asarray(start_q, dtype=float)
    if q.shape != (robot.n_joints,):
        raise SettingsError(f"{where}: expected {robot.n_joints} joint angles {list(robot.joint_names)} [rad], "
                            f"got {list(start_q)}")
    lo, hi = np.asarray(robot.lower, float), np.asarray(robot.upper, float)
    bad = [f"{where}[{i}] ({robot.joint_names[i]}): {q[i]:g} is outside [{lo[i]:g}, {hi[i]:g}]"
           for i in range(len(q)) if not lo[i] <= q[i] <= hi[i]]
    if bad:
        raise SettingsError("; ".join(bad) + " rad (the arm's joint limits)")
