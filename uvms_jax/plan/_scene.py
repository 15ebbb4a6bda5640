"""A scene as a MuJoCo model: a scenario (:class:`~uvms_jax.plan.SceneSpec`, e.g. the thesis's
test cage, thesis 5.1, with any extra obstacles) with the robot built into it by the robot's
one MuJoCo builder, its base at a pose given by the config or by code
(:meth:`SceneSpec.with_base`, ``build_scene(robot, spec, T_world_base=...)``).

World frame: origin at the centre of the cage floor, z up; metres and radians. In the thesis's
cage the arm hangs from the top (its base frame's z points down). Every box of the scene — tables,
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
link at the grasp) are compiled ``16/16`` — a bit of their own, so they meet nothing, while
MuJoCo keeps them in its bounding volumes — until a :class:`Context` turns one on.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax import robot as robots
from uvms_jax.plan._spec import SceneSpec, box_vertices

__all__ = ["Context", "Scene", "build_scene"]

SCENE_BITS = (2, 2)  # contype, conaffinity of static geoms
MOUNT_BITS = (8, 0)  # the mount plate: against the moving links but the first
ARM_BITS = (1, 15)  # moving arm geoms: collide with the arm, the scene, the base link and the mount
SHOULDER_BITS = (1, 11)  # links always in contact with the base link: not against it
FIRST_BITS = (1, 3)  # the first link: it turns about its axis at the base, touching neither base nor mount
BASE_BITS = (4, 0)  # fixed base link: only against the other moving links, jaws and held object
OFF_BITS = (0, 0)
# The in-hand copies of the objects as compiled: a bit no other geom has, so that by default they
# meet nothing (copies on one body are never tested together), yet MuJoCo puts them in its
# bounding volumes (it leaves out geoms compiled with 0/0, and switching bits on later would
# not bring them back: such a copy would then never collide).
HELD_BITS = (16, 16)
# Self-collision pairs nearer than this in every sampled configuration are skipped: at least the
# planner's safety margin (PlanSettings.margin, 0.005 m), so that no pair reads as a collision in
# every pose.
SELF_COLLISION_MARGIN = 0.01  # [m]
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


class Scene:
    """A built scene: the robot in the world, its MuJoCo model, geom groups and the poses of
    objects and bases.

    Attributes:
      spec: the :class:`SceneSpec`.
      robot: the arm (:class:`uvms_jax.robot.Robot`).
      mjspec: the ``mujoco.MjSpec`` the model is compiled from (:attr:`xml`: as MJCF text).
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
      derived: what the stages compute once from the built scene and keep with it (e.g. the
        task graph's edges); a scene is not changed after it is built.
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
        self.mjspec, self.finger_length = self._build_spec()
        self.model = self.mjspec.compile()
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
        self.derived: dict[str, Any] = {}
        self.start_q = np.asarray(spec.start_q if spec.start_q is not None else self._start_configuration(), float)

    def geom_bits(self, context: Context) -> np.ndarray:
        """``(4, ngeom)`` int: per geom its ``contype`` and ``conaffinity`` for validity, then
        for clearance, in ``context`` (held object on, its table copy and the ignored geoms off;
        the module docstring gives the groups).

        Raises:
          ValueError: an unknown held object or obstacle.
        """
        if context.held is not None and context.held not in self.held_geoms:
            raise ValueError(f"unknown held object node {context.held} (objects: {sorted(self.held_geoms)})")
        for key in context.ignore:
            if key not in self.obstacle_geoms:
                raise ValueError(f"cannot ignore unknown obstacle {key!r} (known: {list(self.obstacle_geoms)})")
        off = set()
        for key in context.ignore:
            off.update(self.obstacle_geoms[key])
        if context.held is not None:
            off.update(self.obstacle_geoms.get(context.held, ()))
        held_on = self.held_geoms.get(context.held) if context.held is not None else None
        moving, held = set(self.arm_geoms), set(self.held_geoms.values())
        out = np.zeros((4, self.model.ngeom), dtype=int)
        for g in range(self.model.ngeom):
            if g in self.base_geoms:
                bits = BASE_BITS
            elif g in self.first_geoms:
                bits = FIRST_BITS
            elif g in self.shoulder_geoms:
                bits = SHOULDER_BITS
            elif g in moving or g == held_on:
                bits = ARM_BITS
            elif g in held:
                bits = OFF_BITS
            else:
                bits = OFF_BITS if g in off else MOUNT_BITS if g in self.mount_geoms else SCENE_BITS
            # Clearance model: only the clearance geoms (and the held object) against the scene.
            if g in self.clearance_geoms or g == held_on:
                cbits = (1, 0)
            elif bits in (SCENE_BITS, MOUNT_BITS):
                cbits = (0, 1)
            else:
                cbits = OFF_BITS
            out[:, g] = (*bits, *cbits)
        return out

    def _start_configuration(self, clearance: float = SELF_COLLISION_MARGIN, per_ring: int = 64,
                             seed: int = 0) -> np.ndarray:
        """A collision-free configuration near the arm's home (the middle of its joint range):
        the home itself if it is ``clearance`` [m] clear of everything, else the first clear
        one of random configurations in rings of growing size about it (tenths of the range).

        Raises:
          ValueError: none of them is clear (then give the scenario a ``start_q``).
        """
        robot = self.robot
        model = self.mjspec.compile()
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

    # -- the MuJoCo model -------------------------------------------------------------------
    @property
    def xml(self) -> str:
        """The scene's model as MJCF text, a file for other tools (MuJoCo writes its numbers
        with 6 significant digits: build models from :attr:`mjspec`)."""
        return self.mjspec.to_xml()

    def _build_spec(self) -> tuple[mujoco.MjSpec, float]:
        """The scene's model and the jaw fingers' reach beyond the tool point [m]."""
        spec = mujoco.MjSpec()
        spec.modelname = "thesis_cage"
        spec.compiler.degree = False
        spec.option.gravity = [0.0, 0.0, 0.0]
        spec.visual.global_.offwidth, spec.visual.global_.offheight = 960, 720
        spec.worldbody.add_light(pos=[0.0, 0.0, 3.0], dir=[0.0, 0.0, -1.0])
        self._add_cage(spec)
        self._add_items(spec)
        finger_length = self._add_arm(spec)
        base = robots.base_body(self.robot)
        for a, b in self.self_collision["always"]:
            if base not in (a, b):
                spec.add_exclude(bodyname1=a, bodyname2=b)
        return spec, finger_length

    def _add_cage(self, spec: mujoco.MjSpec) -> None:
        """The ceiling and the table under everything (half-spaces), the cage's frame, the mount."""
        s = self.spec
        # The ceiling and the table under everything are half-spaces (MuJoCo planes): exact,
        # cheap against every shape, and they also forbid slipping past their edges.
        if s.cage_size is not None:
            L, W, H = s.cage_size
            _add_geom(spec, "ceiling", frames.pose(np.diag([1.0, -1.0, -1.0]), (0.0, 0.0, H)), (0.7, 0.7, 0.7, 0.2),
                      type=mujoco.mjtGeom.mjGEOM_PLANE, size=[L / 2, W / 2, 0.05])
        under = s.tables[0]
        _add_geom(spec, under.name, under.T_world_top, (0.6, 0.55, 0.5, 1.0), type=mujoco.mjtGeom.mjGEOM_PLANE,
                  size=[under.size[0] / 2, under.size[1] / 2, 0.05])
        if s.cage_size is not None:
            p, frame = s.profile, (0.6, 0.6, 0.65, 1.0)
            k = 0
            for sx in (-1, 1):
                for sy in (-1, 1):
                    _add_box(spec, f"cage:post{k}", frames.pose(p=(sx * (L - p) / 2, sy * (W - p) / 2, H / 2)), (p, p, H),
                             frame)
                    k += 1
            for z in (p / 2, H - p / 2):
                for sx in (-1, 1):
                    _add_box(spec, f"cage:x{k}", frames.pose(p=(sx * (L - p) / 2, 0, z)), (p, W - 2 * p, p), frame)
                    _add_box(spec, f"cage:y{k}", frames.pose(p=(0, sx * (W - p) / 2, z)), (L - 2 * p, p, p), frame)
                    k += 1
        ms = s.mount_size
        _add_box(spec, "mount", self.T_world_base @ frames.pose(p=(0, 0, -ms[2] / 2)), ms, (0.3, 0.3, 0.3, 1.0),
                 MOUNT_BITS)

    def _add_items(self, spec: mujoco.MjSpec) -> None:
        """The tables on the floor, the obstacles, the base plates and the objects."""
        s = self.spec
        for t in s.tables[1:]:
            _add_box(spec, t.name, t.T_world_box, t.size, (0.75, 0.8, 0.9, 0.6))
        rgba = (0.55, 0.6, 0.7, 0.8)
        for o in s.obstacles:
            if o.shape == "sphere":
                _add_geom(spec, o.name, o.T_world, rgba, type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[o.dims[0], 0.0, 0.0])
            elif o.shape == "capsule":  # primitive: arm capsule vs capsule is exact in MuJoCo
                _add_geom(spec, o.name, o.T_world, rgba, type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                          size=[o.dims[0], o.dims[1] / 2, 0.0])
            else:  # MuJoCo collides with a mesh file's convex hull; boxes and cylinders as convex meshes
                mesh = spec.add_mesh(name=f"m_obstacle_{o.name}")
                if o.shape == "mesh" and not o.vertices:
                    mesh.file, mesh.scale = str(Path(o.file).resolve()), [o.scale] * 3
                else:
                    mesh.uservert = o.hull_vertices().reshape(-1)
                _add_geom(spec, o.name, o.T_world, rgba, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh.name)
        for b in s.bases:
            T = self.T_world_base_top(b.node) @ frames.pose(p=(0, 0, -b.size[2] / 2))
            _add_box(spec, f"n{b.node}:{b.name}", T, b.size, (0.9, 0.3, 0.2, 1.0))
        for o in s.objects:
            spec.add_mesh(name=f"m_{o.name}", uservert=o.vertices().reshape(-1))
            _add_geom(spec, f"n{o.node}:{o.name}", self.T_world_object(o.node), (1.0, 0.55, 0.1, 1.0),
                      type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"m_{o.name}")

    def _add_arm(self, spec: mujoco.MjSpec) -> float:
        """The arm's body tree with each geom's collision bits, its jaw fingers as convex
        meshes and in-hand copies of the objects (off by default); returns the fingers' reach
        beyond the tool point [m]."""
        s, robot = self.spec, self.robot
        base = robots.add_robot(spec, robot, pos=s.mount_pos, quat=frames.matrix_quat(self.T_world_base[:3, :3]),
                                jaws_open=s.jaws_open)
        tool = spec.site(robots.TOOL_SITE)
        T_link_tool = frames.pose(frames.quat_matrix(tool.quat), tool.pos)
        shoulder = {b for _, b in self._base_pairs()}
        finger_length = 0.0
        for body in [base, *base.find_all(mujoco.mjtObj.mjOBJ_BODY)]:
            bits = (BASE_BITS if body.name == base.name else FIRST_BITS if body.name == robot.link_names[0]
                    else SHOULDER_BITS if body.name in shoulder else ARM_BITS)
            for g in body.geoms:
                g.contype, g.conaffinity = bits
                if g.type == mujoco.mjtGeom.mjGEOM_BOX:  # jaw fingers → convex meshes (see the module docstring)
                    size = np.array(g.size) * 2
                    tip = np.linalg.inv(T_link_tool) @ np.r_[g.pos, 1.0]
                    finger_length = max(finger_length, tip[2] + size[2] / 2)
                    spec.add_mesh(name=f"m_{g.name}", uservert=box_vertices(size).reshape(-1))
                    g.type, g.meshname, g.size = mujoco.mjtGeom.mjGEOM_MESH, f"m_{g.name}", [0.0, 0.0, 0.0]
        # In-hand copies of the objects, fixed to the last link at the grasp (off by default).
        last = tool.parent
        for o in s.objects:
            T = T_link_tool @ self.T_tool_obj_for(o.node)
            last.add_geom(name=f"held_{o.name}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"m_{o.name}",
                          pos=T[:3, 3], quat=frames.matrix_quat(T[:3, :3]), rgba=[1.0, 0.55, 0.1, 0.8],
                          contype=HELD_BITS[0], conaffinity=HELD_BITS[1])
        return finger_length


def _add_geom(spec: mujoco.MjSpec, name: str, T: np.ndarray, rgba, bits=SCENE_BITS, **kwargs) -> None:
    """A world geom named ``name`` at ``T (4, 4)`` with colour ``rgba`` and collision ``bits``."""
    spec.worldbody.add_geom(name=name, pos=T[:3, 3], quat=frames.matrix_quat(T[:3, :3]), rgba=rgba, contype=bits[0],
                            conaffinity=bits[1], **kwargs)


def _add_box(spec: mujoco.MjSpec, label: str, T: np.ndarray, size, rgba, bits=SCENE_BITS) -> None:
    """A box of full ``size`` [m] at ``T (4, 4)`` as a convex mesh geom (mesh ``m_<label>``)."""
    spec.add_mesh(name=f"m_{label}", uservert=box_vertices(size).reshape(-1))
    _add_geom(spec, label, T, rgba, bits, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"m_{label}")


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
