"""The one MuJoCo model of a robot (its collision model), and the self-collision pairs to skip.

Bodies follow the chain: the base link, then one body per joint in its frame at ``q = 0``
(``chain.T_base_joint0``), named as the description names them. Each link is a capsule of the
robot's ``link_radius`` from its joint's origin to the next joint's origin (the last to the
tool frame; a sphere where the two coincide); the base link a capsule from its origin to the
first joint's. A robot whose description gives collision geometry (``robot.shapes``) has those
shapes instead of the capsules: spheres and capsules as MuJoCo primitives, boxes and cylinders
as convex meshes (8 vertices; a prism of 32 sides around the cylinder), mesh files as ``<mesh
file=...>`` assets (:func:`mjcf_assets` gives the ``<asset>`` entries every model of the arm
needs). A site ``tool`` marks the tool frame; a gripper adds two finger boxes, the opening along
the tool's x axis, reaching forward along its z axis.
"""

from __future__ import annotations

import itertools
from xml.sax.saxutils import quoteattr  # file names in XML: quoted and escaped

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.kin._chain import REVOLUTE
from uvms_jax.robot._geometry import Shape
from uvms_jax.robot._model import BASE, Robot

__all__ = ["TOOL_SITE", "base_body", "geom_name", "mjcf_assets", "mjcf_body", "robot_mjcf", "self_collision_pairs"]

TOOL_SITE = "tool"
_COINCIDENT = 1e-9  # [m] joint origins closer than this make a sphere, not a capsule
_DISTMAX = 1.0  # [m] mj_geomDistance reports distances up to this (and this beyond it)
_CYLINDER_SIDES = 32  # a cylinder shape is the prism of this many sides around it
# A moving body without shapes still needs mass in MuJoCo (a collision model needs none).
_NO_MASS = '<inertial pos="0 0 0" mass="1e-06" diaginertia="1e-10 1e-10 1e-10"/>'


def _fmt(values) -> str:
    return " ".join(f"{float(v):.10g}" for v in np.ravel(values))


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


def mjcf_assets(robot: Robot) -> list[str]:
    """The ``<mesh>`` entries of an ``<asset>`` element that :func:`mjcf_body`'s geoms use
    (none for a robot of capsules). Mesh names are ``m_<geom name>``."""
    assets = []
    for s, name in zip(robot.shapes, _shape_names(robot)):
        if s.kind == "mesh" and s.file:
            assets.append(f'<mesh name="m_{name}" file={quoteattr(s.file)} scale="{_fmt(s.scale)}"/>')
        elif s.kind == "mesh":
            assets.append(f'<mesh name="m_{name}" vertex="{_fmt(s.vertices)}"/>')
        elif s.kind in ("box", "cylinder"):
            assets.append(f'<mesh name="m_{name}" vertex="{_fmt(_hull_vertices(s))}"/>')
    return assets


def _shape_geom(shape: Shape, name: str) -> str:
    T = shape.T
    pose = f'pos="{_fmt(T[:3, 3])}" quat="{_fmt(frames.matrix_quat(T[:3, :3]))}"'
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


def _link_geom(name: str, end: np.ndarray, radius: float) -> str:
    if np.linalg.norm(end) < _COINCIDENT:
        return f'<geom name="{name}" type="sphere" size="{radius!r}"/>'
    return f'<geom name="{name}" type="capsule" fromto="0 0 0 {_fmt(end)}" size="{radius!r}"/>'


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
    return (f'<inertial pos="{_fmt(com)}" mass="{mass!r}" '
            f'fullinertia="{_fmt([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])}"/>')


def mjcf_body(robot: Robot, pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0), jaws_open: float | None = None,
              inertial: bool = False) -> str:
    """MJCF ``<body>`` tree of the robot (radians), for a ``<worldbody>`` whose
    ``<compiler angle="radian"/>`` is set.

    Args:
      robot: the arm.
      pos, quat: the base link's pose in the parent frame [m], ``(w, x, y, z)``.
      jaws_open: gap between the fingers [m] (default: the gripper's largest); ignored without
        a gripper.
      inertial: write the bodies' mass properties (a simulation needs them; collision
        queries do not).
    """
    chain = robot.chain
    T_joint = np.asarray(chain.T_base_joint0, dtype=np.float64)
    twists = np.asarray(chain.twists, dtype=np.float64)
    tool = np.asarray(chain.T_base_tool0, dtype=np.float64)
    n = robot.n_joints
    lines = [f'<body name="{base_body(robot)}" pos="{_fmt(pos)}" quat="{_fmt(quat)}">']
    if inertial and _inertial(robot, BASE):
        lines.append("  " + _inertial(robot, BASE))
    lines += ["  " + g for g in _body_geoms(robot, BASE, T_joint[0, :3, 3])]
    previous = np.eye(4)
    for i in range(n):
        pad = "  " * (i + 1)
        local = np.linalg.inv(previous) @ T_joint[i]
        R = T_joint[i, :3, :3]
        axis = R.T @ (twists[i, 3:] if chain.kinds[i] == REVOLUTE else twists[i, :3])
        lines.append(f'{pad}<body name="{robot.link_names[i]}" pos="{_fmt(local[:3, 3])}" '
                     f'quat="{_fmt(frames.matrix_quat(local[:3, :3]))}">')
        geoms = _body_geoms(robot, i, (np.linalg.inv(T_joint[i]) @ (T_joint[i + 1] if i + 1 < n else tool))[:3, 3])
        if inertial and _inertial(robot, i):
            lines.append(f"{pad}  " + _inertial(robot, i))
        elif not geoms:
            lines.append(f"{pad}  " + _NO_MASS)
        kind = "hinge" if chain.kinds[i] == REVOLUTE else "slide"
        lines.append(f'{pad}  <joint name="{robot.joint_names[i]}" type="{kind}" axis="{_fmt(axis)}" '
                     f'range="{float(chain.lower[i])!r} {float(chain.upper[i])!r}" limited="true"/>')
        lines += [f"{pad}  " + g for g in geoms]
        previous = T_joint[i]
    pad = "  " * (n + 1)
    T_link_tool = np.linalg.inv(T_joint[-1]) @ tool
    tool_quat = _fmt(frames.matrix_quat(T_link_tool[:3, :3]))
    lines.append(f'{pad}<site name="{TOOL_SITE}" pos="{_fmt(T_link_tool[:3, 3])}" quat="{tool_quat}" size="0.01"/>')
    g = robot.gripper
    if g is not None:
        gap = g.upper if jaws_open is None else jaws_open
        fx, fy, fz = g.finger_size
        for side, sign in (("left", 1.0), ("right", -1.0)):
            p = T_link_tool @ np.array([sign * (gap / 2.0 + fx / 2.0), 0.0, fz / 2.0, 1.0])
            lines.append(f'{pad}<geom name="geom_jaw_{side}" type="box" pos="{_fmt(p[:3])}" quat="{tool_quat}" '
                         f'size="{_fmt(np.array(g.finger_size) / 2)}"/>')
    for d in range(n, -1, -1):
        lines.append("  " * d + "</body>")
    return "\n".join(lines)


def robot_mjcf(robot: Robot, jaws_open: float | None = None, inertial: bool = False) -> str:
    """A complete MJCF model of the robot alone, its base link at the world origin, no gravity."""
    assets = "".join(f"\n    {a}" for a in mjcf_assets(robot))
    return (f'<mujoco model="{robot.name}">\n  <compiler angle="radian"/>\n  <option gravity="0 0 0"/>\n'
            + (f"  <asset>{assets}\n  </asset>\n" if assets else "") +
            f"  <worldbody>\n{mjcf_body(robot, jaws_open=jaws_open, inertial=inertial)}\n  </worldbody>\n</mujoco>\n")


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
