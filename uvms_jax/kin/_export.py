"""URDF export of any chain, and URDF/MJCF of the Reach Bravo 7 from its joint table."""

from __future__ import annotations

from typing import Sequence

import mujoco
import numpy as np

from uvms_jax import bravo7 as _b7
from uvms_jax.kin._chain import REVOLUTE, Chain, UrdfJoint
from uvms_jax.kin._lie import rpy_matrix
from uvms_jax.kin._models import BRAVO7_JAWS, BRAVO7_JOINTS, BRAVO7_TOOL_XYZ


def _fmt(values) -> str:
    return " ".join(f"{float(v):.10g}" for v in values)


def matrix_to_rpy(R: np.ndarray) -> np.ndarray:
    """URDF roll-pitch-yaw of a rotation (``R = Rz(yaw) Ry(pitch) Rx(roll)``), gimbal-lock safe."""
    R = np.asarray(R, dtype=np.float64)
    pitch = np.arcsin(np.clip(-R[2, 0], -1.0, 1.0))
    if abs(R[2, 0]) < 1.0 - 1e-9:
        return np.array([np.arctan2(R[2, 1], R[2, 2]), pitch, np.arctan2(R[1, 0], R[0, 0])])
    # Gimbal lock: only roll ± yaw is defined; put it all in yaw.
    return np.array([0.0, pitch, np.arctan2(-R[0, 1], R[1, 1])])


def _urdf_text(name: str, joints: Sequence[UrdfJoint], tool_xyz, tool_rpy, extra: str = "") -> str:
    links = ["base_link"] + [f"link_{j.name}" for j in joints]
    parts = [f'<?xml version="1.0"?>\n<robot name="{name}">']
    parts += [f'  <link name="{link}"/>' for link in links + ["tool"]]
    for parent, child, j in zip(links[:-1], links[1:], joints):
        parts.append(
            f'  <joint name="{j.name}" type="{j.kind}">\n'
            f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
            f'    <origin xyz="{_fmt(j.xyz)}" rpy="{_fmt(j.rpy)}"/>\n    <axis xyz="{_fmt(j.axis)}"/>\n'
            f'    <limit lower="{j.lower:.10g}" upper="{j.upper:.10g}" velocity="{j.velocity:.10g}" effort="{j.effort:.10g}"/>\n'
            "  </joint>"
        )
    parts.append(
        f'  <joint name="tool_joint" type="fixed">\n    <parent link="{links[-1]}"/>\n    <child link="tool"/>\n'
        f'    <origin xyz="{_fmt(tool_xyz)}" rpy="{_fmt(tool_rpy)}"/>\n  </joint>'
    )
    parts.append(extra)
    parts.append("</robot>\n")
    return "\n".join(p for p in parts if p)


def to_urdf(chain: Chain) -> str:
    """URDF of any chain: one link per joint, the joint frames at ``q = 0`` taken from
    ``chain.T_base_joint0``, and a fixed joint to a link named ``tool``."""
    frames = np.asarray(chain.T_base_joint0, dtype=np.float64)
    twists = np.asarray(chain.twists, dtype=np.float64)
    previous = np.eye(4)
    joints = []
    for i, kind in enumerate(chain.kinds):
        local = np.linalg.inv(previous) @ frames[i]
        direction = twists[i, 3:] if kind == REVOLUTE else twists[i, :3]
        joints.append(
            UrdfJoint(
                name=chain.joint_names[i],
                xyz=tuple(local[:3, 3]),
                rpy=tuple(matrix_to_rpy(local[:3, :3])),
                axis=tuple(frames[i, :3, :3].T @ direction),
                lower=float(chain.lower[i]),
                upper=float(chain.upper[i]),
                kind=kind,
                velocity=float(chain.velocity_limits[i]),
            )
        )
        previous = frames[i]
    tool = np.linalg.inv(previous) @ np.asarray(chain.T_base_tool0, dtype=np.float64)
    return _urdf_text(chain.name, joints, tool[:3, 3], matrix_to_rpy(tool[:3, :3]))


def bravo7_urdf() -> str:
    """URDF of the Reach Bravo 7 written from :mod:`uvms_jax.bravo7` (docs/theory.md §1.3), jaws included.

    The tool link ``tool`` is the jaws base frame; the jaws joint ``A`` hangs from it.
    """
    jaws = (
        '  <link name="jaws"/>\n'
        f'  <joint name="{BRAVO7_JAWS.name}" type="prismatic">\n    <parent link="tool"/>\n    <child link="jaws"/>\n'
        f'    <origin xyz="{_fmt(BRAVO7_JAWS.xyz)}" rpy="0 0 0"/>\n    <axis xyz="{_fmt(BRAVO7_JAWS.axis)}"/>\n'
        f'    <limit lower="{BRAVO7_JAWS.lower}" upper="{BRAVO7_JAWS.upper}" '
        f'velocity="{BRAVO7_JAWS.velocity:.10g}" effort="{BRAVO7_JAWS.effort:.10g}"/>\n'
        "  </joint>"
    )
    return _urdf_text(_b7.NAME, BRAVO7_JOINTS, BRAVO7_TOOL_XYZ, _b7.TOOL_RPY, extra=jaws)


def quat_wxyz(R: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` of a rotation matrix ``(3, 3)``, as MJCF writes it
    (MuJoCo's ``mju_mat2Quat``)."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=np.float64).reshape(9))
    return q


def bravo7_mjcf_body(
    pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0), link_radius: float = _b7.LINK_RADIUS, jaws_open: float = 0.03
) -> str:
    """MJCF ``<body>`` tree of the Bravo 7 (joints G…B, hinge, radians) with primitive shapes.

    Each link is a capsule from its joint origin to the next joint origin; the jaws are two
    fixed boxes ``jaws_open`` apart. A site named ``tool`` marks the jaws base frame. Insert
    the result into a ``<worldbody>`` whose ``<compiler angle="radian"/>`` is set.

    Args:
      pos, quat: mounting pose of the base link in the parent frame [m], (w, x, y, z).
      link_radius: capsule radius [m] (default: the Bravo 7's, links ≈ 0.09 m in diameter).
      jaws_open: gap between the jaw fingers [m].
    """
    r = link_radius
    lines = [f'<body name="base_link" pos="{_fmt(pos)}" quat="{_fmt(quat)}">']
    lines.append(f'  <geom name="geom_base" type="capsule" fromto="0 0 0 {_fmt(BRAVO7_JOINTS[0].xyz)}" size="{r}"/>')
    depth = 1
    for i, joint in enumerate(BRAVO7_JOINTS):
        pad = "  " * depth
        child = BRAVO7_JOINTS[i + 1].xyz if i + 1 < len(BRAVO7_JOINTS) else BRAVO7_TOOL_XYZ
        q = quat_wxyz(np.asarray(rpy_matrix(np.asarray(joint.rpy, dtype=np.float64))))
        lines.append(f'{pad}<body name="link_{joint.name}" pos="{_fmt(joint.xyz)}" quat="{_fmt(q)}">')
        lines.append(
            f'{pad}  <joint name="{joint.name}" type="hinge" axis="{_fmt(joint.axis)}" '
            f'range="{joint.lower} {joint.upper}" limited="true"/>'
        )
        lines.append(f'{pad}  <geom name="geom_{joint.name}" type="capsule" fromto="0 0 0 {_fmt(child)}" size="{r}"/>')
        depth += 1
    pad = "  " * depth
    tz = BRAVO7_TOOL_XYZ
    lines.append(f'{pad}<site name="tool" pos="{_fmt(tz)}" size="0.01"/>')
    finger = 'size="0.008 0.015 0.04"'
    for side, sign in (("left", 1.0), ("right", -1.0)):
        fx = sign * (jaws_open / 2.0 + 0.008)
        lines.append(
            f'{pad}<geom name="geom_jaw_{side}" type="box" pos="{_fmt((tz[0] + fx, tz[1], tz[2] + 0.04))}" {finger}/>'
        )
    for d in range(depth - 1, -1, -1):
        lines.append("  " * d + "</body>")
    return "\n".join(lines)


def bravo7_mjcf(link_radius: float = _b7.LINK_RADIUS, jaws_open: float = 0.03) -> str:
    """A complete MJCF model of the Bravo 7 alone, base link at the world origin."""
    body = bravo7_mjcf_body(link_radius=link_radius, jaws_open=jaws_open)
    return (
        '<mujoco model="bravo7">\n  <compiler angle="radian"/>\n  <option gravity="0 0 0"/>\n'
        f"  <worldbody>\n{body}\n  </worldbody>\n</mujoco>\n"
    )
