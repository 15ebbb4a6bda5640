"""The thesis's test cage as a MuJoCo model, generated from a scenario config (thesis 5.1),
with any extra obstacles of the config (:class:`Obstacle`: box, cylinder, sphere, capsule,
mesh file) and the arm's base at a pose given by the config or by code
(:meth:`SceneSpec.with_base`, ``build_scene(..., T_world_base=...)``).

World frame: origin at the centre of the cage floor, z up; metres and radians. The arm hangs
from the top of the cage (its base frame's z points down). Every box of the scene — tables,
cage profiles, ceiling, base plates, cubes, and the arm's jaw fingers — is a convex *mesh*
of 8 vertices, because MuJoCo's primitive capsule–box test misses a capsule whose axis runs
right through a thin box (it reports a positive distance and no contact); cylinders and hexagonal prisms are convex meshes too.

Collision groups (``contype``/``conaffinity`` bits): scene geoms ``2/2``, moving arm geoms
``1/15``, the fixed base link ``4/0`` (it is bolted to the mount, so it never meets the scene,
only the moving links), the mount plate ``8/0``. Links always in contact with the base link
(computed, see below) get ``1/11`` and meet it not; the first link, which turns about its axis
at the base, gets ``1/3`` and meets neither the base link nor the mount. (The base link is welded
to the world, so an ``<exclude>`` naming it would switch off the world's geoms too; hence bits.)
All world geoms share one body, so MuJoCo never tests them against each other; parent–child
link pairs are filtered by MuJoCo, and the other pairs that are in contact in every sampled
configuration (:func:`uvms_jax.robot.self_collision_pairs`, as MoveIt's setup assistant finds
them) by ``<exclude>``. The in-hand copies of the objects (``held_<name>``, fixed to the last
link at the grasp) are off until a :class:`Context` turns one on.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax import robot as robots

__all__ = [
    "Base",
    "Box",
    "Context",
    "Item",
    "Obstacle",
    "Scene",
    "SceneSpec",
    "MOUNT_KEYS",
    "build_scene",
    "scenario_robot",
]

SCENE_BITS = (2, 2)  # contype, conaffinity of static geoms
MOUNT_BITS = (8, 0)  # the mount plate: against the moving links but the first
ARM_BITS = (1, 15)  # moving arm geoms: collide with the arm, the scene, the base link and the mount
SHOULDER_BITS = (1, 11)  # links always in contact with the base link: not against it
FIRST_BITS = (1, 3)  # the first link: it turns about its axis at the base, touching neither base nor mount
BASE_BITS = (4, 0)  # fixed base link: only against the other moving links, jaws and held object
OFF_BITS = (0, 0)
# Self-collision pairs nearer than this in every sampled configuration are skipped: at least the
# planner's safety margin (PlanSettings.margin, 0.005 m), so that no pair reads as a collision in
# every pose.
SELF_COLLISION_MARGIN = 0.01  # [m]
_CYLINDER_SIDES = 32  # inscribed polygon: radius error r(1 - cos(π/32)) ≈ 0.2 mm for r = 40 mm


def _fmt(v) -> str:
    return " ".join(f"{float(x):.10g}" for x in np.ravel(v))


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
            return _box_vertices(self.dims)
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
        relative to the working directory, times ``scale``; MuJoCo collides with its convex
        hull).
      pos, rpy: pose of its centre (the mesh file's origin).
      dims: the numbers of ``shape`` above, in that order.
    """

    name: str
    shape: str
    pos: tuple[float, float, float]
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    dims: tuple[float, ...] = ()
    file: str = ""
    scale: float = 1.0

    def __post_init__(self) -> None:
        if self.shape not in _OBSTACLE_DIMS:
            raise ValueError(f"obstacle {self.name!r}: unknown shape {self.shape!r} ({', '.join(_OBSTACLE_DIMS)})")
        n = 3 if self.shape == "box" else len(_OBSTACLE_DIMS[self.shape])
        if len(self.dims) != n or (n and min(self.dims) <= 0):
            raise ValueError(f"obstacle {self.name!r}: a {self.shape} needs {n} positive numbers "
                             f"({', '.join(_OBSTACLE_DIMS[self.shape]) or 'none'}), got {list(self.dims)}")
        if self.shape == "mesh":
            if not self.scale > 0:
                raise ValueError(f"obstacle {self.name!r}: scale must be > 0, got {self.scale}")
            if not Path(self.file).is_file():
                raise ValueError(f"obstacle {self.name!r}: cannot read mesh file {self.file!r} (no such file)")

    @staticmethod
    def from_mapping(m: Mapping[str, Any]) -> "Obstacle":
        shape = str(m.get("shape"))
        if shape not in _OBSTACLE_DIMS:
            raise ValueError(f"obstacle {m.get('name')!r}: unknown shape {shape!r} ({', '.join(_OBSTACLE_DIMS)})")
        known = {"name", "shape", "pos", "rpy", "file", "scale", *_OBSTACLE_DIMS[shape]}
        extra = sorted(set(m) - known)
        if extra:
            raise ValueError(f"obstacle {m.get('name')!r}: unknown keys {extra} for a {shape} (keys: {sorted(known)})")
        dims: list[float] = []
        for key in _OBSTACLE_DIMS[shape]:
            if key not in m:
                raise ValueError(f"obstacle {m.get('name')!r}: a {shape} needs {key!r}")
            v = m[key]
            dims += [float(x) for x in v] if isinstance(v, (list, tuple)) else [float(v)]
        return Obstacle(str(m["name"]), shape, tuple(float(x) for x in m["pos"]),
                        tuple(float(x) for x in m.get("rpy", (0.0, 0.0, 0.0))), tuple(dims),
                        str(m.get("file", "")), float(m.get("scale", 1.0)))

    @property
    def T_world(self) -> np.ndarray:
        return frames.pose(frames.rpy_matrix(self.rpy), self.pos)

    def hull_vertices(self) -> np.ndarray:
        """``(k, 3)`` vertices of the convex mesh standing for a box or a cylinder, in its frame
        [m]. A cylinder is the prism *around* it (circumscribed polygon): never smaller."""
        if self.shape == "box":
            return _box_vertices(self.dims)
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
    def from_mapping(m: Mapping[str, Any]) -> "SceneSpec":
        """Build from the scenario mapping (a plain dict, e.g. ``OmegaConf.to_container(cfg)``)."""
        t = lambda x: tuple(float(v) for v in x)  # noqa: E731
        objects = []
        # Nodes: the given numbers, or by default the objects 1 … k and the bases k + 1 … in the
        # file's order (the task graph's start is 0, its goal one past the last base).
        auto = {str(x["name"]): i + 1 for i, x in enumerate([*m["objects"], *m["bases"]])}
        node_of = lambda x: int(x["node"]) if x.get("node") is not None else auto[str(x["name"])]  # noqa: E731
        names = {str(o["name"]): node_of(o) for o in m["objects"]}

        def fits(b) -> tuple[int, ...]:  # objects by name or node number
            unknown = [f for f in b["fits"] if isinstance(f, str) and f not in names]
            if unknown:
                raise ValueError(f"base {b.get('name')!r} fits unknown objects {unknown} (objects: {sorted(names)})")
            return tuple(names[f] if isinstance(f, str) else int(f) for f in b["fits"])

        for o in m["objects"]:
            dims = {"box": lambda: o["size"], "cylinder": lambda: (o["radius"], o["height"]),
                    "hex_prism": lambda: (o["edge"], o["height"])}
            if o["shape"] not in dims:
                raise ValueError(f"object {o.get('name')!r}: unknown shape {o['shape']!r}")
            objects.append(Item(node_of(o), str(o["name"]), str(o["shape"]), t(dims[o["shape"]]()),
                                str(o["table"]), t(o["at"]), float(o.get("yaw", 0.0))))
        grasp = m.get("grasp", {})
        cage = m.get("cage")
        spec = SceneSpec(
            cage_size=None if cage is None else t(cage["size"]),
            profile=0.0 if cage is None else float(cage["profile"]),
            ceiling_thickness=0.0 if cage is None else float(cage["ceiling_thickness"]),
            mount_pos=t(m["arm"]["mount_pos"]),
            mount_rpy=t(m["arm"]["mount_rpy"]),
            mount_size=t(m["arm"]["mount_size"]),
            jaws_open=float(m["arm"]["jaws_open"]),
            tables=tuple(Box(str(b["name"]), t(b["pos"]), t(b["size"]), t(b.get("rpy", (0, 0, 0)))) for b in m["tables"]),
            objects=tuple(objects),
            bases=tuple(Base(node_of(b), str(b["name"]), t(b["size"]), str(b["table"]), t(b["at"]),
                             float(b.get("yaw", 0.0)), fits(b)) for b in m["bases"]),
            object_density=float(m["object_density"]),
            water_density=float(m["water_density"]),
            gravity=float(m["gravity"]),
            start_q=None if m.get("start_q") is None else t(m["start_q"]),
            grasp_standoff=float(grasp.get("standoff", 0.05)),
            approach=float(grasp.get("approach", 0.08)),
            obstacles=tuple(Obstacle.from_mapping(o) for o in m.get("obstacles", ()) or ()),
        )
        spec.validate()
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


@dataclasses.dataclass(frozen=True)
class Context:
    """What the collision checker considers at a moment of the task.

    Attributes:
      held: node of the object in the jaws (its in-hand copy is on, its table copy off), or None.
      ignore: nodes of objects/bases (and names of tables) whose geoms are switched off, e.g.
        the object being grasped during the approach, or the base and table under the object
        being placed.
    """

    held: int | None = None
    ignore: tuple[int | str, ...] = ()


def _box_vertices(size) -> np.ndarray:
    h = np.asarray(size, dtype=float) / 2.0
    return np.array([[sx * h[0], sy * h[1], sz * h[2]] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])


class Scene:
    """A built scene: the robot in the world, its MuJoCo model, geom groups and the poses of
    objects and bases.

    Attributes:
      spec: the :class:`SceneSpec`.
      robot: the arm (:class:`uvms_jax.robot.Robot`).
      xml: the MJCF text.
      model: ``mujoco.MjModel`` (its contype/conaffinity are switched by the collision checker).
      T_world_base: ``(4, 4)`` pose of the arm's base link in the world.
      self_collision: the arm's skipped self-collision pairs
        (:func:`uvms_jax.robot.self_collision_pairs`: ``adjacent`` and ``always``).
      base_geoms: geom ids of the fixed base link.
      arm_geoms: geom ids of the moving arm (its links and fingers).
      shoulder_geoms: arm geoms of the links always in contact with the base link.
      first_geoms: arm geoms of the first link (it meets neither the base link nor the mount).
      mount_geoms: the mount plate's geoms.
      clearance_geoms: arm geoms whose distance to the scene counts as clearance (all but the
        first link's: it turns about its joint's axis under the mount, so its distance to the
        mount never changes).
      held_geoms: object node → geom id of its in-hand copy.
      obstacle_geoms: label (object/base node or table name, "cage", "ceiling", "mount")
        → geom ids.
      T_obj_tool: ``(4, 4)`` grasp: the tool in the object frame.
    """

    def __init__(self, spec: SceneSpec, robot: robots.Robot, self_collision_samples: int = 200):
        spec.validate()
        if spec.start_q is not None and len(spec.start_q) != robot.n_joints:
            raise ValueError(f"start_q has {len(spec.start_q)} values, the arm {robot.name!r} has {robot.n_joints} "
                             f"joints ({', '.join(robot.joint_names)})")
        self.spec = spec
        self.robot = robot
        self.tables = {b.name: b for b in spec.tables}
        self.objects = {o.node: o for o in spec.objects}
        self.bases = {b.node: b for b in spec.bases}
        self.T_world_base = spec.T_world_base
        self.T_base_world = np.linalg.inv(self.T_world_base)
        self.self_collision = robots.self_collision_pairs(robot, self_collision_samples, jaws_open=spec.jaws_open,
                                                          margin=SELF_COLLISION_MARGIN)
        self.xml, self.finger_length = self._build_xml()
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        m = self.model
        bid = lambda n: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, n)  # noqa: E731
        link_ids = [bid(n) for n in robot.link_names]
        base_id = bid(robots.base_body(robot))
        self.held_geoms = {o.node: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"held_{o.name}")
                           for o in spec.objects}
        held = set(self.held_geoms.values())
        self.base_geoms = tuple(g for g in range(m.ngeom) if m.geom_bodyid[g] == base_id)
        self.arm_geoms = tuple(g for g in range(m.ngeom) if m.geom_bodyid[g] in link_ids and g not in held)
        shoulder = {bid(b) for a, b in self._base_pairs()}
        self.shoulder_geoms = tuple(g for g in self.arm_geoms if m.geom_bodyid[g] in shoulder)
        self.first_geoms = tuple(g for g in self.arm_geoms if m.geom_bodyid[g] == link_ids[0])
        self.mount_geoms = tuple(g for g in range(m.ngeom) if m.geom(g).name == "mount")
        self.clearance_geoms = tuple(g for g in self.arm_geoms if m.geom_bodyid[g] != link_ids[0])
        self.obstacle_geoms: dict[int | str, tuple[int, ...]] = {}
        for g in range(m.ngeom):
            if m.geom_bodyid[g] != 0:
                continue
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)
            label = name.split(":", 1)[0]
            key: int | str = int(label[1:]) if label[0] == "n" and label[1:].isdigit() else label
            self.obstacle_geoms[key] = self.obstacle_geoms.get(key, ()) + (g,)
        self.T_obj_tool = np.linalg.inv(self.T_tool_obj_for(None))
        self.default_bits = (m.geom_contype.copy(), m.geom_conaffinity.copy())
        self.start_q = np.asarray(spec.start_q if spec.start_q is not None else self._start_configuration(), float)

    def _start_configuration(self, clearance: float = SELF_COLLISION_MARGIN, per_ring: int = 64,
                             seed: int = 0) -> np.ndarray:
        """A collision-free configuration near the arm's home (the middle of its joint range):
        the home itself if it is ``clearance`` [m] clear of everything, else the first clear
        one of random configurations in rings of growing size about it (tenths of the range).

        Raises:
          ValueError: none of them is clear (then give the scenario a ``start_q``).
        """
        robot = self.robot
        model = mujoco.MjModel.from_xml_string(self.xml)
        model.geom_margin[:] = clearance / 2  # a pair's margins add up
        data = mujoco.MjData(model)
        lower, upper = robot.lower, robot.upper
        home = (lower + upper) / 2
        rng = np.random.default_rng(seed)
        rings = [home[None]] + [np.clip(home + rng.uniform(-0.5, 0.5, (per_ring, robot.n_joints)) * f * (upper - lower),
                                        lower, upper) for f in np.linspace(0.1, 1.0, 10)]
        for q in np.concatenate(rings):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_collision(model, data)
            if data.ncon == 0:
                return q
        raise ValueError(f"no configuration of {robot.name!r} within its limits is {clearance} m clear of the scene "
                         f"near its home {np.round(home, 3).tolist()}: give the scenario a start_q")

    def _base_pairs(self) -> list[tuple[str, str]]:
        """Skipped self-collision pairs of the base link (it is welded to the world, so MuJoCo's
        parent–child filter does not see its child: bits keep these apart)."""
        base = robots.base_body(self.robot)
        return [p for p in self.self_collision["adjacent"] + self.self_collision["always"] if p[0] == base]

    # -- poses ---------------------------------------------------------------------------
    def T_world_object(self, node: int) -> np.ndarray:
        """Pose of an object's centre at its start position ``(4, 4)`` (z = the shape's axis)."""
        o = self.objects[node]
        return self.tables[o.table].T_world_top @ frames.pose(frames.rot_z(o.yaw), (*o.at, 0.0)) @ frames.pose(p=(0, 0, o.height / 2))

    def T_world_base_top(self, node: int) -> np.ndarray:
        """Frame on the centre of a base plate's top face ``(4, 4)``."""
        b = self.bases[node]
        return self.tables[b.table].T_world_top @ frames.pose(frames.rot_z(b.yaw), (*b.at, b.size[2]))

    def T_world_placed(self, base: int, obj: int) -> np.ndarray:
        """Pose of object ``obj``'s centre when placed on base ``base``."""
        return self.T_world_base_top(base) @ frames.pose(p=(0, 0, self.objects[obj].height / 2))

    def T_tool_obj_for(self, node: int | None) -> np.ndarray:
        """The grasp: the object frame in the tool frame (object ``node``; None → standoff only).

        Top grasp: the approach (tool z) runs down the object's axis, the jaws open along the
        object's x axis, the tool sits ``grasp_standoff`` above the object's top face.
        """
        h = 0.0 if node is None else self.objects[node].height
        return frames.pose(np.diag([1.0, -1.0, -1.0]), (0.0, 0.0, self.spec.grasp_standoff + h / 2))

    def mass(self, node: int) -> float:
        return self.spec.object_density * self.objects[node].volume

    def payload_force_world(self, node: int) -> np.ndarray:
        """``(3,)`` net force of the held object on the jaws, world frame [N]: ``[0, 0, F_b − F_g]``
        (thesis eq. 4.12–4.14)."""
        o, s = self.objects[node], self.spec
        return np.array([0.0, 0.0, s.water_density * s.gravity * o.volume - self.mass(node) * s.gravity])

    # -- MJCF ----------------------------------------------------------------------------
    def _build_xml(self) -> tuple[str, float]:
        s = self.spec
        assets: list[str] = []

        def mesh(name: str, verts: np.ndarray) -> str:
            assets.append(f'<mesh name="{name}" vertex="{_fmt(verts)}"/>')
            return name

        world: list[str] = []

        def box(label: str, T: np.ndarray, size, rgba: str, bits=SCENE_BITS) -> None:
            mname = mesh(f"m_{label}", _box_vertices(size))
            world.append(
                f'<geom name="{label}" type="mesh" mesh="{mname}" pos="{_fmt(T[:3, 3])}" '
                f'quat="{_fmt(frames.matrix_quat(T[:3, :3]))}" rgba="{rgba}" contype="{bits[0]}" conaffinity="{bits[1]}"/>'
            )

        if s.cage_size is not None:
            L, W, H = s.cage_size
            # The ceiling and the table under everything are half-spaces (MuJoCo planes): exact,
            # cheap against every shape, and they also forbid slipping past their edges.
            world.append(
                f'<geom name="ceiling" type="plane" pos="0 0 {H}" quat="0 1 0 0" size="{L / 2} {W / 2} 0.05" '
                f'rgba="0.7 0.7 0.7 0.2" contype="{SCENE_BITS[0]}" conaffinity="{SCENE_BITS[1]}"/>'
            )
        under = s.tables[0]
        top = under.T_world_top
        world.append(
            f'<geom name="{under.name}" type="plane" pos="{_fmt(top[:3, 3])}" quat="{_fmt(frames.matrix_quat(top[:3, :3]))}" '
            f'size="{under.size[0] / 2} {under.size[1] / 2} 0.05" rgba="0.6 0.55 0.5 1" '
            f'contype="{SCENE_BITS[0]}" conaffinity="{SCENE_BITS[1]}"/>'
        )
        if s.cage_size is not None:
            p = s.profile
            k = 0
            for sx in (-1, 1):
                for sy in (-1, 1):
                    box(f"cage:post{k}", frames.pose(p=(sx * (L - p) / 2, sy * (W - p) / 2, H / 2)), (p, p, H), "0.6 0.6 0.65 1")
                    k += 1
            for z in (p / 2, H - p / 2):
                for sx in (-1, 1):
                    box(f"cage:x{k}", frames.pose(p=(sx * (L - p) / 2, 0, z)), (p, W - 2 * p, p), "0.6 0.6 0.65 1")
                    box(f"cage:y{k}", frames.pose(p=(0, sx * (W - p) / 2, z)), (L - 2 * p, p, p), "0.6 0.6 0.65 1")
                    k += 1
        ms = s.mount_size
        mount_T = self.T_world_base @ frames.pose(p=(0, 0, -ms[2] / 2))
        box("mount", mount_T, ms, "0.3 0.3 0.3 1", MOUNT_BITS)
        for t in s.tables[1:]:
            box(t.name, t.T_world_box, t.size, "0.75 0.8 0.9 0.6")
        bits = f'contype="{SCENE_BITS[0]}" conaffinity="{SCENE_BITS[1]}" rgba="0.55 0.6 0.7 0.8"'
        for o in s.obstacles:
            T = o.T_world
            pose = f'pos="{_fmt(T[:3, 3])}" quat="{_fmt(frames.matrix_quat(T[:3, :3]))}"'
            if o.shape == "sphere":
                world.append(f'<geom name="{o.name}" type="sphere" size="{o.dims[0]!r}" {pose} {bits}/>')
            elif o.shape == "capsule":  # primitive: arm capsule vs capsule is exact in MuJoCo
                world.append(f'<geom name="{o.name}" type="capsule" size="{o.dims[0]!r} {o.dims[1] / 2!r}" {pose} {bits}/>')
            elif o.shape == "mesh":  # MuJoCo reads the file and collides with its convex hull
                mname = f"m_obstacle_{o.name}"
                assets.append(f'<mesh name="{mname}" file="{Path(o.file).resolve()}" scale="{_fmt([o.scale] * 3)}"/>')
                world.append(f'<geom name="{o.name}" type="mesh" mesh="{mname}" {pose} {bits}/>')
            else:  # boxes and cylinders as convex meshes (see the module docstring)
                mname = mesh(f"m_obstacle_{o.name}", o.hull_vertices())
                world.append(f'<geom name="{o.name}" type="mesh" mesh="{mname}" {pose} {bits}/>')
        for b in s.bases:
            T = self.T_world_base_top(b.node) @ frames.pose(p=(0, 0, -b.size[2] / 2))
            box(f"n{b.node}:{b.name}", T, b.size, "0.9 0.3 0.2 1")
        for o in s.objects:
            T = self.T_world_object(o.node)
            mname = mesh(f"m_{o.name}", o.vertices())
            world.append(
                f'<geom name="n{o.node}:{o.name}" type="mesh" mesh="{mname}" pos="{_fmt(T[:3, 3])}" '
                f'quat="{_fmt(frames.matrix_quat(T[:3, :3]))}" rgba="1 0.55 0.1 1" contype="{SCENE_BITS[0]}" conaffinity="{SCENE_BITS[1]}"/>'
            )

        robot = self.robot
        arm = ET.fromstring(robots.mjcf_body(robot, s.mount_pos, frames.matrix_quat(self.T_world_base[:3, :3]), s.jaws_open))
        assets += robots.mjcf_assets(robot)  # the description's meshes, boxes and cylinders of the arm
        last = arm.find(".//site[@name='tool']/..")
        tool_site = last.find("site[@name='tool']")
        T_link_tool = frames.pose(frames.quat_matrix(tool_site.get("quat")), [float(v) for v in tool_site.get("pos").split()])
        base = robots.base_body(robot)
        shoulder = {b for _, b in self._base_pairs()}
        finger_length = 0.0
        for body in arm.iter("body"):
            name = body.get("name")
            for g in body.findall("geom"):
                bits = (BASE_BITS if name == base else FIRST_BITS if name == robot.link_names[0]
                        else SHOULDER_BITS if name in shoulder else ARM_BITS)
                g.set("contype", str(bits[0]))
                g.set("conaffinity", str(bits[1]))
                if g.get("type") == "box":  # jaw fingers → convex meshes (see the module docstring)
                    size = np.array([float(v) for v in g.get("size").split()]) * 2
                    pos = np.array([float(v) for v in g.get("pos").split()])
                    tip = np.linalg.inv(T_link_tool) @ np.r_[pos, 1.0]
                    finger_length = max(finger_length, tip[2] + size[2] / 2)
                    g.set("type", "mesh")
                    g.set("mesh", mesh(f"m_{g.get('name')}", _box_vertices(size)))
                    del g.attrib["size"]
        # In-hand copies of the objects, fixed to the last link at the grasp (off by default).
        for o in s.objects:
            T = T_link_tool @ self.T_tool_obj_for(o.node)
            mname = f"m_{o.name}"
            ET.SubElement(last, "geom", {
                "name": f"held_{o.name}", "type": "mesh", "mesh": mname, "pos": _fmt(T[:3, 3]),
                "quat": _fmt(frames.matrix_quat(T[:3, :3])), "rgba": "1 0.55 0.1 0.8", "contype": "0", "conaffinity": "0",
            })
        excludes = "".join(f'<exclude body1="{a}" body2="{b}"/>' for a, b in self.self_collision["always"]
                           if base not in (a, b))
        xml = (
            '<mujoco model="thesis_cage">\n  <compiler angle="radian"/>\n  <option gravity="0 0 0"/>\n'
            '  <visual><global offwidth="960" offheight="720"/></visual>\n'
            f"  <asset>\n    {chr(10).join(assets)}\n  </asset>\n"
            f"  <worldbody>\n    <light pos=\"0 0 3\" dir=\"0 0 -1\"/>\n    {chr(10).join(world)}\n"
            f"{ET.tostring(arm, encoding='unicode')}\n  </worldbody>\n"
            f"  <contact>{excludes}</contact>\n</mujoco>\n"
        )
        return xml, finger_length


#: Keys of a scenario's ``arm`` mapping that place the arm in the scene; the others are the
#: arm's own settings (:func:`uvms_jax.robot.robot_from_config`: ``card``, ``description``, …).
MOUNT_KEYS = ("mount_pos", "mount_rpy", "mount_size", "jaws_open")


def scenario_robot(scenario: Mapping[str, Any]) -> robots.Robot:
    """The arm a scenario names: its ``arm`` mapping less the mount keys (:data:`MOUNT_KEYS`),
    e.g. ``{card: NAME}`` (a shipped arm) or ``{description: my_arm.urdf, tip: tool0, link_radius: 0.05}``."""
    arm = scenario.get("arm")
    if not isinstance(arm, Mapping):
        raise ValueError("the scenario needs an `arm` mapping: the arm (card or description) and its mount")
    return robots.robot_from_config({k: v for k, v in arm.items() if k not in MOUNT_KEYS})


def build_scene(robot: robots.Robot, spec: SceneSpec | Mapping[str, Any], T_world_base=None) -> Scene:
    """Build the MuJoCo scene of a robot in a scenario.

    Args:
      robot: the arm.
      spec: the scene: a :class:`SceneSpec` or a scenario mapping.
      T_world_base: ``(4, 4)`` pose of the arm's base link in the world [m]; None keeps the
        scenario's ``arm.mount_pos`` / ``arm.mount_rpy`` (see :meth:`SceneSpec.with_base`).
    """
    spec = spec if isinstance(spec, SceneSpec) else SceneSpec.from_mapping(spec)
    return Scene(spec if T_world_base is None else spec.with_base(T_world_base), robot)
