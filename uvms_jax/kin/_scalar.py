"""The kinematics kernel: one pass over the joints of a chain, written on scalars.

Every quantity is a nested list of "scalars": 0-d arrays for the chain geometry (traced
pytree leaves, so the kernel is differentiable and vmappable in the design parameters) and
arrays of the batch shape for anything that depends on ``q``. Every batched operation is
then elementwise and fuses into one kernel on CPU and GPU — no tiny batched matrix products,
no strided gathers. Measured on a 2-core CPU for the 12-DOF UVMS, this is ~20× faster than
the same maths on ``(..., 3, 3)`` arrays.

The functions here are meant to run inside ``jit`` (the public wrappers in ``_fk`` jit them
with the chain as an argument, so one compiled program serves every geometry of a topology).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from uvms_jax.kin._chain import Chain
from uvms_jax.kin._lie import cross3, dot3, exp_scalars, stack_scalars

Rows = list  # nested list of scalars (arrays of one batch shape, or Python floats)

_IDENTITY = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def rotate(R, x) -> list:
    """``R x`` for a rotation given as 3 rows of 3 scalars and a point as 3."""
    return [dot3(R[i], x) for i in range(3)]


def invert(R, p) -> tuple[list, list]:
    """``(Rᵀ, −Rᵀ p)``: the inverse of the rigid motion ``(R, p)``."""
    Rt = [[R[j][i] for j in range(3)] for i in range(3)]
    return Rt, [-dot3(Rt[i], p) for i in range(3)]


def wrap_angle(q, lower):
    """Revolute angle ``q`` shifted by a multiple of 2π to the smallest value ≥ ``lower`` [rad]
    (the same pose; never clipped)."""
    return lower + jnp.mod(q - lower, 2.0 * np.pi)


def compose(R, p, Ri, pi) -> tuple[list, list]:
    """``(R, p) ∘ (Ri, pi) = (R Ri, R pi + p)``."""
    Rp = rotate(R, pi)
    return (
        [[R[i][0] * Ri[0][j] + R[i][1] * Ri[1][j] + R[i][2] * Ri[2][j] for j in range(3)] for i in range(3)],
        [Rp[i] + p[i] for i in range(3)],
    )


def _entries(a, dtype):
    """A geometry array as nested scalars: Python floats when its numbers are known (they become
    constants of the compiled kernel, which the GPU kernel of ``uvms_jax.indices`` needs), 0-d
    arrays of ``dtype`` when it is traced (the usual case: the chain is a ``jit`` argument)."""
    if isinstance(a, jax.core.Tracer):
        a = jnp.asarray(a, dtype)
        return [[a[i, j] for j in range(a.shape[1])] for i in range(a.shape[0])]
    return np.asarray(a, np.float64).tolist()


def compose_pose(R, p, T) -> tuple[list, list]:
    """``(R, p) ∘ T`` for a constant pose ``T (4, 4)``, cast to the dtype of ``p``."""
    T = _entries(T, jnp.result_type(*p))
    return compose(R, p, [row[:3] for row in T[:3]], [row[3] for row in T[:3]])


class Pass(NamedTuple):
    """One pass over the joints at ``q``; every scalar has the batch shape of ``q[..., 0]``.

    Attributes:
      columns: per joint, the spatial twist ``ξ'_i = Ad(e^{ξ1θ1}⋯e^{ξ(i−1)θ(i−1)}) ξ_i`` as
        ``(v', ω')`` (3 scalars each, base frame).
      products: per joint, ``(R, p)`` of ``e^{ξ1θ1}⋯e^{ξiθi}`` (base frame).
    """

    columns: list
    products: list


def columns_of(q) -> list:
    """``q: (..., n)`` array, or already a list of n arrays of one batch shape → that list."""
    if isinstance(q, (list, tuple)):
        return list(jnp.broadcast_arrays(*q))
    return [q[..., i] for i in range(q.shape[-1])]


def _joint_step(carry, joint):
    """The kernel: one joint of the pass, on scalars.

    ``carry = (R, p)`` is ``e^{ξ1θ1}⋯e^{ξ(i−1)θ(i−1)}``, ``joint = (ξ_i, θ_i)``; returns the
    product through joint i and the spatial twist ``ξ'_i = Ad(carry) ξ_i`` as ``(v', ω')``.
    """
    (R, p), (twist, theta) = carry, joint
    w_s = rotate(R, twist[3:])
    v_s = [a + b for a, b in zip(rotate(R, twist[:3]), cross3(p, w_s))]
    return compose(R, p, *exp_scalars(twist, theta)), (v_s, w_s)


def forward(chain: Chain, q_cols: list) -> Pass:
    """The pass unrolled over the joints (``n`` is static): for kernels that reduce what it
    yields to a few numbers (the dexterity indices), everything fuses into one loop.

    Args:
      chain: the robot; its geometry is cast to the dtype of the joint values.
      q_cols: n arrays of one batch shape, joint i's values [rad or m].
    """
    twists = _entries(chain.twists, q_cols[0].dtype)
    carry = (_IDENTITY, [0.0, 0.0, 0.0])
    columns, products = [], []
    for i in range(chain.n_joints):
        carry, column = _joint_step(carry, (twists[i], q_cols[i]))
        columns.append(column)
        products.append(carry)
    return Pass(columns, products)


def forward_scanned(chain: Chain, q: Array) -> Pass:
    """The same pass as a ``lax.scan`` over the joints, for kernels that write whole poses
    and Jacobians: every joint's product is stored, so the compiled program stays small
    (unrolled, XLA copies the expression of every earlier joint into each of the many
    outputs: minutes of compile for a 12-joint chain).

    Returns a :class:`Pass` whose scalars have shape ``(n, *batch)`` (joint axis first);
    ``products`` and ``columns`` hold one entry: the stacked values.
    """
    twists = jnp.asarray(chain.twists, q.dtype)
    q_joint_first = jnp.moveaxis(q, -1, 0)
    zero, one = jnp.zeros(q.shape[:-1], q.dtype), jnp.ones(q.shape[:-1], q.dtype)
    identity = ([[one, zero, zero], [zero, one, zero], [zero, zero, one]], [zero, zero, zero])

    def step(carry, x):
        twist, theta = x
        carry, column = _joint_step(carry, ([twist[k] for k in range(6)], theta))
        return carry, (carry, column)

    _, (products, columns) = jax.lax.scan(step, identity, (twists, q_joint_first))
    return Pass([columns], [products])


def tool_pose(chain: Chain, kpass: Pass) -> tuple[list, list]:
    """``(R, p)`` of ``T_base_tool = e^{ξ1θ1}⋯e^{ξnθn} T_base_tool0`` as scalars (unrolled pass)."""
    return compose_pose(*kpass.products[-1], chain.T_base_tool0)


def geometric_rows(kpass: Pass, p_tool: list) -> Rows:
    """Geometric Jacobian as 6 rows × n scalars: the spatial columns with their reference
    point moved to the tool point, ``v_p = v' + ω' × p_tool`` (rows ``[v; ω]``)."""
    linear = [[a + b for a, b in zip(v, cross3(w, p_tool))] for v, w in kpass.columns]
    angular = [w for _, w in kpass.columns]
    return [[col[r] for col in linear] for r in range(3)] + [[col[r] for col in angular] for r in range(3)]


def spatial_rows(chain: Chain, q) -> Rows:
    """Spatial-twist Jacobian of ``chain`` at ``q`` as 6 rows × n scalars (the columns
    ``ξ'_i`` of the pass, reference point at the base origin)."""
    columns = forward(chain, columns_of(q)).columns
    return [[v[r] for v, _ in columns] for r in range(3)] + [[w[r] for _, w in columns] for r in range(3)]


def pose_and_jacobian_rows(chain: Chain, q) -> tuple[list, list, Rows]:
    """Tool pose ``(R, p)`` and geometric Jacobian (6 rows × n) of ``chain`` at ``q`` as
    scalars of the batch shape, from one unrolled pass.

    ``q`` is an array ``(..., n)`` or a list of n arrays (its columns). For kernels that
    consume J entry by entry (indices): they fuse with the kinematics and never store J.
    """
    kpass = forward(chain, columns_of(q))
    R_tool, p_tool = tool_pose(chain, kpass)
    return R_tool, p_tool, geometric_rows(kpass, p_tool)


def jacobian_rows(chain: Chain, q) -> Rows:
    """Geometric Jacobian of ``chain`` at ``q`` as 6 rows × n scalars (:func:`pose_and_jacobian_rows`)."""
    return pose_and_jacobian_rows(chain, q)[2]


def pose_array(R: list, p: list, batch_shape: tuple, dtype) -> Array:
    """Rotation rows and translation of scalars → ``(*batch_shape, 4, 4)`` homogeneous pose."""
    rows = [R[i] + [p[i]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
    return stack_scalars(rows, batch_shape, dtype)


def spd_solve_scalars(A: list, b: list) -> list:
    """``x`` with ``A x = b`` for a small symmetric positive-definite ``A`` given as rows of
    scalars (``A[i][j]`` read for ``j ≤ i`` only), by a Cholesky factorisation written out entry
    by entry: the one implementation of :func:`uvms_jax.kin.spd_solve`, also run inside the GPU
    IK kernel."""
    m = len(b)
    L = [[None] * m for _ in range(m)]
    for j in range(m):
        L[j][j] = jnp.sqrt(A[j][j] - sum(L[j][k] * L[j][k] for k in range(j)))
        for i in range(j + 1, m):
            L[i][j] = (A[i][j] - sum(L[i][k] * L[j][k] for k in range(j))) / L[j][j]
    y = []
    for i in range(m):
        y.append((b[i] - sum(L[i][k] * y[k] for k in range(i))) / L[i][i])
    x = [None] * m
    for i in reversed(range(m)):
        x[i] = (y[i] - sum(L[k][i] * x[k] for k in range(i + 1, m))) / L[i][i]
    return x
