"""The three robots of the project (docs/theory.md §1): docking arm, 12-DOF UVMS, Reach Bravo 7."""

from __future__ import annotations

import numpy as np

from uvms_jax import bravo7 as _b7
from uvms_jax.kin._chain import (
    PRISMATIC,
    REVOLUTE,
    Chain,
    UrdfJoint,
    chain_from_urdf_joints,
    make_chain,
    prismatic_twist,
    revolute_twist,
)

# Docking arm (docking paper, docs/theory.md §1.1).
DOCKING_ARM_LIMITS = (
    (-2.8, -2.35, -2.35, -4.6, -4.6, -2.6),
    (2.8, 2.35, 2.35, 4.6, 4.6, 2.6),
)


def docking_arm(l0: float = 0.1, l1: float = 0.4, l2: float = 0.4) -> Chain:
    """6R elbow arm with spherical wrist (Murray's elbow manipulator), stretched along +x of B.

    Axes ``z, y, y, z, y, x`` through ``(0,0,0)``, ``(0,0,l0)``, ``(l1,0,l0)`` and the wrist
    centre ``(l1+l2, 0, l0)``; the tool frame sits at the wrist centre, aligned with B at q = 0.
    Lengths in metres.
    """
    x, y, z = np.eye(3)
    shoulder, elbow, wrist = (0.0, 0.0, l0), (l1, 0.0, l0), (l1 + l2, 0.0, l0)
    axes = [(z, (0, 0, 0)), (y, shoulder), (y, elbow), (z, wrist), (y, wrist), (x, wrist)]
    tool = np.eye(4)
    tool[:3, 3] = wrist
    return make_chain(
        twists=np.stack([revolute_twist(w, q) for w, q in axes]),
        T_base_tool0=tool,
        lower=DOCKING_ARM_LIMITS[0],
        upper=DOCKING_ARM_LIMITS[1],
        kinds=[REVOLUTE] * 6,
        joint_names=[f"theta{i}" for i in range(1, 7)],
        velocity_limits=[1.0] * 6,
        name="docking_arm",
    )


def uvms12(y_mb: float = 0.75, l1: float = 0.1, l2: float = 0.4, l3: float = 0.4) -> Chain:
    """12-DOF UVMS of the dexterity paper (docs/theory.md §1.2): vehicle x, y, z, θx, θy, θz + 6R arm.

    Prismatic x, y, z and XYZ-Euler rotations through the vehicle CoG (the base frame), then
    the arm with base MB ``y_mb`` ahead of the CoG, stretched along +y. Tool at ``q4``.
    Vehicle translations are unlimited in principle; the limits here (±10 m) only bound
    samplers. Lengths in metres.
    """
    x, y, z = np.eye(3)
    q2, q3, q4 = (0.0, y_mb, l1), (0.0, y_mb + l2, l1), (0.0, y_mb + l2 + l3, l1)
    arm = [(z, q2), (-x, q2), (-x, q3), (z, q4), (-x, q4), (y, q4)]
    twists = [prismatic_twist(x), prismatic_twist(y), prismatic_twist(z)]
    twists += [revolute_twist(w, (0, 0, 0)) for w in (x, y, z)]
    twists += [revolute_twist(w, q) for w, q in arm]
    tool = np.eye(4)
    tool[:3, 3] = q4
    big = 10.0
    lower = [-big] * 3 + [-np.pi] * 3 + list(DOCKING_ARM_LIMITS[0])
    upper = [big] * 3 + [np.pi] * 3 + list(DOCKING_ARM_LIMITS[1])
    return make_chain(
        twists=np.stack(twists),
        T_base_tool0=tool,
        lower=lower,
        upper=upper,
        kinds=[PRISMATIC] * 3 + [REVOLUTE] * 9,
        joint_names=["x", "y", "z", "theta_x", "theta_y", "theta_z"] + [f"theta_m{i}" for i in range(1, 7)],
        velocity_limits=[1.0] * 3 + [0.5] * 3 + [1.0] * 6,
        name="uvms12",
    )


# The Reach Bravo 7 in kin's URDF form, from its one home uvms_jax.bravo7 (docs/theory.md §1.3).
def _urdf_joint(j: _b7.Joint) -> UrdfJoint:
    return UrdfJoint(j.name, j.xyz, j.rpy, j.axis, j.lower, j.upper, kind=j.kind, velocity=j.velocity, effort=j.effort)


BRAVO7_JOINTS = tuple(_urdf_joint(j) for j in _b7.ARM_JOINTS)  # G, F, E, D, C, B
BRAVO7_TOOL_XYZ = _b7.TOOL_XYZ  # jaws base frame in link B's frame
BRAVO7_JAWS = _urdf_joint(_b7.JAWS)


def bravo7() -> Chain:
    """Reach Bravo 7 arm, joints G, F, E, D, C, B (URDF angle convention); tool = jaws base frame."""
    return chain_from_urdf_joints(BRAVO7_JOINTS, _b7.TOOL_XYZ, _b7.TOOL_RPY, name=_b7.NAME)
