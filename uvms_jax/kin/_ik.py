"""Inverse kinematics: closed form for the 6R elbow arm, damped least squares for any chain."""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.kin._chain import Chain, with_dtype
from uvms_jax.kin._fk import fk_of, pose_and_jacobian_of
from uvms_jax.kin._lie import exp_twist, matmul, matvec, pose_error, rigid_inverse
from uvms_jax.kin._scalar import spd_solve_scalars
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
    two_pi = 2.0 * jnp.pi
    wrapped = chain.lower + jnp.mod(q - chain.lower, two_pi)
    q = jnp.where(revolute, wrapped, q)
    return q, jnp.all((q >= chain.lower) & (q <= chain.upper), axis=-1)


def reaches(T_target: Array, T: Array) -> Array:
    """``(...)`` True where pose ``T`` equals ``T_target`` within the IK tolerances of its dtype.

    The orientation test uses ``‖R_target − R‖_F ≈ √2 |Δθ|`` (cheaper than a matrix log).
    """
    dp = jnp.linalg.norm(T_target[..., :3, 3] - T[..., :3, 3], axis=-1)
    dR = jnp.sqrt(jnp.sum((T_target[..., :3, :3] - T[..., :3, :3]) ** 2, axis=(-1, -2)))
    return (dp < POSITION_TOL[T.dtype]) & (dR < jnp.sqrt(2.0) * ROTATION_TOL[T.dtype])


def elbow_branches(chain: Chain, T: Array) -> IKSolutions:
    """Eight closed-form branches for one target ``T (4, 4)`` (Murray §3.3.2), unverified.

    ``q`` holds the raw algebraic angles shifted into the limits modulo 2π (finite
    everywhere); ``valid`` covers solvability of every subproblem and the joint limits.
    Callers confirm with :func:`reaches` on FK of ``q``.
    """
    w = chain.twists[:, 3:]
    # Points on the axes: shoulder = closest point of axis 2 to the origin (it lies on axis 1
    # too), elbow likewise on axis 3; wrist centre = tool point at q = 0.
    point = lambda i: jnp.cross(w[i], chain.twists[i, :3])
    shoulder, elbow, wrist0 = point(1), point(2), chain.T_base_tool0[:3, 3]
    p = T[:3, 3]

    theta3, ok3 = pk.distance(w[2], elbow, wrist0, shoulder, jnp.linalg.norm(p - shoulder))
    branches_q, branches_ok = [], []
    Rm, pm = rigid_inverse(chain.T_base_tool0[:3, :3], chain.T_base_tool0[:3, 3])
    for e in range(2):
        R3, p3 = exp_twist(chain.twists[2], theta3[e])
        wrist_e = matvec(R3, wrist0) + p3
        theta1, theta2, ok12 = pk.two_axes(w[0], w[1], shoulder, wrist_e, p)
        for s in range(2):
            R1, p1 = exp_twist(chain.twists[0], theta1[s])
            R2, p2 = exp_twist(chain.twists[1], theta2[s])
            R12, p12 = matmul(R1, R2), matvec(R1, p2) + p1
            R123, p123 = matmul(R12, R3), matvec(R12, p3) + p12
            Ri, pi = rigid_inverse(R123, p123)
            # g_a = (e1 e2 e3)^-1 T M^-1 = e4 e5 e6.
            Ra = matmul(matmul(Ri, T[:3, :3]), Rm)
            pa = matvec(Ri, matvec(T[:3, :3], pm) + T[:3, 3]) + pi
            on_axis6 = wrist0 + w[5]
            theta4, theta5, ok45 = pk.two_axes(w[3], w[4], wrist0, on_axis6, matvec(Ra, on_axis6) + pa)
            off_axis6 = wrist0 + w[3]
            for r in range(2):
                R4, p4 = exp_twist(chain.twists[3], theta4[r])
                R5, p5 = exp_twist(chain.twists[4], theta5[r])
                R45, p45 = matmul(R4, R5), matvec(R4, p5) + p4
                Rb, pb = rigid_inverse(R45, p45)
                target = matvec(Rb, matvec(Ra, off_axis6) + pa) + pb
                theta6 = pk.rotation_to(w[5], wrist0, off_axis6, target)
                branches_q.append(jnp.stack([theta1[s], theta2[s], theta3[e], theta4[r], theta5[r], theta6]))
                branches_ok.append(ok3 & ok12 & ok45)
    q = jnp.stack(branches_q)
    q, inside = wrap_into_limits(chain, q)
    finite = jnp.all(jnp.isfinite(q), axis=-1)
    valid = jnp.stack(branches_ok) & inside & finite
    return IKSolutions(q=jnp.where(finite[:, None], q, 0.0), valid=valid)


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
