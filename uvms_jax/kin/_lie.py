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


def cross3(a, b) -> list:
    """``a × b`` of two 3-sequences of scalars (floats or arrays of one batch shape)."""
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot3(a, b):
    """``a · b`` of two 3-sequences of scalars."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def exp_scalars(twist, theta) -> tuple[list, list]:
    """``exp(ξ̂ θ)`` on scalars: the one exponential of the package (Murray eq. 2.14, 2.36).

    With ``W = ω̂`` and ``W² = ωωᵀ − |ω|² I``:
    ``R = I + sin θ W + (1 − cos θ) W²``,
    ``p = θ v + (1 − cos θ)(ω × v) + (θ − sin θ)(ω(ω·v) − |ω|² v)``.
    One formula covers both joint kinds: with ω = 0 it reduces to ``R = I, p = v θ``.

    Args:
      twist: 6 scalars ``[v, ω]`` (Python floats or arrays), ``|ω| = 1`` (revolute) or
        ``ω = 0, |v| = 1`` (prismatic).
      theta: joint value [rad or m], an array of the batch shape.

    Returns:
      ``R`` as 3 rows of 3 scalars and ``p`` as 3 scalars, each broadcast over ``theta``.
    """
    v, w = twist[:3], twist[3:]
    s, c = jnp.sin(theta), jnp.cos(theta)
    C = 1.0 - c
    ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    W = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
    R = [[(1.0 - C * ww if i == j else 0.0) + s * W[i][j] + C * w[i] * w[j] for j in range(3)] for i in range(3)]
    wv = w[0] * v[0] + w[1] * v[1] + w[2] * v[2]
    wxv = cross3(w, v)
    p = [theta * v[i] + C * wxv[i] + (theta - s) * (w[i] * wv - ww * v[i]) for i in range(3)]
    return R, p


def stack_scalars(rows, batch_shape: tuple, dtype) -> Array:
    """Nested lists of scalars (``rows[a][b]``) → array ``(*batch_shape, len(rows), len(rows[0]))``."""
    full = lambda x: jnp.broadcast_to(jnp.asarray(x, dtype), (1,) + tuple(batch_shape))  # noqa: E731
    # One concatenation along a new leading axis (contiguous copies of whole batch arrays),
    # then the axes moved last: far cheaper to compile and run than interleaving scalars along
    # a minor axis, and than nested stacks (XLA's CPU code for a stack of stacks of the 48
    # angles of the closed-form IK ran 35× slower than this).
    flat = jnp.concatenate([full(x) for row in rows for x in row])
    return jnp.moveaxis(flat.reshape((len(rows), len(rows[0])) + tuple(batch_shape)), (0, 1), (-2, -1))


def exp_twist(twist: Array, theta: Array) -> tuple[Array, Array]:
    """Exponential ``exp(ξ̂ θ)`` of a unit twist, as rotation and translation arrays.

    Args:
      twist: ``(..., 6)`` ``[v, ω]`` with ``|ω| = 1`` (revolute) or ``ω = 0, |v| = 1``
        (prismatic).
      theta: ``(...)`` joint value [rad or m].

    Returns:
      ``R (..., 3, 3)``, ``p (..., 3)`` (see :func:`exp_scalars`).
    """
    twist, theta = jnp.asarray(twist), jnp.asarray(theta)
    dtype = jnp.result_type(twist, theta)
    shape = jnp.broadcast_shapes(twist.shape[:-1], theta.shape)
    R, p = exp_scalars([twist[..., k] for k in range(6)], theta)
    return stack_scalars(R, shape, dtype), stack_scalars([p], shape, dtype)[..., 0, :]


def adjoint_twist(R: Array, p: Array, twist: Array) -> Array:
    """``Ad_g ξ`` for ``g = (R, p)``: ``[R v + p × R ω, R ω]``; shapes ``(...,3,3)``, ``(...,3)``, ``(...,6)``."""
    Rw = matvec(R, twist[..., 3:])
    return jnp.concatenate([matvec(R, twist[..., :3]) + jnp.cross(p, Rw), Rw], axis=-1)


def homogeneous(R: Array, p: Array) -> Array:
    """``(..., 3, 3)``, ``(..., 3)`` → ``(..., 4, 4)`` homogeneous transform."""
    top = jnp.concatenate([R, p[..., None]], axis=-1)
    bottom = jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0], dtype=R.dtype), top.shape[:-2] + (1, 4))
    return jnp.concatenate([top, bottom], axis=-2)


def rigid_inverse(R: Array, p: Array) -> tuple[Array, Array]:
    """``(Rᵀ, −Rᵀ p)``: the inverse of the rigid motion ``(R (..., 3, 3), p (..., 3))``."""
    Rt = jnp.swapaxes(R, -1, -2)
    return Rt, -matvec(Rt, p)


def pose_inverse(T: Array) -> Array:
    """``T⁻¹ = [Rᵀ, −Rᵀ p; 0, 1]`` of homogeneous poses ``(..., 4, 4)``."""
    return homogeneous(*rigid_inverse(T[..., :3, :3], T[..., :3, 3]))


def axis_rotation(axis: int, angle) -> Array:
    """Rotation ``(..., 3, 3)`` by ``angle (...)`` [rad] about the frame's x, y or z axis
    (``axis`` 0, 1 or 2)."""
    angle = jnp.asarray(angle)
    c, s = jnp.cos(angle), jnp.sin(angle)
    one, zero = jnp.ones_like(c), jnp.zeros_like(c)
    i, j = (axis + 1) % 3, (axis + 2) % 3  # the turning plane, i → j positive (x → y about z)
    rows = [[one if a == b else zero for b in range(3)] for a in range(3)]
    rows[i][i], rows[i][j], rows[j][i], rows[j][j] = c, -s, s, c
    return jnp.stack([jnp.stack(r, axis=-1) for r in rows], axis=-2)


def rpy_matrix(rpy) -> Array:
    """URDF roll-pitch-yaw ``(..., 3)`` [rad] → ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    rpy = jnp.asarray(rpy)
    return matmul(matmul(axis_rotation(2, rpy[..., 2]), axis_rotation(1, rpy[..., 1])), axis_rotation(0, rpy[..., 0]))


# Below this |vee|² = (2 sin θ)², rotation_log uses the series of θ / (2 sin θ); the remainder
# θ⁴ is far below the round-off of either float type there.
_SMALL_VEE_SQ = 4e-12  # sin θ < 1e-6


def rotation_log_scalars(R: list) -> list:
    """Axis-angle vector of a rotation given as 3 rows of 3 scalars (arrays of one batch shape),
    as 3 scalars: the one implementation of :func:`rotation_log`, also run inside the GPU IK
    kernel (``uvms_jax.kin._ik_gpu``). Safe at θ = 0 and near π.

    Value and gradient are finite everywhere: every branch that a ``where`` discards is fed a
    harmless input (double ``where``), so its derivative cannot turn into NaN.
    """
    where = jnp.where
    cos = jnp.clip((R[0][0] + R[1][1] + R[2][2] - 1.0) / 2.0, -1.0, 1.0)
    vee = [R[2][1] - R[1][2], R[0][2] - R[2][0], R[1][0] - R[0][1]]
    # vee = 2 sin θ · axis. Near θ = 0, θ / (2 sin θ) = 1/2 + θ²/12 + O(θ⁴) with θ² ≈ |vee|²/4;
    # the norm's derivative is infinite at 0, so it only ever sees a nonzero input.
    vee_sq = vee[0] * vee[0] + vee[1] * vee[1] + vee[2] * vee[2]
    nonzero = vee_sq > 0.0
    sin = where(nonzero, 0.5 * jnp.sqrt(where(nonzero, vee_sq, 1.0)), 0.0)
    theta = jnp.arctan2(sin, cos)
    small = vee_sq < _SMALL_VEE_SQ
    scale = where(small, 0.5 + vee_sq / 48.0, theta / (2.0 * where(small, 1.0, sin)))
    # Near θ = π the antisymmetric part vanishes; recover the axis from the symmetric part.
    # There (R + Rᵀ)/2 − cos·I = (1 − cos) k kᵀ: take its largest column (the first on ties) as
    # the axis k. Elsewhere B is replaced by I (it may be 0 there: keep its norm's gradient finite).
    near_pi = cos < -0.99
    B = [[where(near_pi, (R[i][j] + R[j][i]) / 2.0 - (cos if i == j else 0.0), float(i == j)) for j in range(3)]
         for i in range(3)]
    first = (B[0][0] >= B[1][1]) & (B[0][0] >= B[2][2])
    second = ~first & (B[1][1] >= B[2][2])
    col = [where(first, B[i][0], where(second, B[i][1], B[i][2])) for i in range(3)]
    norm = jnp.sqrt(col[0] * col[0] + col[1] * col[1] + col[2] * col[2])  # ≥ (1 − cos)/3 > 0.6 near π
    axis = [c / norm for c in col]
    # Sign of the axis: agree with the (small) antisymmetric part where it still carries one.
    sign = where(axis[0] * vee[0] + axis[1] * vee[1] + axis[2] * vee[2] < 0, -1.0, 1.0)
    return [where(near_pi, theta * sign * axis[i], scale * vee[i]) for i in range(3)]


def rotation_log(R: Array) -> Array:
    """Axis-angle vector ``(..., 3)`` of a rotation ``(..., 3, 3)`` (:func:`rotation_log_scalars`)."""
    return jnp.stack(rotation_log_scalars([[R[..., i, j] for j in range(3)] for i in range(3)]), axis=-1)


def pose_error(T_target: Array, T: Array) -> Array:
    """6-vector ``[p_target − p, log(R_target Rᵀ)]`` (world-frame position and orientation error)."""
    dp = T_target[..., :3, 3] - T[..., :3, 3]
    dR = matmul(T_target[..., :3, :3], jnp.swapaxes(T[..., :3, :3], -1, -2))
    return jnp.concatenate([dp, rotation_log(dR)], axis=-1)
