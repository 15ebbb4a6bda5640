"""Any arm on a vehicle: the vehicle's degrees of freedom prepended to the arm's joints."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from uvms_jax.kin._chain import Chain, make_chain, prismatic_twist, revolute_twist
from uvms_jax.urdf import PRISMATIC, REVOLUTE

# The dexterity paper's 6-DOF vehicle (docs/theory.md §1.2), in the one order the product of
# exponentials is taken: translations, then XYZ Euler rotations through the vehicle origin.
VEHICLE_DOFS = ("x", "y", "z", "roll", "pitch", "yaw")
_JOINT_NAME = {"x": "x", "y": "y", "z": "z", "roll": "theta_x", "pitch": "theta_y", "yaw": "theta_z"}
_AXIS = {"x": 0, "y": 1, "z": 2, "roll": 0, "pitch": 1, "yaw": 2}


def _check_mount(mount) -> np.ndarray:
    T = np.eye(4) if mount is None else np.asarray(mount, dtype=np.float64)
    if T.shape != (4, 4):
        raise ValueError(f"mount must be a (4, 4) pose of the arm base in the vehicle frame, got shape {T.shape}")
    if not np.all(np.isfinite(T)):
        raise ValueError("mount contains NaN or infinite values")
    R = T[:3, :3]
    if not np.allclose(T[3], [0.0, 0.0, 0.0, 1.0], atol=1e-9):
        raise ValueError(f"mount's last row must be [0, 0, 0, 1], got {T[3]}")
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0.0:
        raise ValueError("mount's rotation block is not a rotation matrix (RᵀR = I, det R = +1)")
    return T


def _check_dofs(vehicle_dofs: Sequence[str]) -> tuple[str, ...]:
    dofs = tuple(vehicle_dofs)
    unknown = [d for d in dofs if d not in VEHICLE_DOFS]
    if unknown:
        raise ValueError(f"unknown vehicle DOFs {unknown}; choose from {VEHICLE_DOFS}")
    if len(set(dofs)) != len(dofs):
        raise ValueError(f"vehicle DOFs repeated: {dofs}")
    ordered = tuple(d for d in VEHICLE_DOFS if d in dofs)
    if dofs != ordered:
        # The order is the order of the exponentials: a different one would silently be a
        # different Euler convention.
        raise ValueError(f"vehicle DOFs must be given in the order {VEHICLE_DOFS}, got {dofs} (use {ordered})")
    return dofs


def adjoint_twists(T: np.ndarray, twists: np.ndarray) -> np.ndarray:
    """Twists ``(n, 6)`` ``[v, ω]`` of frame b re-expressed in frame a, for ``T = T_a_b``:
    ``ω' = R ω``, ``v' = R v + p × (R ω)`` (Murray, Li & Sastry, eq. 2.58)."""
    R, p = T[:3, :3], T[:3, 3]
    w = twists[:, 3:] @ R.T
    v = twists[:, :3] @ R.T + np.cross(p, w)
    return np.concatenate([v, w], axis=1)


def uvms(
    arm: Chain,
    mount=None,
    vehicle_dofs: Sequence[str] = VEHICLE_DOFS,
    translation_limit: float = 10.0,
    name: str | None = None,
    translation_speed: float = 1.0,
    rotation_speed: float = 0.5,
) -> Chain:
    """The arm on a free-floating vehicle, as one chain: vehicle DOFs first, then the arm.

    The base frame of the result is the vehicle frame at ``q = 0`` (the inertial frame the
    vehicle starts in). Translations are prismatic joints along that frame's x, y, z axes;
    rotations are revolute joints about x, y, z through the vehicle origin, taken in that order
    after the translations, so the vehicle pose is ``Trans(x, y, z) · Rx(roll) Ry(pitch) Rz(yaw)``
    (XYZ Euler angles, the dexterity paper's 6-DOF vehicle, docs/theory.md §1.2). Leaving out
    DOFs (e.g. roll and pitch of a passively stable vehicle) fixes them at 0.

    Args:
      arm: the manipulator, its base frame at the vehicle origin unless ``mount`` moves it.
      mount: ``(4, 4)`` pose ``T_vehicle_armbase`` of the arm's base frame in the vehicle
        frame [m]; identity if None.
      vehicle_dofs: ordered subset of ``("x", "y", "z", "roll", "pitch", "yaw")``. The joints
        are named ``x, y, z, theta_x, theta_y, theta_z``.
      translation_limit: the vehicle translations are limited to ``±translation_limit`` [m]
        (only to bound samplers; the rotations to ``±π`` rad).
      name: model name; default ``"<arm.name>_uvms"``.
      translation_speed, rotation_speed: vehicle velocity limits [m/s], [rad/s].

    Returns:
      A :class:`Chain` with ``len(vehicle_dofs) + arm.n_joints`` joints and the arm's tool.

    Raises:
      ValueError: on an unknown, repeated or reordered DOF, a mount that is not a rigid
        transform, a non-positive limit, or an arm joint named like a vehicle joint.
    """
    dofs = _check_dofs(vehicle_dofs)
    T_mount = _check_mount(mount)
    if not translation_limit > 0.0:
        raise ValueError(f"translation_limit must be positive, got {translation_limit}")
    names = [_JOINT_NAME[d] for d in dofs]
    clash = sorted(set(names) & set(arm.joint_names))
    if clash:
        raise ValueError(f"arm joints {clash} are named like vehicle joints; rename them in the arm")
    axes = np.eye(3)
    kinds = [PRISMATIC if d in ("x", "y", "z") else REVOLUTE for d in dofs]
    vehicle_twists = [
        prismatic_twist(axes[_AXIS[d]]) if k == PRISMATIC else revolute_twist(axes[_AXIS[d]], np.zeros(3))
        for d, k in zip(dofs, kinds)
    ]
    limits = [translation_limit if k == PRISMATIC else np.pi for k in kinds]
    speeds = [translation_speed if k == PRISMATIC else rotation_speed for k in kinds]
    arm_twists = adjoint_twists(T_mount, np.asarray(arm.twists, dtype=np.float64))
    twists = np.concatenate([np.reshape(vehicle_twists, (-1, 6)), arm_twists])
    # Every vehicle joint frame is the vehicle frame itself at q = 0.
    frames = np.concatenate([np.tile(np.eye(4), (len(dofs), 1, 1)), T_mount @ np.asarray(arm.T_base_joint0, np.float64)])
    return make_chain(
        twists=twists,
        T_base_tool0=T_mount @ np.asarray(arm.T_base_tool0, dtype=np.float64),
        lower=[-x for x in limits] + list(np.asarray(arm.lower, dtype=np.float64)),
        upper=limits + list(np.asarray(arm.upper, dtype=np.float64)),
        kinds=kinds + list(arm.kinds),
        joint_names=names + list(arm.joint_names),
        T_base_joint0=frames,
        velocity_limits=speeds + list(np.asarray(arm.velocity_limits, dtype=np.float64)),
        name=f"{arm.name}_uvms" if name is None else name,
    )
