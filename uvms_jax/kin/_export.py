"""URDF export of any chain, and the URDF of the Reach Bravo 7 from its joint table."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from uvms_jax import bravo7 as _b7
from uvms_jax import frames
from uvms_jax.kin._chain import Chain
from uvms_jax.kin._models import BRAVO7_JAWS, BRAVO7_JOINTS, BRAVO7_TOOL_XYZ
from uvms_jax.text import numbers
from uvms_jax.urdf import REVOLUTE, UrdfJoint


def _urdf_text(name: str, joints: Sequence[UrdfJoint], tool_xyz, tool_rpy, extra: str = "") -> str:
    links = ["base_link"] + [f"link_{j.name}" for j in joints]
    parts = [f'<?xml version="1.0"?>\n<robot name="{name}">']
    parts += [f'  <link name="{link}"/>' for link in links + ["tool"]]
    for parent, child, j in zip(links[:-1], links[1:], joints):
        parts.append(
            f'  <joint name="{j.name}" type="{j.kind}">\n'
            f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
            f'    <origin xyz="{numbers(j.xyz)}" rpy="{numbers(j.rpy)}"/>\n    <axis xyz="{numbers(j.axis)}"/>\n'
            f'    <limit lower="{j.lower:.10g}" upper="{j.upper:.10g}" velocity="{j.velocity:.10g}" effort="{j.effort:.10g}"/>\n'
            "  </joint>"
        )
    parts.append(
        f'  <joint name="tool_joint" type="fixed">\n    <parent link="{links[-1]}"/>\n    <child link="tool"/>\n'
        f'    <origin xyz="{numbers(tool_xyz)}" rpy="{numbers(tool_rpy)}"/>\n  </joint>'
    )
    parts.append(extra)
    parts.append("</robot>\n")
    return "\n".join(p for p in parts if p)


def to_urdf(chain: Chain) -> str:
    """URDF of any chain: one link per joint, the joint frames at ``q = 0`` taken from
    ``chain.T_base_joint0``, and a fixed joint to a link named ``tool``."""
    T_joint = np.asarray(chain.T_base_joint0, dtype=np.float64)
    twists = np.asarray(chain.twists, dtype=np.float64)
    previous = np.eye(4)
    joints = []
    for i, kind in enumerate(chain.kinds):
        local = np.linalg.inv(previous) @ T_joint[i]
        direction = twists[i, 3:] if kind == REVOLUTE else twists[i, :3]
        joints.append(
            UrdfJoint(
                name=chain.joint_names[i],
                xyz=tuple(local[:3, 3]),
                rpy=tuple(frames.matrix_rpy(local[:3, :3])),
                axis=tuple(T_joint[i, :3, :3].T @ direction),
                lower=float(chain.lower[i]),
                upper=float(chain.upper[i]),
                kind=kind,
                velocity=float(chain.velocity_limits[i]),
            )
        )
        previous = T_joint[i]
    tool = np.linalg.inv(previous) @ np.asarray(chain.T_base_tool0, dtype=np.float64)
    return _urdf_text(chain.name, joints, tool[:3, 3], frames.matrix_rpy(tool[:3, :3]))


def bravo7_urdf() -> str:
    """URDF of the Reach Bravo 7 written from :mod:`uvms_jax.bravo7` (docs/theory.md §1.3), jaws included.

    The tool link ``tool`` is the jaws base frame; the jaws joint ``A`` hangs from it.
    """
    jaws = (
        '  <link name="jaws"/>\n'
        f'  <joint name="{BRAVO7_JAWS.name}" type="prismatic">\n    <parent link="tool"/>\n    <child link="jaws"/>\n'
        f'    <origin xyz="{numbers(BRAVO7_JAWS.xyz)}" rpy="0 0 0"/>\n    <axis xyz="{numbers(BRAVO7_JAWS.axis)}"/>\n'
        f'    <limit lower="{BRAVO7_JAWS.lower}" upper="{BRAVO7_JAWS.upper}" '
        f'velocity="{BRAVO7_JAWS.velocity:.10g}" effort="{BRAVO7_JAWS.effort:.10g}"/>\n'
        "  </joint>"
    )
    return _urdf_text(_b7.NAME, BRAVO7_JOINTS, BRAVO7_TOOL_XYZ, _b7.TOOL_RPY, extra=jaws)
