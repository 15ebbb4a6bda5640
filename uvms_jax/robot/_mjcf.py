"""The one MuJoCo model of a robot (its collision model), and the self-collision pairs to skip.

Bodies follow the chain: the base link, then one body per joint in its frame at ``q = 0``
(``chain.T_base_joint0``), named as the description names them. Each link is a capsule of the
robot's ``link_radius`` from its joint's origin to the next joint's origin (the last to the
tool frame; a sphere where the two coincide); the base link a capsule from its origin to the
first joint's. A robot whose description gives collision geometry (``robot.shapes``) has those
shapes instead of the capsules: spheres and capsules as MuJoCo primitives, boxes and cylinders
as convex meshes (8 vertices; a prism of 32 sides around the cylinder), mesh files as ``<mesh
file=...>`` assets (:func:`mjcf_assets` gives the ``<asset>`` entries every model of the arm
needs). A site ``tool`` marks the tool frame. The hand: a robot whose description has fingers
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
from xml.sax.saxutils import quoteattr  # file names in XML: quoted and escaped

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.kin import REVOLUTE
from uvms_jax.robot._geometry import Shape
from uvms_jax.robot._model import BASE, Robot
from uvms_jax.text import numbers

__all__ = ["TOOL_SITE", "base_body", "card_jaws", "geom_name", "link_capsules", "mjcf_assets", "mjcf_body", "robot_mjcf",
           "self_collision_pairs"]

TOOL_SITE = "tool"
_COINCIDENT = 1e-9  # [m] joint origins closer than this make a sphere, not a capsule
_DISTMAX = 1.0  # [m] mj_geomDistance reports distances up to this (and this beyond it)
_CYLINDER_SIDES = 32  # a cylinder shape is the prism of this many sides around it
# A moving body without shapes still needs mass in MuJoCo (a collision model needs none).
_NO_MASS = '<inertial pos="0 0 0" mass="1e-06" diaginertia="1e-10 1e-10 1e-10"/>'


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


def mjcf_assets(robot: Robot, attached: tuple[Shape, ...] = ()) -> list[str]:
    """The ``<mesh>`` entries of an ``<asset>`` element that :func:`mjcf_body`'s geoms use
    (none for a robot of capsules), its fingers' and the ``attached`` shapes' included. Mesh
    names are ``m_<geom name>``."""
    assets = []
    for s, name in _all_shapes(robot) + _attached_named(robot, attached):
        if s.kind == "mesh" and s.file:
            assets.append(f'<mesh name="m_{name}" file={quoteattr(s.file)} scale="{numbers(s.scale)}"/>')
        elif s.kind == "mesh":
            assets.append(f'<mesh name="m_{name}" vertex="{numbers(s.vertices)}"/>')
        elif s.kind in ("box", "cylinder"):
            assets.append(f'<mesh name="m_{name}" vertex="{numbers(_hull_vertices(s))}"/>')
    return assets


def _shape_geom(shape: Shape, name: str, T_move: np.ndarray | None = None) -> str:
    T = shape.T if T_move is None else T_move @ shape.T
    pose = f'pos="{numbers(T[:3, 3])}" quat="{numbers(frames.matrix_quat(T[:3, :3]))}"'
    if shape.kind == "sphere":
        return f'<geom name="{name}" type="sphere" size="{shape.size[0]!r}" {pose}/>'
    if shape.kind == "capsule":
        return f'<geom name="{name}" type="capsule" size="{shape.size[0]!r} {shape.size[1] / 2!r}" {pose}/>'
    return f'<geom name="{name}" type="mesh" mesh="m_{name}" {pose}/>'


def _body_geoms(robot: Robot, body: int, end: np.ndarray) -> list[str]:
    """The body's geoms: its capsule (to ``end`` in its frame), or its shapes."""
    if not robot.shapes:
        return [_link_geom(geom_name(robot, body), end, robot.link_radius)]
    return [_shape_geom(s, n) for s, n in zip(robot.shapes, _shape_names(robot)) if s.body == body]


def _finger_lines(robot: Robot, body: int, opening: float, finger_joints: bool) -> list[str]:
    """The fingers hanging from ``body``: their geoms at ``opening`` [m] fixed to it, or (with
    ``finger_joints``) finger bodies on slide joints whose range the gripper's limits give."""
    lines = []
    g = robot.gripper
    for f, names in zip(robot.fingers, _finger_shape_names(robot)):
        if f.body != body:
            continue
        if not finger_joints:
            lines += [_shape_geom(s, n, f.T(opening)) for s, n in zip(f.shapes, names)]
            continue
        lo, hi = sorted((f.value(g.lower), f.value(g.upper)))
        lines += [f'<body name="{f.link}">', "  " + _NO_MASS,
                  f'  <joint name="{f.joint}" type="slide" axis="{numbers(f.axis)}" range="{lo!r} {hi!r}" limited="true"/>',
                  *["  " + _shape_geom(s, n) for s, n in zip(f.shapes, names)], "</body>"]
    return lines


def _link_geom(name: str, end: np.ndarray, radius: float) -> str:
    if np.linalg.norm(end) < _COINCIDENT:
        return f'<geom name="{name}" type="sphere" size="{radius!r}"/>'
    return f'<geom name="{name}" type="capsule" fromto="0 0 0 {numbers(end)}" size="{radius!r}"/>'


def _inertial(robot: Robot, body: int) -> str:
    """The body's summed mass properties as an MJCF ``<inertial>`` (empty when it has none)."""
    parts = [b for b in robot.inertials if b.body == body and b.mass > 0]
    if not parts:
        return ""
    mass = sum(b.mass for b in parts)
    com = sum(b.mass * np.asarray(b.com) for b in parts) / mass
    I = np.zeros((3, 3))
    for b in parts:  # parallel-axis theorem about the summed centre of mass
        xx, yy, zz, xy, xz, yz = b.inertia
        d = np.asarray(b.com) - com
        I += np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) + b.mass * (d @ d * np.eye(3) - np.outer(d, d))
    return (f'<inertial pos="{numbers(com)}" mass="{mass!r}" '
            f'fullinertia="{numbers([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])}"/>')


def mjcf_body(robot: Robot, pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0), jaws_open: float | None = None,
              inertial: bool = False, finger_joints: bool = False, attached: tuple[Shape, ...] = ()) -> str:
    """MJCF ``<body>`` tree of the robot (radians), for a ``<worldbody>`` whose
    ``<compiler angle="radian"/>`` is set.

    Args:
      robot: the arm.
      pos, quat: the base link's pose in the parent frame [m], ``(w, x, y, z)``.
      jaws_open: the gripper's opening [m], its joint's value (the gap between the finger
        boxes; the description's fingers slide by :meth:`~uvms_jax.robot.Finger.value` of it);
        default: the gripper's largest; ignored without a gripper.
      inertial: write the bodies' mass properties (a simulation needs them; collision
        queries do not). The fingers' masses stay folded into the body they hang from.
      finger_joints: the description's fingers as bodies on their slide joints (at value 0:
        ``jaws_open`` is not used) rather than fixed at ``jaws_open``.
      attached: shapes fixed to the arm's bodies for this model (e.g. an object in the hand;
        ``Shape.body`` the body, its pose in that body's frame), geoms named ``geom_<link>``
        (their meshes: :func:`mjcf_assets` with the same shapes).

    Raises:
      ValueError: ``jaws_open`` outside the gripper's limits for a robot with fingers, or an
        attached shape on no body of the arm or with a geom name already taken.
    """
    named = _attached_named(robot, attached)
    g = robot.gripper
    opening = None if g is None else (g.upper if jaws_open is None else float(jaws_open))
    if robot.fingers and not g.lower <= opening <= g.upper:
        raise ValueError(f"jaws_open {opening} m is outside the gripper's limits [{g.lower}, {g.upper}] m")
    chain = robot.chain
    T_joint = np.asarray(chain.T_base_joint0, dtype=np.float64)
    twists = np.asarray(chain.twists, dtype=np.float64)
    tool = np.asarray(chain.T_base_tool0, dtype=np.float64)
    n = robot.n_joints
    ends = dict(link_capsules(robot))
    lines = [f'<body name="{base_body(robot)}" pos="{numbers(pos)}" quat="{numbers(quat)}">']
    if inertial and _inertial(robot, BASE):
        lines.append("  " + _inertial(robot, BASE))
    lines += ["  " + g for g in _body_geoms(robot, BASE, ends[BASE])]
    lines += ["  " + g for g in _finger_lines(robot, BASE, opening, finger_joints)]
    lines += ["  " + _shape_geom(s, name) for s, name in named if s.body == BASE]
    previous = np.eye(4)
    for i in range(n):
        pad = "  " * (i + 1)
        local = np.linalg.inv(previous) @ T_joint[i]
        R = T_joint[i, :3, :3]
        axis = R.T @ (twists[i, 3:] if chain.kinds[i] == REVOLUTE else twists[i, :3])
        lines.append(f'{pad}<body name="{robot.link_names[i]}" pos="{numbers(local[:3, 3])}" '
                     f'quat="{numbers(frames.matrix_quat(local[:3, :3]))}">')
        geoms = _body_geoms(robot, i, ends[i])
        if inertial and _inertial(robot, i):
            lines.append(f"{pad}  " + _inertial(robot, i))
        elif not geoms:
            lines.append(f"{pad}  " + _NO_MASS)
        kind = "hinge" if chain.kinds[i] == REVOLUTE else "slide"
        lines.append(f'{pad}  <joint name="{robot.joint_names[i]}" type="{kind}" axis="{numbers(axis)}" '
                     f'range="{float(chain.lower[i])!r} {float(chain.upper[i])!r}" limited="true"/>')
        lines += [f"{pad}  " + g for g in geoms + _finger_lines(robot, i, opening, finger_joints)]
        lines += [f"{pad}  " + _shape_geom(s, name) for s, name in named if s.body == i]
        previous = T_joint[i]
    pad = "  " * (n + 1)
    T_link_tool = np.linalg.inv(T_joint[-1]) @ tool
    tool_quat = numbers(frames.matrix_quat(T_link_tool[:3, :3]))
    lines.append(f'{pad}<site name="{TOOL_SITE}" pos="{numbers(T_link_tool[:3, 3])}" quat="{tool_quat}" size="0.01"/>')
    for s in card_jaws(robot, opening):
        T = s.T
        lines.append(f'{pad}<geom name="geom_{s.link}" type="box" pos="{numbers(T[:3, 3])}" '
                     f'quat="{numbers(frames.matrix_quat(T[:3, :3]))}" size="{numbers(np.array(s.size) / 2)}"/>')
    for d in range(n, -1, -1):
        lines.append("  " * d + "</body>")
    return "\n".join(lines)


def card_jaws(robot: Robot, opening: float | None = None) -> tuple[Shape, ...]:
    """The finger boxes that stand for the hand of an arm whose card gives a gripper but whose
    description has no fingers, as box shapes of :attr:`Gripper.finger_size` on the last body
    (named ``jaw_left`` and ``jaw_right``; their geoms in :func:`mjcf_body`: ``geom_jaw_left``,
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


def robot_mjcf(robot: Robot, jaws_open: float | None = None, inertial: bool = False,
               attached: tuple[Shape, ...] = ()) -> str:
    """A complete MJCF model of the robot alone (with the ``attached`` shapes of
    :func:`mjcf_body`), its base link at the world origin, no gravity."""
    assets = "".join(f"\n    {a}" for a in mjcf_assets(robot, attached))
    return (f'<mujoco model="{robot.name}">\n  <compiler angle="radian"/>\n  <option gravity="0 0 0"/>\n'
            + (f"  <asset>{assets}\n  </asset>\n" if assets else "") +
            f"  <worldbody>\n{mjcf_body(robot, jaws_open=jaws_open, inertial=inertial, attached=attached)}\n"
            "  </worldbody>\n</mujoco>\n")


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
    model = mujoco.MjModel.from_xml_string(robot_mjcf(robot, jaws_open))
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
