"""Area manipulability measure M_a (docking paper eq. 1, docs/theory.md §2).

``M_a = min over control points of (max over valid IK branches of w)``: the arm base must
reach every point of a task area, and the worst point with its best branch scores it. The
inner ``max`` alone is the ``w_max`` of the docking paper's eq. 16.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from uvms_jax import kin
from uvms_jax.indices._indices import manipulability_from_rows


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
    −z of the world and the tool z axis along the heading ``yaw (...)`` [rad]
    (the docking arm's default, docs/theory.md §1.1)."""
    yaw = jnp.asarray(yaw)
    c, s = jnp.cos(yaw), jnp.sin(yaw)
    zero, one = jnp.zeros_like(yaw), jnp.ones_like(yaw)
    x = jnp.stack([zero, zero, -one], axis=-1)
    y = jnp.stack([-s, c, zero], axis=-1)
    z = jnp.stack([c, s, zero], axis=-1)
    return jnp.stack([x, y, z], axis=-1)


@jax.jit
def _tool_targets(T_world_base: Array, p_world_points: Array, R_world_tool: Array) -> Array:
    R_bw = jnp.swapaxes(T_world_base[..., :3, :3], -1, -2)[..., None, :, :]  # (..., 1, 3, 3)
    p_wb = T_world_base[..., :3, 3]
    hi = jax.lax.Precision.HIGHEST  # full float32 products on GPUs too (TF32 breaks the IK check)
    R_bt = jnp.einsum("...ij,...jk->...ik", R_bw, R_world_tool, precision=hi)  # (..., 1 or k, 3, 3)
    p_bt = jnp.einsum("...ij,...j->...i", R_bw, p_world_points - p_wb[..., None, :], precision=hi)  # (..., k, 3)
    R_bt = jnp.broadcast_to(R_bt, p_bt.shape + (3,))
    top = jnp.concatenate([R_bt, p_bt[..., None]], axis=-1)
    bottom = jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0], dtype=p_bt.dtype), p_bt.shape[:-1] + (1, 4))
    return jnp.concatenate([top, bottom], axis=-2)


def tool_targets(T_world_base, p_world_points, R_world_tool) -> Array:
    """Tool targets ``T_base_tool (..., k, 4, 4)`` at the control points, in the arm base frame.

    Args:
      T_world_base: ``(..., 4, 4)`` arm base poses in the world [m].
      p_world_points: ``(k, 3)`` control points in the world [m].
      R_world_tool: demanded tool orientation in the world: ``(3, 3)`` for all, ``(k, 3, 3)``
        per point, or ``(..., 1, 3, 3)`` / ``(..., k, 3, 3)`` per base pose (and point).
    """
    T_world_base = jnp.asarray(T_world_base)
    if T_world_base.ndim < 2 or T_world_base.shape[-2:] != (4, 4):
        raise ValueError(f"T_world_base must have shape (..., 4, 4), got {T_world_base.shape}")
    points = jnp.asarray(p_world_points, dtype=T_world_base.dtype)
    if points.ndim != 2 or points.shape[-1] != 3:
        raise ValueError(f"p_world_points must have shape (k, 3), got {points.shape}")
    R = jnp.asarray(R_world_tool, dtype=T_world_base.dtype)
    if R.ndim < 2 or R.shape[-2:] != (3, 3) or (R.ndim > 2 and R.shape[-3] not in (1, points.shape[0])):
        raise ValueError(f"R_world_tool must have shape (3, 3), (k, 3, 3) or (..., k, 3, 3), got {R.shape}")
    return _tool_targets(T_world_base, points, R)


@jax.jit
def _max_branch_w(chain: kin.Chain, T: Array) -> Array:
    """``(...)`` best w over the valid closed-form branches of targets ``T (..., 4, 4)``, on
    scalars: the IK fuses into one loop, then each branch's FK, Jacobian and w into another
    (no Jacobian is ever stored)."""
    chain = kin.with_dtype(chain, T.dtype)
    batch = T.shape[:-2]
    R_t, p_t = [[T[..., i, j] for j in range(3)] for i in range(3)], [T[..., i, 3] for i in range(3)]
    q, ok = kin.elbow_branch_scalars(chain, R_t, p_t)
    # The branches one after another (a scan), not unrolled: eight copies of the FK and the
    # Jacobian in one expression made the GPU compiler take over a minute.
    q = jnp.concatenate([jnp.broadcast_to(x, (1,) + batch) for q_b in q for x in q_b]).reshape((8, 6) + batch)

    def branch(best, x):
        q_b, ok_b = list(x[0]), x[1]
        # The branch's angles are finite even where it does not exist (elbow_branch_scalars), so
        # w and its gradient stay finite; the checks only mask the result.
        R, p, rows = kin.pose_and_jacobian_rows(chain, q_b)
        valid = ok_b & kin.reaches_scalars(R_t, p_t, R, p, T.dtype)
        return jnp.maximum(best, jnp.where(valid, manipulability_from_rows(rows), 0.0)), None

    best, _ = jax.lax.scan(branch, jnp.zeros(batch, T.dtype), (q, jnp.stack(ok)))
    return best


# Eager calls pad the flat batch of targets to a bucket, so that populations, grids and maps
# of different sizes reuse a few compiled kernels (compiling the IK is the slow part).
MIN_TARGET_BUCKET = 512


def bucket_size(n: int) -> int:
    """Padded length for ``n`` eager IK targets: the next power of two, at least 512."""
    return max(MIN_TARGET_BUCKET, 1 << max(0, int(n) - 1).bit_length())


def max_branch_manipulability(chain: kin.Chain, T_base_tool) -> Array:
    """``max`` of w over the valid closed-form IK branches of each target, 0 where none is
    valid (``w_max`` of the docking paper's eq. 16).

    Args:
      chain: 6R elbow arm (see :func:`uvms_jax.kin.elbow_ik`).
      T_base_tool: ``(..., 4, 4)`` target tool poses in the arm base frame [m].

    Returns:
      ``(...)`` best manipulability (of the 6×6 geometric Jacobian).
    """
    T = jnp.asarray(T_base_tool)
    if T.ndim < 2 or T.shape[-2:] != (4, 4):
        raise ValueError(f"target pose must have shape (..., 4, 4), got {T.shape}")
    if not jnp.issubdtype(T.dtype, jnp.floating):
        T = T.astype(jnp.float32)
    if isinstance(T, jax.core.Tracer):
        return _max_branch_w(chain, T)
    if bool(jnp.isnan(T).any()):
        raise ValueError("target pose contains NaN")
    flat = T.reshape((-1, 4, 4))
    n = flat.shape[0]
    padded = jnp.concatenate([flat, jnp.broadcast_to(flat[:1], (bucket_size(n) - n, 4, 4))], axis=0)
    return _max_branch_w(chain, padded)[:n].reshape(T.shape[:-2])


def area_manipulability(chain: kin.Chain, T_world_base, p_world_points, R_world_tool) -> Array:
    """``M_a = min over control points of (max over IK branches of w)`` (docking paper eq. 1).

    Args:
      chain: 6R elbow arm.
      T_world_base: ``(..., 4, 4)`` arm base poses in the world (e.g. a GA population) [m].
      p_world_points: ``(k, 3)`` control points in the world [m].
      R_world_tool: demanded tool orientation, see :func:`tool_targets`.

    Returns:
      ``(...)`` M_a; 0 for a base pose from which some control point has no valid branch.
    """
    w_max = max_branch_manipulability(chain, tool_targets(T_world_base, p_world_points, R_world_tool))
    return jnp.min(w_max, axis=-1)
