"""Rigid frames on the host, in NumPy: the one set of pose and rotation helpers that scenes,
robot models, the docking setup and the files use (traced JAX code has its own in
``uvms_jax.kin``: ``rpy_matrix``, ``homogeneous``).

Conventions: ``T`` is a ``(4, 4)`` homogeneous pose, ``R`` a ``(3, 3)`` rotation; roll-pitch-
yaw is URDF's, ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (fixed axes x, y, z); quaternions are MJCF's
``(w, x, y, z)``. Metres and radians.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["matrix_euler_xyz", "matrix_quat", "matrix_rpy", "pose", "quat_matrix", "rot_z", "rpy_matrix", "rpy_pose"]


def pose(R=None, p=(0.0, 0.0, 0.0)) -> np.ndarray:
    """``(4, 4)`` pose of rotation ``R (3, 3)`` (default: none) and position ``p (3,)`` [m]."""
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    T[:3, 3] = p
    return T


def rpy_matrix(rpy: Sequence[float]) -> np.ndarray:
    """Rotation ``(3, 3)`` of URDF roll-pitch-yaw ``(3,)`` [rad]: ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    return Rotation.from_euler("xyz", np.asarray(rpy, dtype=float)).as_matrix()


def rpy_pose(xyz: Sequence[float], rpy: Sequence[float]) -> np.ndarray:
    """``(4, 4)`` pose from a position [m] and URDF roll-pitch-yaw [rad]."""
    return pose(rpy_matrix(rpy), xyz)


def rot_z(yaw: float) -> np.ndarray:
    """Rotation ``(3, 3)`` about z by ``yaw`` [rad]."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def matrix_rpy(R: np.ndarray) -> np.ndarray:
    """URDF roll-pitch-yaw ``(3,)`` of a rotation ``(3, 3)``; at gimbal lock (pitch ±π/2), where
    only roll ± yaw is defined, all of it goes into yaw."""
    R = np.asarray(R, dtype=np.float64)
    pitch = np.arcsin(np.clip(-R[2, 0], -1.0, 1.0))
    if abs(R[2, 0]) < 1.0 - 1e-9:
        return np.array([np.arctan2(R[2, 1], R[2, 2]), pitch, np.arctan2(R[1, 0], R[0, 0])])
    return np.array([0.0, pitch, np.arctan2(-R[0, 1], R[1, 1])])


def matrix_euler_xyz(R: np.ndarray) -> np.ndarray:
    """Angles ``(a, b, c)`` [rad] with ``R = Rx(a) Ry(b) Rz(c)`` (intrinsic x, y, z): the
    vehicle's roll, pitch and yaw joints of :func:`uvms_jax.kin.uvms`."""
    return Rotation.from_matrix(np.asarray(R, dtype=np.float64)).as_euler("XYZ")


def matrix_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` of a rotation ``(3, 3)``, as MuJoCo writes it (``mju_mat2Quat``)."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=np.float64).reshape(9))
    return q


def quat_matrix(wxyz: Sequence[float] | str) -> np.ndarray:
    """Rotation ``(3, 3)`` of a quaternion ``(w, x, y, z)`` (or an MJCF ``quat`` attribute)."""
    q = np.asarray(wxyz.split() if isinstance(wxyz, str) else wxyz, dtype=np.float64)
    R = np.empty(9)
    mujoco.mju_quat2Mat(R, q / np.linalg.norm(q))
    return R.reshape(3, 3)
