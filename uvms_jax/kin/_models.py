"""The three robots of the project (docs/theory.md §1): docking arm, 12-DOF UVMS, Reach Bravo 7."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from scipy.spatial.transform import Rotation

from uvms_jax import bravo7 as _b7
from uvms_jax import frames
from uvms_jax.kin._chain import (
    REVOLUTE,
    Chain,
    chain_from_urdf_joints,
    make_chain,
    revolute_twist,
    with_dtype,
)
from uvms_jax.kin._fk import kinematics
from uvms_jax.kin._vehicle import uvms

# Docking arm (docking paper, docs/theory.md §1.1).
DOCKING_ARM_LIMITS = (
    (-2.8, -2.35, -2.35, -4.6, -4.6, -2.6),
    (2.8, 2.35, 2.35, 4.6, 4.6, 2.6),
)


def docking_arm(l0: float = 0.1, l1: float = 0.4, l2: float = 0.4) -> Chain:
    """6R elbow arm with spherical wrist (Murray's elbow manipulator), stretched along +x of B.

    Axes ``z, y, y, z, y, x`` through ``(0,0,0)``, ``(0,0,l0)``, ``(l1,0,l0)`` and the wrist
    centre ``(l1+l2, 0, l0)``; the tool frame sits at the wrist centre, aligned with B at q = 0.
    Lengths in metres; the defaults are the paper's ([D11] §IV, tested against
    :data:`uvms_jax.papers.D11_ARM_LENGTHS`).
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

    :func:`~uvms_jax.kin.uvms` of the 6R elbow arm with its base MB ``y_mb`` ahead of the
    vehicle CoG (the base frame), stretched along +y: axes ``z, −x, −x, z, −x, y`` through MB
    ``(0, y_mb, l1)``, the elbow ``(0, y_mb + l2, l1)`` and the wrist centre
    ``(0, y_mb + l2 + l3, l1)``, where the tool sits, aligned with the vehicle frame at q = 0.
    Vehicle translations are unlimited in principle; the limits here (±10 m) only bound
    samplers. Lengths in metres.
    """
    return uvms(_uvms12_arm(l1, l2, l3), mount=_translation((0.0, y_mb, 0.0)), name="uvms12")


def _translation(p) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def _uvms12_arm(l1: float, l2: float, l3: float) -> Chain:
    """The dexterity paper's arm in its own base frame (MB below the shoulder, +y forward).

    Joint frames sit where the axes meet the links: the base, the shoulder, the elbow and
    (three times) the wrist centre.
    """
    x, y, z = np.eye(3)
    base, shoulder, elbow, wrist = (0.0, 0.0, 0.0), (0.0, 0.0, l1), (0.0, l2, l1), (0.0, l2 + l3, l1)
    axes = [(z, base), (-x, shoulder), (-x, elbow), (z, wrist), (-x, wrist), (y, wrist)]
    return make_chain(
        twists=np.stack([revolute_twist(w, q) for w, q in axes]),
        T_base_tool0=_translation(wrist),
        lower=DOCKING_ARM_LIMITS[0],
        upper=DOCKING_ARM_LIMITS[1],
        kinds=[REVOLUTE] * 6,
        joint_names=[f"theta_m{i}" for i in range(1, 7)],
        T_base_joint0=np.stack([_translation(q) for _, q in axes]),
        velocity_limits=[1.0] * 6,
        name="uvms12_arm",
    )


# The Reach Bravo 7 from its one home uvms_jax.bravo7 (docs/theory.md §1.3): its joints are
# URDF joints (uvms_jax.urdf.UrdfJoint) with a device id.
BRAVO7_JOINTS = _b7.ARM_JOINTS  # G, F, E, D, C, B
BRAVO7_TOOL_XYZ = _b7.TOOL_XYZ  # jaws base frame in link B's frame
BRAVO7_JAWS = _b7.JAWS


def bravo7() -> Chain:
    """Reach Bravo 7 arm, joints G, F, E, D, C, B (URDF angle convention); tool = jaws base frame."""
    return chain_from_urdf_joints(BRAVO7_JOINTS, _b7.TOOL_XYZ, _b7.TOOL_RPY, name=_b7.NAME)


def _dh_link_frames(q: np.ndarray) -> np.ndarray:
    """``(8, 4, 4)`` the manufacturer's link frames 0…7 in the URDF base frame, for URDF angles
    ``q (6,)`` [rad]: link 0's is the DH base frame, link k ≥ 1's the DH frame k-1 turned by its
    row's θ (origin on that joint's axis, turning with link k), before the row's d, a and α."""
    T = frames.pose(p=_b7.DH_BASE_XYZ)
    out = [T]
    for i, row in enumerate(_b7.DH_LINKS):
        theta = row.theta_offset + (_b7.DH_JOINT_SIGNS[i] * q[i] if i < len(_b7.DH_JOINT_SIGNS) else 0.0)
        turned = T @ frames.pose(frames.rot_z(theta))
        out.append(turned)
        T = turned @ frames.pose(Rotation.from_rotvec([row.alpha, 0.0, 0.0]).as_matrix(), (row.a, 0.0, row.d))
    return np.stack(out)


@functools.cache  # constants, computed once
def bravo7_inertials() -> tuple[_b7.Inertial, ...]:
    """The manufacturer's mass properties (:data:`uvms_jax.bravo7.DH_INERTIALS`) mapped into the
    URDF frames of :data:`uvms_jax.bravo7.INERTIAL_BODIES` (SI units): the source of the
    ``<inertial>`` elements of the shipped Bravo 7 description.

    Each manufacturer's link frame is fixed to its URDF body; the fixed transform is taken in
    the mid-range pose, which halves the pose-dependent spread. Its rotation is the same in every
    pose (quarter turns, and for link 2 the elbow offset angle θa); its offset holds to the few
    millimetres by which the two descriptions of the arm differ (tests/hw prove both). Inertia
    tensors are rotated, centres moved. Computed in float64 whatever the process default.
    """
    q_mid = np.array([0.5 * (j.lower + j.upper) for j in _b7.ARM_JOINTS])
    with jax.enable_x64(True):
        k = kinematics(with_dtype(bravo7(), jnp.float64), jnp.asarray(q_mid))
        urdf = np.concatenate([np.eye(4)[None], np.asarray(k.T_base_joint), np.asarray(k.T_base_tool)[None]])
    body_index = {"base": 0, **{j.name: i + 1 for i, j in enumerate(_b7.ARM_JOINTS)}, "tool": len(urdf) - 1}
    out = []
    for inertial, body, T_dh in zip(_b7.DH_INERTIALS, _b7.INERTIAL_BODIES, _dh_link_frames(q_mid)):
        X = np.linalg.inv(urdf[body_index[body]]) @ T_dh
        R, p = X[:3, :3], X[:3, 3]
        xx, yy, zz, xy, xz, yz = inertial.inertia
        I = R @ np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) @ R.T
        point = lambda v: tuple(float(c) for c in R @ v + p)
        out.append(_b7.Inertial(inertial.mass, point(inertial.com), tuple(float(I[i, j]) for i, j in _UPPER),
                                inertial.volume, point(inertial.cob)))
    return tuple(out)


_UPPER = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))  # (xx, yy, zz, xy, xz, yz) of a tensor
