"""Inverse kinematics: closed form for the 6R elbow arm, damped least squares for any chain."""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.kin._chain import Chain, with_dtype
from uvms_jax.kin._fk import fk_of, pose_and_jacobian_of
from uvms_jax.kin._lie import cross3, dot3, exp_scalars, matmul, matvec, pose_error, stack_scalars
from uvms_jax.kin._scalar import compose, invert, rotate, spd_solve_scalars, wrap_angle
from uvms_jax.kin import _ik_gpu
from uvms_jax.kin import _paden_kahan as pk

POSITION_TOL = {jnp.dtype("float32"): 1e-4, jnp.dtype("float64"): 1e-8}  # [m] accepted FK(IK(T)) residual
ROTATION_TOL = {jnp.dtype("float32"): 1e-3, jnp.dtype("float64"): 1e-7}  # [rad]


class IKSolutions(NamedTuple):
    """IK result. ``q`` holds NaN wherever ``valid`` is False (never a garbage angle).

    Attributes:
      q: ``(..., k, n)`` candidate joint vectors [rad] (k = 8 for the closed form).
      valid: ``(..., k)`` reachable, inside the joint limits and FK(q) = T within tolerance.
    """

    q: Array
    valid: Array


def _check_pose(T) -> Array:
    T = jnp.asarray(T)
    if T.ndim < 2 or T.shape[-2:] != (4, 4):
        raise ValueError(f"target pose must have shape (..., 4, 4), got {T.shape}")
    if not jnp.issubdtype(T.dtype, jnp.floating):
        T = T.astype(jnp.float32)
    if not isinstance(T, jax.core.Tracer) and bool(jnp.isnan(T).any()):
        raise ValueError("target pose contains NaN")
    return T


def wrap_into_limits(chain: Chain, q: Array) -> tuple[Array, Array]:
    """Shift revolute angles by multiples of 2π to the smallest value ≥ the lower limit.

    Returns the shifted ``q (..., n)`` and ``inside (...)`` (every joint within its limits).
    """
    revolute = jnp.array([k == "revolute" for k in chain.kinds])
    q = jnp.where(revolute, wrap_angle(q, chain.lower), q)
    return q, jnp.all((q >= chain.lower) & (q <= chain.upper), axis=-1)


def reaches(T_target: Array, T: Array) -> Array:
    """``(...)`` True where pose ``T`` equals ``T_target`` within the IK tolerances of its dtype.

    The orientation test uses ``‖R_target − R‖_F ≈ √2 |Δθ|`` (cheaper than a matrix log).
    """
    entries = lambda T: ([[T[..., i, j] for j in range(3)] for i in range(3)], [T[..., i, 3] for i in range(3)])  # noqa: E731
    return reaches_scalars(*entries(T_target), *entries(T), T.dtype)


def reaches_scalars(R_target: list, p_target: list, R: list, p: list, dtype) -> Array:
    """:func:`reaches` on scalars (rotation rows and translations of one batch shape)."""
    dp2 = sum((a - b) ** 2 for a, b in zip(p_target, p))
    dR2 = sum((a - b) ** 2 for ra, rb in zip(R_target, R) for a, b in zip(ra, rb))
    position_tol, rotation_tol = POSITION_TOL[jnp.dtype(dtype)], ROTATION_TOL[jnp.dtype(dtype)]
    return (jnp.sqrt(dp2) < position_tol) & (jnp.sqrt(dR2) < jnp.sqrt(2.0) * rotation_tol)


def elbow_branch_scalars(chain: Chain, R_t: list, p_t: list) -> tuple[list, list]:
    """The eight closed-form branches (Murray §3.3.2) on scalars: the target ``R_t`` (3 rows of
    3), ``p_t`` (3) as arrays of one batch shape (:mod:`uvms_jax.kin._scalar`'s form).

    Returns:
      ``q`` (8 branches of 6 scalars: the raw algebraic angles, revolute ones shifted into
      ``[lower, lower + 2π)``, not clipped; a branch with a non-finite angle is all 0, so
      that FK, Jacobians and their gradients stay finite) and ``ok`` (8 scalars: every
      subproblem solvable, every angle finite and within its limits); ordered (elbow,
      shoulder, wrist) branch bits. Callers confirm with :func:`reaches` on FK of ``q``.
    """
    twists = [[chain.twists[j, i] for i in range(6)] for j in range(6)]
    w = [t[3:] for t in twists]
    M = [[chain.T_base_tool0[i, j] for j in range(4)] for i in range(3)]
    # Points on the axes: shoulder = closest point of axis 2 to the origin (it lies on axis 1
    # too), elbow likewise on axis 3; wrist centre = tool point at q = 0.
    shoulder, elbow, wrist0 = cross3(w[1], twists[1][:3]), cross3(w[2], twists[2][:3]), [M[i][3] for i in range(3)]
    to_shoulder = pk.sub3(p_t, shoulder)
    theta3, ok3 = pk.distance(w[2], elbow, wrist0, shoulder, jnp.sqrt(dot3(to_shoulder, to_shoulder)))
    M_inverse = invert([row[:3] for row in M], wrist0)
    on_axis6, off_axis6 = [wrist0[i] + w[5][i] for i in range(3)], [wrist0[i] + w[3][i] for i in range(3)]
    branches_q, branches_ok = [], []
    for e in range(2):
        R3, p3 = exp_scalars(twists[2], theta3[e])
        wrist_e = [a + b for a, b in zip(rotate(R3, wrist0), p3)]
        theta1, theta2, ok12 = pk.two_axes(w[0], w[1], shoulder, wrist_e, p_t)
        for s in range(2):
            R123, p123 = compose(*compose(*exp_scalars(twists[0], theta1[s]), *exp_scalars(twists[1], theta2[s])), R3, p3)
            # g_a = (e1 e2 e3)⁻¹ T M⁻¹ = e4 e5 e6.
            Ra, pa = compose(*compose(*invert(R123, p123), R_t, p_t), *M_inverse)
            at_axis6 = [a + b for a, b in zip(rotate(Ra, on_axis6), pa)]
            theta4, theta5, ok45 = pk.two_axes(w[3], w[4], wrist0, on_axis6, at_axis6)
            moved = [a + b for a, b in zip(rotate(Ra, off_axis6), pa)]
            for r in range(2):
                R45, p45 = compose(*exp_scalars(twists[3], theta4[r]), *exp_scalars(twists[4], theta5[r]))
                Rb, pb = invert(R45, p45)
                target = [a + b for a, b in zip(rotate(Rb, moved), pb)]
                theta6 = pk.rotation_to(w[5], wrist0, off_axis6, target)
                q = [wrap_angle(a, lo) for a, lo in zip([theta1[s], theta2[s], theta3[e], theta4[r], theta5[r], theta6],
                                                        chain.lower)]
                finite = functools.reduce(jnp.logical_and, [jnp.isfinite(a) for a in q])
                inside = functools.reduce(jnp.logical_and, [(a >= lo) & (a <= up) for a, lo, up in
                                                            zip(q, chain.lower, chain.upper)])
                branches_q.append([jnp.where(finite, a, 0.0) for a in q])
                branches_ok.append(ok3 & ok12 & ok45 & finite & inside)
    return branches_q, branches_ok


def elbow_branches(chain: Chain, T: Array) -> IKSolutions:
    """Eight closed-form branches for targets ``T (..., 4, 4)`` (:func:`elbow_branch_scalars`),
    unverified: ``q (..., 8, 6)`` finite everywhere (0 where an angle is not),
    ``valid (..., 8)`` covering solvability of every subproblem and the joint limits. Callers
    confirm with :func:`reaches` on FK of ``q``."""
    q, ok = elbow_branch_scalars(chain, [[T[..., i, j] for j in range(3)] for i in range(3)],
                                 [T[..., i, 3] for i in range(3)])
    return IKSolutions(q=stack_scalars(q, T.shape[:-2], T.dtype), valid=jnp.stack(ok, axis=-1))


def _elbow_ik_one(chain: Chain, T: Array) -> IKSolutions:
    branches = elbow_branches(chain, T)
    T_reached = fk_of(chain, branches.q)
    valid = branches.valid & reaches(T, T_reached)
    return IKSolutions(q=jnp.where(valid[:, None], branches.q, jnp.nan), valid=valid)


@jax.jit
def _elbow_ik(chain: Chain, T: Array) -> IKSolutions:
    chain = with_dtype(chain, T.dtype)
    flat = T.reshape((-1, 4, 4))
    out = jax.vmap(_elbow_ik_one, in_axes=(None, 0))(chain, flat)
    return jax.tree_util.tree_map(lambda x: x.reshape(T.shape[:-2] + x.shape[1:]), out)


def elbow_ik(chain: Chain, T_base_tool) -> IKSolutions:
    """Closed-form IK of a 6R elbow arm with spherical wrist by Paden–Kahan subproblems.

    The chain must have the structure of :func:`uvms_jax.kin.docking_arm` (axes 1 and 2
    intersecting at the shoulder, axes 2 and 3 parallel, axes 4–6 meeting at the wrist
    centre = tool point).

    Args:
      chain: the arm.
      T_base_tool: ``(..., 4, 4)`` target tool poses in the base frame [m].

    Returns:
      :class:`IKSolutions` with ``q (..., 8, 6)`` ordered (elbow, shoulder, wrist) branch
      bits, and ``valid (..., 8)``.
    """
    if chain.n_joints != 6 or any(k != "revolute" for k in chain.kinds):
        raise ValueError(f"elbow_ik needs a 6R chain, got {chain.name!r} with kinds {chain.kinds}")
    return _elbow_ik(chain, _check_pose(T_base_tool))


LIMITS = ("clip", "wrap")


def spd_solve(A: Array, b: Array) -> Array:
    """``x (..., m)`` with ``A x = b`` for small symmetric positive-definite ``A (..., m, m)``
    (m ≤ 6 here: the DLS system ``J Jᵀ + λ² I``), by a Cholesky factorisation written out entry
    by entry.

    Why not ``jnp.linalg.solve``: batched over a population's poses, seeds and targets, the
    library's LU runs as one small factorisation per matrix (a batched cuBLAS/LAPACK call inside
    every DLS iteration), while the written-out form is elementwise arithmetic on ``(...)``
    arrays that XLA fuses with the kinematics around it. Backward stable for SPD matrices; the
    damping keeps ``A``'s smallest eigenvalue ≥ λ² > 0.
    """
    m = A.shape[-1]
    return jnp.stack(spd_solve_scalars([[A[..., i, j] for j in range(i + 1)] for i in range(m)],
                                       [b[..., i] for i in range(m)]), axis=-1)


def dls_ik(chain: Chain, T_base_tool: Array, q0: Array, iterations: int, damping=1.0, *, limits: str = "clip") -> Array:
    """Damped least squares from seeds ``q0 (..., n)`` towards ``T_base_tool (..., 4, 4)``
    (leading axes broadcast together), a fixed number of iterations, no checks, no ``jit``
    (for use inside other kernels: planning's targets and docking's fitness both run it).

    Each step solves ``(J Jᵀ + λ² I) y = e``, ``Δq = Jᵀ y`` with the error-scaled damping
    ``λ² = damping² (‖e‖² + 10⁻⁶)``: robust far from the target and near singularities,
    Gauss–Newton-fast as the error vanishes (the Levenberg–Marquardt flavour of DLS). Products
    run at full float32 precision on GPUs too (TF32 breaks the reach checks).

    Args:
      limits: ``"clip"`` keeps every iterate inside the joint limits (box-constrained DLS);
        ``"wrap"`` only shifts revolute angles by whole turns into ``[lower, lower + 2π)`` and
        leaves the limits to the caller (docking counts a solution outside them as invalid
        rather than moving it).

    Returns ``q (..., n)``. Solutions are not checked: compare ``fk(q)`` with the target.
    """
    if limits not in LIMITS:
        raise ValueError(f"limits must be one of {LIMITS}, got {limits!r}")
    shape = jnp.broadcast_shapes(T_base_tool.shape[:-2], q0.shape[:-1])
    q = _keep(chain, jnp.broadcast_to(q0, shape + q0.shape[-1:]), limits)
    loop = lambda T, q: jax.lax.fori_loop(0, iterations, lambda _, q: dls_step(chain, T, q, damping, limits), q)  # noqa: E731
    if _ik_gpu.applies(q):  # on a GPU, the whole loop as one kernel (same arithmetic)
        return _ik_gpu.dls_ik_kernel(chain, T_base_tool, q, iterations, damping, limits, loop)
    return loop(T_base_tool, q)


def _keep(chain: Chain, q: Array, limits: str) -> Array:
    return jnp.clip(q, chain.lower, chain.upper) if limits == "clip" else wrap_into_limits(chain, q)[0]


def dls_step(chain: Chain, T_base_tool: Array, q: Array, damping=1.0, limits: str = "clip") -> Array:
    """One iteration of :func:`dls_ik` from ``q (..., n)``: the solve of ``(J Jᵀ + λ² I) y = e``
    (:func:`spd_solve`) and the step ``Jᵀ y``, kept by ``limits``."""
    T_q, J = pose_and_jacobian_of(chain, q)
    e = pose_error(T_base_tool, T_q)
    lam2 = damping**2 * (jnp.sum(e * e, axis=-1) + 1e-6)
    y = spd_solve(matmul(J, jnp.swapaxes(J, -1, -2)) + lam2[..., None, None] * jnp.eye(6, dtype=q.dtype), e)
    return _keep(chain, q + matvec(jnp.swapaxes(J, -1, -2), y), limits)


def _numeric_ik_one(key, chain, T, n_seeds, iterations, damping):
    u = jax.random.uniform(key, (n_seeds, chain.n_joints), dtype=T.dtype)
    seeds = chain.lower + u * (chain.upper - chain.lower)
    q = dls_ik(chain, T, seeds, iterations, damping, limits="clip")
    err = pose_error(T, fk_of(chain, q))
    pos, rot = jnp.linalg.norm(err[:, :3], axis=-1), jnp.linalg.norm(err[:, 3:], axis=-1)
    ok = (pos < POSITION_TOL[T.dtype]) & (rot < ROTATION_TOL[T.dtype])
    best = jnp.argmin(jnp.where(ok, 0.0, 1.0) * 1e3 + pos + rot)
    return q[best], ok[best], q, ok


@jax.jit(static_argnames=("n_seeds", "iterations"))
def _numeric_ik(key, chain, T, n_seeds, iterations, damping):
    chain = with_dtype(chain, T.dtype)
    flat = T.reshape((-1, 4, 4))
    keys = jax.random.split(key, flat.shape[0])
    out = jax.vmap(_numeric_ik_one, in_axes=(0, None, 0, None, None, None))(
        keys, chain, flat, n_seeds, iterations, damping
    )
    return jax.tree_util.tree_map(lambda x: x.reshape(T.shape[:-2] + x.shape[1:]), out)


def numeric_ik(
    key: Array,
    chain: Chain,
    T_base_tool,
    n_seeds: int = 32,
    iterations: int = 100,
    damping: float = 1.0,
    all_seeds: bool = False,
) -> IKSolutions:
    """Numerical IK of any chain: damped least squares from many random seeds in parallel.

    Args:
      key: PRNG key for the seeds (uniform inside the joint limits).
      chain: the robot.
      T_base_tool: ``(..., 4, 4)`` target tool poses [m].
      n_seeds: seeds per target, all run in parallel.
      iterations: DLS iterations per seed.
      damping: DLS damping factor; λ² = damping² (‖e‖² + 10⁻⁶).
      all_seeds: return every seed's converged solution (``(..., n_seeds, n)``) instead of
        the best one per target.

    Returns:
      :class:`IKSolutions`: best solution ``q (..., n)``, ``valid (...)``; or, with
      ``all_seeds``, ``q (..., n_seeds, n)`` and ``valid (..., n_seeds)``. ``q`` is NaN where
      not valid.
    """
    T = _check_pose(T_base_tool)
    best_q, best_ok, q, ok = _numeric_ik(key, chain, T, n_seeds, iterations, damping)
    if all_seeds:
        return IKSolutions(q=jnp.where(ok[..., None], q, jnp.nan), valid=ok)
    return IKSolutions(q=jnp.where(best_ok[..., None], best_q, jnp.nan), valid=best_ok)
