"""Area manipulability measure M_a (docking paper eq. 1, SPEC §2)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jax import Array

from uvms_jax.indices._indices import manipulability_from_rows
import jax

from uvms_jax.kin import Chain, with_dtype
from uvms_jax.kin._fk import _kinematics_one
from uvms_jax.kin._scalar import geometry, jacobian_rows
from uvms_jax.kin._ik import _check_pose, elbow_branches, reaches
from uvms_jax.kin._lie import homogeneous, matmul


def control_points(center, size: float, n_per_side: int = 2) -> np.ndarray:
    """Control points on a square horizontal task area, ``(n_per_side², 3)`` [m].

    ``n_per_side = 2`` gives the four corners K, L, M, N of the paper; larger values give
    a regular grid including the corners (the paper itself asks for more points).
    """
    if n_per_side < 2:
        raise ValueError(f"n_per_side must be >= 2 (2 = the four corners), got {n_per_side}")
    if size <= 0:
        raise ValueError(f"task area size must be positive, got {size}")
    offsets = np.linspace(-size / 2.0, size / 2.0, n_per_side)
    gx, gy = np.meshgrid(offsets, offsets, indexing="ij")
    center = np.asarray(center, dtype=np.float64)
    return np.stack([center[0] + gx.ravel(), center[1] + gy.ravel(), np.full(gx.size, center[2])], axis=-1)


def approach_down(yaw) -> Array:
    """Tool orientation ``R_world_tool (..., 3, 3)`` with the approach axis (tool x) along
    −z of the world and the tool z axis along the heading ``yaw`` [rad] (SPEC §1.1 default)."""
    yaw = jnp.asarray(yaw)
    c, s = jnp.cos(yaw), jnp.sin(yaw)
    zero, one = jnp.zeros_like(yaw), jnp.ones_like(yaw)
    x = jnp.stack([zero, zero, -one], axis=-1)
    y = jnp.stack([-s, c, zero], axis=-1)
    z = jnp.stack([c, s, zero], axis=-1)
    return jnp.stack([x, y, z], axis=-1)


def _max_branch_w_one(chain: Chain, T: Array) -> Array:
    branches = elbow_branches(chain, T)  # (8, 6)
    T_reached = jax.vmap(_kinematics_one, in_axes=(None, 0))(chain, branches.q).T_base_tool
    valid = branches.valid & reaches(T, T_reached)
    w = manipulability_from_rows(jacobian_rows(geometry(chain), [branches.q[:, i] for i in range(6)]))
    return jnp.max(jnp.where(valid, w, 0.0), axis=-1)


@jax.jit
def _max_branch_w(chain: Chain, T: Array) -> Array:
    chain = with_dtype(chain, T.dtype)
    flat = T.reshape((-1, 4, 4))
    return jax.vmap(_max_branch_w_one, in_axes=(None, 0))(chain, flat).reshape(T.shape[:-2])


def max_branch_manipulability(chain: Chain, T_base_tool) -> Array:
    """``max`` of w over the valid closed-form IK branches of each target, 0 where none is valid.

    Args:
      chain: 6R elbow arm (see :func:`uvms_jax.kin.elbow_ik`).
      T_base_tool: ``(..., 4, 4)`` target tool poses in the arm base frame.

    Returns:
      ``(...)`` best manipulability (of the 6×6 geometric Jacobian).
    """
    return _max_branch_w(chain, _check_pose(T_base_tool))


def area_manipulability(chain: Chain, T_world_base, p_world_points, R_world_tool) -> Array:
    """``M_a = min over control points of (max over IK branches of w)`` (docking paper eq. 1).

    Args:
      chain: 6R elbow arm.
      T_world_base: ``(..., 4, 4)`` arm base poses (e.g. a GA population).
      p_world_points: ``(k, 3)`` control points [m].
      R_world_tool: demanded tool orientation, ``(3, 3)``, ``(k, 3, 3)`` per point, or
        ``(..., k, 3, 3)`` per base pose and point (e.g. a yaw that follows each candidate).

    Returns:
      ``(...)`` M_a; 0 for a base pose from which some control point has no valid branch.
    """
    T_world_base = jnp.asarray(T_world_base)
    points = jnp.asarray(p_world_points, dtype=T_world_base.dtype)
    if points.ndim != 2 or points.shape[-1] != 3:
        raise ValueError(f"p_world_points must have shape (k, 3), got {points.shape}")
    R = jnp.asarray(R_world_tool, dtype=T_world_base.dtype)
    R = jnp.broadcast_to(R, jnp.broadcast_shapes(R.shape, points.shape[:1] + (3, 3)))
    T_world_tool = homogeneous(R, jnp.broadcast_to(points, R.shape[:-1]))  # (..., k, 4, 4)
    R_wb, p_wb = T_world_base[..., :3, :3], T_world_base[..., :3, 3]
    R_bw = jnp.swapaxes(R_wb, -1, -2)
    T_base_world = homogeneous(R_bw, -jnp.sum(R_bw * p_wb[..., None, :], axis=-1))
    T_base_tool = matmul(T_base_world[..., None, :, :], T_world_tool)  # (..., k, 4, 4)
    return jnp.min(max_branch_manipulability(chain, T_base_tool), axis=-1)
