"""Small SE(3) helpers on trailing axes; every function broadcasts over leading axes.

Twists are ordered ``[v, ω]`` (linear part first), as in Murray, Li & Sastry.
All small matrix products go through :func:`matmul` / :func:`matvec`, so the lowering of
tiny batched products is chosen in one place.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import Array


def matmul(a: Array, b: Array) -> Array:
    """Product of small matrices ``(..., m, k) @ (..., k, n)``, broadcasting leading axes.

    Full float32 precision: GPUs default to TF32 products (~1e-3 relative), far too coarse
    for kinematics (it made every IK residual check fail on an H100).
    """
    return jnp.matmul(a, b, precision=jax.lax.Precision.HIGHEST)


def matvec(a: Array, x: Array) -> Array:
    """``(..., m, k) @ (..., k)``, broadcasting leading axes."""
    return matmul(a, x[..., None])[..., 0]


def skew(w: Array) -> Array:
    """``(..., 3)`` → ``(..., 3, 3)`` cross-product matrix, ``skew(a) @ b = a × b``."""
    zero = jnp.zeros_like(w[..., 0])
    wx, wy, wz = w[..., 0], w[..., 1], w[..., 2]
    return jnp.stack(
        [
            jnp.stack([zero, -wz, wy], axis=-1),
            jnp.stack([wz, zero, -wx], axis=-1),
            jnp.stack([-wy, wx, zero], axis=-1),
        ],
        axis=-2,
    )


def exp_twist(twist: Array, theta: Array) -> tuple[Array, Array]:
    """Exponential ``exp(ξ̂ θ)`` of a unit twist, as rotation and translation.

    Args:
      twist: ``(..., 6)`` ``[v, ω]`` with ``|ω| = 1`` (revolute) or ``ω = 0, |v| = 1``
        (prismatic).
      theta: ``(...)`` joint value [rad or m].

    Returns:
      ``R (..., 3, 3)``, ``p (..., 3)``. One formula covers both joint kinds: with ω = 0
      it reduces to ``R = I, p = v θ`` (Murray et al. eq. 2.36).
    """
    v, w = twist[..., :3], twist[..., 3:]
    s, c = jnp.sin(theta)[..., None, None], jnp.cos(theta)[..., None, None]
    W = skew(w)
    W2 = matmul(W, W)
    eye = jnp.eye(3, dtype=W.dtype)
    R = eye + s * W + (1.0 - c) * W2
    th = theta[..., None, None]
    V = eye * th + (1.0 - c) * W + (th - s) * W2
    return R, matvec(V, v)


def adjoint_twist(R: Array, p: Array, twist: Array) -> Array:
    """``Ad_g ξ`` for ``g = (R, p)``: ``[R v + p × R ω, R ω]``; shapes ``(...,3,3)``, ``(...,3)``, ``(...,6)``."""
    Rw = matvec(R, twist[..., 3:])
    return jnp.concatenate([matvec(R, twist[..., :3]) + jnp.cross(p, Rw), Rw], axis=-1)


def homogeneous(R: Array, p: Array) -> Array:
    """``(..., 3, 3)``, ``(..., 3)`` → ``(..., 4, 4)`` homogeneous transform."""
    top = jnp.concatenate([R, p[..., None]], axis=-1)
    bottom = jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0], dtype=R.dtype), top.shape[:-2] + (1, 4))
    return jnp.concatenate([top, bottom], axis=-2)


def rpy_matrix(rpy) -> Array:
    """URDF roll-pitch-yaw ``(..., 3)`` [rad] → ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    rpy = jnp.asarray(rpy)
    z = jnp.zeros(3, dtype=rpy.dtype)
    one = jnp.ones((), dtype=rpy.dtype)

    def axis_rot(axis: int, angle: Array) -> Array:
        w = z.at[axis].set(one)
        R, _ = exp_twist(jnp.concatenate([z, w]), angle)
        return R

    return matmul(matmul(axis_rot(2, rpy[..., 2]), axis_rot(1, rpy[..., 1])), axis_rot(0, rpy[..., 0]))


def rotation_log(R: Array) -> Array:
    """Axis-angle vector ``(..., 3)`` of a rotation ``(..., 3, 3)``; safe at θ = 0 and near π."""
    cos = jnp.clip((jnp.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    vee = jnp.stack(
        [R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], axis=-1
    )
    sin = 0.5 * jnp.linalg.norm(vee, axis=-1)
    theta = jnp.arctan2(sin, cos)
    # Near θ = 0 the factor θ / (2 sin θ) → 1/2; the double where keeps gradients finite.
    small = sin < 1e-6
    safe_sin = jnp.where(small, 1.0, sin)
    scale = jnp.where(small, 0.5, theta / (2.0 * safe_sin))
    axis_angle = scale[..., None] * vee
    # Near θ = π the antisymmetric part vanishes; recover the axis from the symmetric part.
    # There (R + Rᵀ)/2 − cos·I = (1 − cos) k kᵀ: take its largest column as the axis k.
    B = (R + jnp.swapaxes(R, -1, -2)) / 2.0 - cos[..., None, None] * jnp.eye(3, dtype=R.dtype)
    pick = jax.nn.one_hot(jnp.argmax(jnp.diagonal(B, axis1=-2, axis2=-1), axis=-1), 3, dtype=R.dtype)
    col = matvec(B, pick)
    axis_pi = col / jnp.maximum(jnp.linalg.norm(col, axis=-1, keepdims=True), 1e-12)
    # Sign of the axis: agree with the (small) antisymmetric part where it still carries one.
    axis_pi = axis_pi * jnp.where(jnp.sum(axis_pi * vee, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    near_pi = cos < -0.99
    return jnp.where(near_pi[..., None], theta[..., None] * axis_pi, axis_angle)


def pose_error(T_target: Array, T: Array) -> Array:
    """6-vector ``[p_target − p, log(R_target Rᵀ)]`` (world-frame position and orientation error)."""
    dp = T_target[..., :3, 3] - T[..., :3, 3]
    dR = matmul(T_target[..., :3, :3], jnp.swapaxes(T[..., :3, :3], -1, -2))
    return jnp.concatenate([dp, rotation_log(dR)], axis=-1)
