"""The one MuJoCo model of a robot (its collision model), built with ``mujoco.MjSpec``
(:func:`add_robot` into any model, :func:`robot_spec` alone), and the self-collision pairs to skip.

Bodies follow the chain: the base link, then one body per joint in its frame at ``q = 0``
(``chain.T_base_joint0``), named as the description names them. Each link is a capsule of the
robot's ``link_radius`` from its joint's origin to the next joint's origin (the last to the
tool frame; a sphere where the two coincide); the base link a capsule from its origin to the
first joint's. A robot whose description gives collision geometry (``robot.shapes``) has those
shapes instead of the capsules: spheres and capsules as MuJoCo primitives, boxes and cylinders
as convex meshes (8 vertices; a prism of 32 sides around the cylinder), mesh files as mesh
assets of the model (named ``m_<geom name>``). A site ``tool`` marks the tool frame. The hand: a robot whose description has fingers
(``robot.fingers``) gets their shapes, named ``geom_<finger joint>_<k>``: fixed to the body they
hang from at the opening asked for (a kinematic model: the planning scene, the self-collision
pairs), or, with ``finger_joints``, as finger bodies named as the description names them, each
on its slide joint (the simulated arm, which ties the mimics to the gripper joint:
:func:`uvms_jax.hw.add_drives`). Without fingers a gripper adds two finger boxes (:func:`card_jaws`), the
opening along the tool's x axis, reaching forward along its z axis. Shapes fixed to the arm for
one use of its model (an object in the hand) come as ``attached`` shapes.
"""

from __future__ import annotations

import itertools
import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.kin import REVOLUTE
from uvms_jax.robot._geometry import Shape
from uvms_jax.robot._model import BASE, Robot

__all__ = ["TOOL_SITE", "add_robot", "base_body", "card_jaws", "geom_name", "link_capsules", "robot_mjcf", "robot_spec",
           "self_collision_pairs"]

TOOL_SITE = "tool"
_COINCIDENT = 1e-9  # [m] joint origins closer than this make a sphere, not a capsule
_DISTMAX = 1.0  # [m] mj_geomDistance reports distances up to this (and this beyond it)
_CYLINDER_SIDES = 32  # a cylinder shape is the prism of this many sides around it
# A moving body without shapes still needs mass in MuJoCo (a collision model needs none).
_NO_MASS, _NO_INERTIA = 1e-6, 1e-10  # [kg, kg·m²]
_TOOL_SITE_SIZE = 0.01  # [m] the tool site's drawn radius


def base_body(robot: Robot) -> str:
    """The base's body name in the model (an MJCF arm based on its world body gets ``base_link``:
    in a scene the world is the scene's)."""
    return "base_link" if robot.base_link == "world" else robot.base_link


def geom_name(robot: Robot, body: int) -> str:
    """Name of a body's link capsule: ``geom_base`` or ``geom_<joint>``; the description's shapes
    of that body are ``geom_base_<k>`` / ``geom_<joint>_<k>`` (``k`` counts that body's shapes)."""
    return "geom_base" if body == BASE else f"geom_{robot.joint_names[body]}"


def _shape_names(robot: Robot) -> list[str]:
    """Geom names of ``robot.shapes``, in order."""
    count: dict[int, int] = {}
    names = []
    for s in robot.shapes:
        k = count[s.body] = count.get(s.body, -1) + 1
        names.append(f"{geom_name(robot, s.body)}_{k}")
    return names


def _finger_shape_names(robot: Robot) -> list[list[str]]:
    """Geom names of each finger's shapes: ``geom_<finger joint>_<k>``."""
    return [[f"geom_{f.joint}_{k}" for k in range(len(f.shapes))] for f in robot.fingers]


def _all_shapes(robot: Robot) -> list[tuple[Shape, str]]:
    """Every shape of the arm and its fingers with its geom name."""
    named = list(zip(robot.shapes, _shape_names(robot)))
    for f, names in zip(robot.fingers, _finger_shape_names(robot)):
        named += list(zip(f.shapes, names))
    return named


def link_capsules(robot: Robot) -> list[tuple[int, np.ndarray]]:
    """The links' capsules (the collision model where ``robot.shapes`` is empty): ``(body, end)``
    per body, the capsule of radius ``robot.link_radius`` from the body's origin to ``end (3,)``
    [m] in its frame (the next joint's origin, the last body's the tool frame; a sphere where
    ``end`` is the origin)."""
    T_joint = np.asarray(robot.chain.T_base_joint0, dtype=np.float64)
    tool = np.asarray(robot.chain.T_base_tool0, dtype=np.float64)
    n = robot.n_joints
    ends = [(BASE, T_joint[0, :3, 3])]
    for i in range(n):
        ends.append((i, (np.linalg.inv(T_joint[i]) @ (T_joint[i + 1] if i + 1 < n else tool))[:3, 3]))
    return ends


def _hull_vertices(shape: Shape) -> np.ndarray:
    """``(k, 3)`` convex mesh vertices of a box or cylinder shape in its frame (a cylinder: the
    circumscribed prism, never smaller)."""
    if shape.kind == "box":
        h = np.asarray(shape.size, dtype=float) / 2.0
        return np.array([[sx * h[0], sy * h[1], sz * h[2]] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    r, length = shape.size
    a = np.arange(_CYLINDER_SIDES) * 2 * np.pi / _CYLINDER_SIDES
    ring = np.stack([np.cos(a), np.sin(a)], -1) * r / np.cos(np.pi / _CYLINDER_SIDES)
    return np.concatenate([np.c_[ring, np.full(len(a), -length / 2)], np.c_[ring, np.full(len(a), length / 2)]])


def _attached_named(robot: Robot, attached) -> list[tuple[Shape, str]]:
    """Shapes fixed to the arm's bodies for one use of its model (e.g. an object in the hand)
    with their geom names ``geom_<link>``; ValueError for a bad body or a repeated name."""
    named = [(s, f"geom_{s.link}") for s in attached]
    taken = {n for _, n in _all_shapes(robot)} | {f"geom_{s.link}" for s in card_jaws(robot)}
    for s, name in named:
        if not BASE <= s.body < robot.n_joints:
            raise ValueError(f"attached shape {s.link!r}: body {s.body} is not -1 … {robot.n_joints - 1}")
        if name in taken:
            raise ValueError(f"attached shape {s.link!r}: its geom name {name!r} is taken (give it another link name)")
        taken.add(name)
    return named


def _add_meshes(spec: mujoco.MjSpec, robot: Robot, attached: tuple[Shape, ...]) -> None:
    """Add the meshes that :func:`add_robot`'s geoms use to ``spec`` (none for a robot of
    capsules), its fingers' and the ``attached`` shapes' included, named ``m_<geom name>``."""
    for s, name in _all_shapes(robot) + _attached_named(robot, attached):
        if s.kind == "mesh" and s.file:
            spec.add_mesh(name=f"m_{name}", file=s.file, scale=s.scale)
        elif s.kind == "mesh":
            spec.add_mesh(name=f"m_{name}", uservert=np.asarray(s.vertices, dtype=float).reshape(-1))
        elif s.kind in ("box", "cylinder"):
            spec.add_mesh(name=f"m_{name}", uservert=_hull_vertices(s).reshape(-1))


def _pose(T: np.ndarray) -> dict:
    """``pos`` and ``quat`` (w, x, y, z) keywords of a pose ``T (4, 4)``."""
    return dict(pos=T[:3, 3], quat=frames.matrix_quat(T[:3, :3]))


def _add_shape(body: mujoco.MjsBody, shape: Shape, name: str, T_move: np.ndarray | None = None) -> None:
    """The shape as a geom of ``body``: spheres and capsules as primitives, the rest as the mesh
    ``m_<name>``; at its pose, moved by ``T_move (4, 4)`` where given."""
    pose = _pose(shape.T if T_move is None else T_move @ shape.T)
    if shape.kind == "sphere":
        body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[shape.size[0], 0.0, 0.0], **pose)
    elif shape.kind == "capsule":
        body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[shape.size[0], shape.size[1] / 2, 0.0],
                      **pose)
    else:
        body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"m_{name}", **pose)


def _add_body_geoms(body: mujoco.MjsBody, robot: Robot, k: int, end: np.ndarray) -> None:
    """Body ``k``'s geoms: its link capsule (to ``end`` in its frame), or its shapes."""
    if robot.shapes:
        for s, n in zip(robot.shapes, _shape_names(robot)):
            if s.body == k:
                _add_shape(body, s, n)
    elif np.linalg.norm(end) < _COINCIDENT:
        body.add_geom(name=geom_name(robot, k), type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[robot.link_radius, 0.0, 0.0])
    else:
        body.add_geom(name=geom_name(robot, k), type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=[0.0, 0.0, 0.0, *end],
                      size=[robot.link_radius, 0.0, 0.0])


def _add_fingers(body: mujoco.MjsBody, robot: Robot, k: int, opening: float, finger_joints: bool) -> None:
    """The fingers hanging from body ``k``: their geoms at ``opening`` [m] fixed to it, or (with
    ``finger_joints``) finger bodies on slide joints whose range the gripper's limits give."""
    g = robot.gripper
    for f, names in zip(robot.fingers, _finger_shape_names(robot)):
        if f.body != k:
            continue
        if not finger_joints:
            for s, n in zip(f.shapes, names):
                _add_shape(body, s, n, f.T(opening))
            continue
        lo, hi = sorted((f.value(g.lower), f.value(g.upper)))
        child = body.add_body(name=f.link)
        _set_no_mass(child)
        child.add_joint(name=f.joint, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=f.axis, range=[lo, hi],
                        limited=mujoco.mjtLimited.mjLIMITED_TRUE)
        for s, n in zip(f.shapes, names):
            _add_shape(child, s, n)


def _set_no_mass(body: mujoco.MjsBody) -> None:
    """A moving body without shapes still needs mass in MuJoCo (a collision model needs none)."""
    body.mass, body.ipos, body.inertia, body.explicitinertial = _NO_MASS, [0.0, 0.0, 0.0], [_NO_INERTIA] * 3, True


def _set_inertial(body: mujoco.MjsBody, robot: Robot, k: int) -> bool:
    """Give body ``k`` the robot's summed mass properties of it; False (nothing set) when it
    has none."""
    parts = [b for b in robot.inertials if b.body == k and b.mass > 0]
    if not parts:
        return False
    mass = sum(b.mass for b in parts)
    com = sum(b.mass * np.asarray(b.com) for b in parts) / mass
    I = np.zeros((3, 3))
    for b in parts:  # parallel-axis theorem about the summed centre of mass
        xx, yy, zz, xy, xz, yz = b.inertia
        d = np.asarray(b.com) - com
        I += np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) + b.mass * (d @ d * np.eye(3) - np.outer(d, d))
    body.mass, body.ipos, body.explicitinertial = mass, com, True
    body.fullinertia = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
    return True


def _add_attached(body: mujoco.MjsBody, named: list[tuple[Shape, str]], k: int) -> None:
    for s, name in named:
        if s.body == k:
            _add_shape(body, s, name)


def add_robot(spec: mujoco.MjSpec, robot: Robot, parent: mujoco.MjsBody | None = None, pos=(0.0, 0.0, 0.0),
              quat=(1.0, 0.0, 0.0, 0.0), jaws_open: float | None = None, inertial: bool = False,
              finger_joints: bool = False, attached: tuple[Shape, ...] = ()) -> mujoco.MjsBody:
    """Add the robot's body tree to ``spec`` under ``parent`` (default: the world body), with
    the meshes its geoms use. ``spec`` must take angles in radians
    (``spec.compiler.degree = False``): the joint ranges are.

    Args:
      spec: the model to add to (changed in place).
      robot: the arm.
      parent: the body the base link hangs from (e.g. a vehicle), default ``spec.worldbody``.
      pos, quat: the base link's pose in the parent frame [m], ``(w, x, y, z)``.
      jaws_open: the gripper's opening [m], its joint's value (the gap between the finger
        boxes; the description's fingers slide by :meth:`~uvms_jax.robot.Finger.value` of it);
        default: the gripper's largest; ignored without a gripper.
      inertial: give the bodies their mass properties (a simulation needs them; collision
        queries do not). The fingers' masses stay folded into the body they hang from.
      finger_joints: the description's fingers as bodies on their slide joints (at value 0:
        ``jaws_open`` is not used) rather than fixed at ``jaws_open``.
      attached: shapes fixed to the arm's bodies for this model (e.g. an object in the hand;
        ``Shape.body`` the body, its pose in that body's frame), geoms named ``geom_<link>``.

    Returns:
      the base link's body.

    Raises:
      ValueError: ``jaws_open`` outside the gripper's limits for a robot with fingers, or an
        attached shape on no body of the arm or with a geom name already taken.
    """
    named = _attached_named(robot, attached)
    g = robot.gripper
    opening = None if g is None else (g.upper if jaws_open is None else float(jaws_open))
    if robot.fingers and not g.lower <= opening <= g.upper:
        raise ValueError(f"jaws_open {opening} m is outside the gripper's limits [{g.lower}, {g.upper}] m")
    if spec.compiler.degree:
        raise ValueError("add_robot: the spec takes angles in degrees; set spec.compiler.degree = False")
    _add_meshes(spec, robot, attached)
    chain = robot.chain
    T_joint = np.asarray(chain.T_base_joint0, dtype=np.float64)
    twists = np.asarray(chain.twists, dtype=np.float64)
    ends = dict(link_capsules(robot))
    base = (spec.worldbody if parent is None else parent).add_body(name=base_body(robot), pos=pos, quat=quat)
    if inertial:
        _set_inertial(base, robot, BASE)
    _add_body_geoms(base, robot, BASE, ends[BASE])
    _add_fingers(base, robot, BASE, opening, finger_joints)
    _add_attached(base, named, BASE)
    body, previous = base, np.eye(4)
    for i in range(robot.n_joints):
        body = body.add_body(name=robot.link_names[i], **_pose(np.linalg.inv(previous) @ T_joint[i]))
        revolute = chain.kinds[i] == REVOLUTE
        if not (inertial and _set_inertial(body, robot, i)) and not _has_geoms(robot, i):
            _set_no_mass(body)
        body.add_joint(name=robot.joint_names[i], type=mujoco.mjtJoint.mjJNT_HINGE if revolute else mujoco.mjtJoint.mjJNT_SLIDE,
                       axis=T_joint[i, :3, :3].T @ (twists[i, 3:] if revolute else twists[i, :3]),
                       range=[float(chain.lower[i]), float(chain.upper[i])], limited=mujoco.mjtLimited.mjLIMITED_TRUE)
        _add_body_geoms(body, robot, i, ends[i])
        _add_fingers(body, robot, i, opening, finger_joints)
        _add_attached(body, named, i)
        previous = T_joint[i]
    tool = body.add_site(name=TOOL_SITE, **_pose(np.linalg.inv(T_joint[-1]) @ np.asarray(chain.T_base_tool0, dtype=np.float64)))
    tool.size[0] = _TOOL_SITE_SIZE
    for s in card_jaws(robot, opening):
        body.add_geom(name=f"geom_{s.link}", type=mujoco.mjtGeom.mjGEOM_BOX, size=np.array(s.size) / 2, **_pose(s.T))
    return base


def _has_geoms(robot: Robot, k: int) -> bool:
    """Whether body ``k`` gets geoms of its own (its capsule, or shapes of the description)."""
    return not robot.shapes or any(s.body == k for s in robot.shapes)


def card_jaws(robot: Robot, opening: float | None = None) -> tuple[Shape, ...]:
    """The finger boxes that stand for the hand of an arm whose card gives a gripper but whose
    description has no fingers, as box shapes of :attr:`Gripper.finger_size` on the last body
    (named ``jaw_left`` and ``jaw_right``; their geoms in :func:`add_robot`: ``geom_jaw_left``,
    ``geom_jaw_right``): ``opening`` [m] apart along the tool's x axis (default: the gripper's
    largest), reaching forward along its z axis. Empty without a gripper or with fingers."""
    g = robot.gripper
    if g is None or robot.fingers:
        return ()
    opening = g.upper if opening is None else float(opening)
    T_joint = np.asarray(robot.chain.T_base_joint0, dtype=np.float64)
    T_link_tool = np.linalg.inv(T_joint[-1]) @ np.asarray(robot.chain.T_base_tool0, dtype=np.float64)
    fx, _, fz = g.finger_size
    return tuple(Shape(robot.n_joints - 1, "box", tuple(float(v) for v in (T_link_tool @ frames.pose(
        p=(sign * (opening / 2.0 + fx / 2.0), 0.0, fz / 2.0))).reshape(16)), tuple(g.finger_size), link=f"jaw_{side}")
        for side, sign in (("left", 1.0), ("right", -1.0)))


def robot_spec(robot: Robot, jaws_open: float | None = None, inertial: bool = False,
               attached: tuple[Shape, ...] = ()) -> mujoco.MjSpec:
    """A complete model of the robot alone (:func:`add_robot` with these arguments), its base
    link at the world origin, no gravity; ``.compile()`` gives the ``MjModel``."""
    spec = mujoco.MjSpec()
    spec.modelname = robot.name
    spec.compiler.degree = False
    spec.option.gravity = [0.0, 0.0, 0.0]
    add_robot(spec, robot, jaws_open=jaws_open, inertial=inertial, attached=attached)
    return spec


def robot_mjcf(robot: Robot, jaws_open: float | None = None, inertial: bool = False,
               attached: tuple[Shape, ...] = ()) -> str:
    """:func:`robot_spec` as MJCF text, a file for other tools (MuJoCo writes its numbers with
    6 significant digits: build models from :func:`robot_spec`, not from this text)."""
    return robot_spec(robot, jaws_open, inertial, attached).to_xml()


def self_collision_pairs(robot: Robot, n_samples: int = 200, seed: int = 0, jaws_open: float | None = None,
                         margin: float = 0.0) -> dict[str, list[tuple[str, str]]]:
    """The body pairs a self-collision check skips, found as MoveIt's setup assistant finds them.

    ``adjacent``: a link and its parent. ``always``: non-adjacent pairs nearer than ``margin``
    [m] (a collision checker's safety distance) in every one of ``n_samples`` configurations
    drawn uniformly within the joint limits: they touch by construction (e.g. capsules meeting
    at a joint cluster), so a check of them says nothing about the pose.

    Returns:
      ``{"adjacent": [(body, body), ...], "always": [(body, body), ...]}`` (body names).
    """
    if n_samples < 1:
        raise ValueError(f"n_samples must be >= 1, got {n_samples}")
    model = robot_spec(robot, jaws_open).compile()
    data = mujoco.MjData(model)
    names = [base_body(robot), *robot.link_names]
    adjacent = list(zip(names[:-1], names[1:]))
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in names]
    candidates = [(a, b) for a, b in itertools.combinations(range(len(names)), 2) if b > a + 1]
    # Every pair is tested whatever MuJoCo's filters: distances between the bodies' geoms.
    geoms = {k: [g for g in range(model.ngeom) if model.geom_bodyid[g] == ids[k]] for k in range(len(names))}
    rng = np.random.default_rng(seed)
    q = rng.uniform(robot.lower, robot.upper, (n_samples, robot.n_joints))
    always = set(candidates)
    for row in q:
        data.qpos[:] = row
        mujoco.mj_kinematics(model, data)
        touching = set()
        for a, b in always:
            if any(mujoco.mj_geomDistance(model, data, g1, g2, _DISTMAX, None) <= margin
                   for g1 in geoms[a] for g2 in geoms[b]):
                touching.add((a, b))
        always = touching
        if not always:
            break
    return {"adjacent": adjacent, "always": [(names[a], names[b]) for a, b in sorted(always)]}
