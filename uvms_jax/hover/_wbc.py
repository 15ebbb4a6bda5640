"""A whole-body controller for the vehicle and its arm, as pure functions of arrays.

Two tasks, in order of priority, over the generalised coordinates ``ζ = (η, q)`` of
:func:`uvms_jax.kin.uvms` on the docked vehicle frame V₀ (η: the vehicle's displacement from the
docked pose, translation then XYZ Euler angles; q: the arm's joints):

1. **the tool's 6-D pose on its planned path**, ``J₁ = ∂(tool twist)/∂ζ̇`` the chain's geometric
   Jacobian (6 × (6 + n)); the task velocity is ``v₁ = ẋ_d + K₁ e₁`` (:func:`pose_error`);
2. **station keeping**, ``J₂ = [I₆ 0]``, ``v₂ = −K₂ η``, in the first task's null space.

:func:`task_priority` solves them with the weighted pseudo-inverse (the vehicle's columns weigh
little, so the arm does the first task and the vehicle moves for the second) and the exact
null-space projector ``N₁ = I − J₁⁺_W J₁`` (``J₁ N₁ = 0``: the second task cannot move the
first). :func:`limited_rates` keeps the arm's rates within the joint velocity limits and within
what keeps its targets inside the position limits, by saturating the joints that would leave
their bounds and solving again without them (the saturation-in-null-space idea), then, if a
bound is still crossed, scaling the whole rate vector down (0 always lies inside the bounds):
no limit is ever exceeded, and every period where one was active is counted.

The feed-forward wrench the thrusters give the hull so that it stays still while the arm moves
along its plan (:func:`arm_momentum_rate`, :func:`hydrostatic_wrench`, :func:`drag_wrench`):
``w_ff = ṗ_arm − w_hydrostatic − w_drag − w_added_mass``, all in V about its origin.

Every function takes ``xp`` (``numpy`` or ``jax.numpy``). Units: m, rad, s, kg, N, N·m.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ._hydro import fluid_xfrc

# μ of the second task's solve (task_priority; J₂ N₁ is dimensionless here): the station keeping's
# rates move by a relative μ²/σ_min(J₂ N₁)² ≤ 2.3e-5 on the demo's plan (σ_min ≥ 0.21 along it),
# and μ² = 1e-6, eight float32 ulps of C Cᵀ's unit-sized diagonal, keeps the Cholesky factor real
# in float32 where the arm is singular and C loses rank.
SECOND_TASK_DAMPING = 1e-3

__all__ = ["ArmParts", "arm_momentum_rate", "drag_wrench", "hydrostatic_wrench", "limited_rates", "link_motion",
           "pose_error", "spd_solve", "task_priority", "weighted_pinv"]


class ArmParts(NamedTuple):
    """The arm's mass properties per part, each fixed to one body, in that body's frame.

    Attributes:
      body: ``(P,)`` int, the body: ``-1`` the base (fixed to the mount), ``i`` the link joint
        i moves.
      mass: ``(P,)`` [kg]; com: ``(P, 3)`` [m]; inertia: ``(P, 3, 3)`` about the centre of mass
        [kg·m²]; volume: ``(P,)`` displaced water [m³]; cob: ``(P, 3)`` centre of buoyancy [m].
    """

    body: np.ndarray
    mass: np.ndarray
    com: np.ndarray
    inertia: np.ndarray
    volume: np.ndarray
    cob: np.ndarray


def pose_error(T_desired, T, xp=np):
    """``(..., 6)`` the error of pose ``T`` from ``T_desired`` (both ``(..., 4, 4)`` in one frame):
    position difference [m], then the rotation vector of ``R_d Rᵀ`` [rad] (axis × angle, exact
    for angles below π), both in that frame."""
    R_e = T_desired[..., :3, :3] @ xp.swapaxes(T[..., :3, :3], -1, -2)
    skew = xp.stack([R_e[..., 2, 1] - R_e[..., 1, 2], R_e[..., 0, 2] - R_e[..., 2, 0],
                     R_e[..., 1, 0] - R_e[..., 0, 1]], axis=-1) / 2.0  # sin θ · axis
    cos = xp.clip((R_e[..., 0, 0] + R_e[..., 1, 1] + R_e[..., 2, 2] - 1.0) / 2.0, -1.0, 1.0)
    sin = xp.linalg.norm(skew, axis=-1, keepdims=True)
    angle = xp.arctan2(sin, cos[..., None])
    scale = xp.where(sin > 1e-12, angle / xp.maximum(sin, 1e-12), 1.0)
    return xp.concatenate([T_desired[..., :3, 3] - T[..., :3, 3], scale * skew], axis=-1)


def weighted_pinv(J, w_inv_sqrt, xp=np):
    """``(m, k)`` the weighted pseudo-inverse ``J⁺_W = W^{-1/2} (J W^{-1/2})⁺`` of ``J (k, m)``,
    ``w_inv_sqrt (m,)`` the square roots of ``W⁻¹``'s diagonal (0: a coordinate that must not
    move), for ``J W^{-1/2}`` of full row rank (the vehicle's columns give the tool's task that
    rank whatever the arm): ``W^{-1/2} Aᵀ (A Aᵀ)⁻¹``, ``A = J W^{-1/2}``, by Cholesky
    (:func:`spd_solve`). ``J J⁺_W J = J`` to rounding, whatever the weights."""
    A = J * w_inv_sqrt[None, :]
    return w_inv_sqrt[:, None] * spd_solve(A @ A.T, A, xp=xp).T


def spd_solve(M, rhs, xp=np):
    """``M⁻¹ rhs`` for a symmetric positive-definite ``M (k, k)`` and ``rhs (k, …)``, by its
    Cholesky factor, unrolled (``k`` is static): elementwise operations only, so that under
    ``vmap`` a batch of small systems costs a few fused loops rather than a library call each."""
    k = M.shape[0]
    L = [[None] * k for _ in range(k)]
    for j in range(k):
        L[j][j] = xp.sqrt(M[j, j] - sum(L[j][p] ** 2 for p in range(j)))
        for i in range(j + 1, k):
            L[i][j] = (M[i, j] - sum(L[i][p] * L[j][p] for p in range(j))) / L[j][j]
    y = []
    for i in range(k):  # L y = rhs
        y.append((rhs[i] - sum(L[i][p] * y[p] for p in range(i))) / L[i][i])
    x = [None] * k
    for i in reversed(range(k)):  # Lᵀ x = y
        x[i] = (y[i] - sum(L[p][i] * x[p] for p in range(i + 1, k))) / L[i][i]
    return xp.stack(x)


def task_priority(J1, v1, J2, v2, w_inv_sqrt, damping, xp=np):
    """Two tasks by priority: ``ζ̇ = ζ̇₁ + N₁ (J₂ N₁)⁺ (v₂ − J₂ ζ̇₁)``.

    The pseudo-inverses are Cholesky solves of the tasks' small Gram matrices
    (:func:`spd_solve`), not SVDs: ``J₁⁺_W`` is :func:`weighted_pinv`, and ``(J₂ N₁)⁺ r`` is
    ``Cᵀ (C Cᵀ + μ² I)⁻¹ r``, ``C = J₂ N₁``, ``μ`` = :data:`SECOND_TASK_DAMPING`: the exact
    pseudo-inverse to a relative ``μ²/σ_min(C)²`` where ``C`` has full row rank (for the
    vehicle's rows it has the arm Jacobian's rank), and bounded where it has not.

    Args:
      J1: ``(6, m)`` the first task's Jacobian; v1: ``(6,)`` its velocity.
      J2: ``(k, m)`` the second task's Jacobian; v2: ``(k,)`` its velocity.
      w_inv_sqrt: ``(m,)`` square roots of the inverse weights (:func:`weighted_pinv`).
      damping: damping of the first task's least squares (in its units, e.g. [m]): near a
        singularity ``ζ̇₁ = W^{-1/2} Aᵀ (A Aᵀ + λ² I)⁻¹ v₁``, ``A = J₁ W^{-1/2}``.

    Returns:
      ``(ζ̇ (m,), ζ̇₂ (m,), N₁ (m, m))``: the rates, the second task's part of them (``J₁ ζ̇₂ = 0``
      to rounding: ``N₁ = I − J₁⁺_W J₁`` is built from the undamped pseudo-inverse), and ``N₁``.
    """
    A = J1 * w_inv_sqrt[None, :]
    gram = A @ A.T
    eye = xp.eye(A.shape[0], dtype=A.dtype)
    dot1 = w_inv_sqrt * (A.T @ spd_solve(gram + damping ** 2 * eye, v1, xp=xp))
    N1 = xp.eye(J1.shape[1], dtype=J1.dtype) - w_inv_sqrt[:, None] * (A.T @ spd_solve(gram, J1, xp=xp))
    C = J2 @ N1
    eye2 = xp.eye(C.shape[0], dtype=C.dtype)
    dot2 = N1 @ (C.T @ spd_solve(C @ C.T + SECOND_TASK_DAMPING ** 2 * eye2, v2 - J2 @ dot1, xp=xp))
    return dot1 + dot2, dot2, N1


def limited_rates(J1, v1, J2, v2, w_inv_sqrt, damping, arm, lo, hi, xp=np):
    """:func:`task_priority` with the arm's rates kept within ``[lo, hi]``.

    Each pass fixes the arm joints whose rate leaves its bounds at the bound they cross (their
    weight set to 0, their motion taken off both tasks' velocities) and solves again for the
    rest; ``len(arm)`` passes at most. Whatever still crosses a bound after them (a task the free
    joints cannot do) is met by scaling all the rates down by the one factor that brings the
    worst inside: ``lo ≤ 0 ≤ hi`` makes that always possible.

    Args:
      arm: ``(n,)`` int, the arm's coordinates in ζ; lo, hi: ``(n,)`` their rate bounds
        [rad/s], ``lo ≤ 0 ≤ hi``.
      the rest: as :func:`task_priority`.

    Returns:
      ``(ζ̇ (m,), limited)``: the rates, the arm's within ``[lo, hi]``, and whether a bound was
      active (a bool scalar).
    """
    m, w_inv_sqrt = J1.shape[1], xp.asarray(w_inv_sqrt)
    fixed = xp.zeros(arm.shape[0], dtype=bool)
    fixed_rate = xp.zeros(arm.shape[0], dtype=J1.dtype)
    for _ in range(arm.shape[0] + 1):
        w = _scatter(w_inv_sqrt, arm, xp.where(fixed, 0.0, w_inv_sqrt[arm]), xp)
        held = _scatter(xp.zeros(m, dtype=J1.dtype), arm, xp.where(fixed, fixed_rate, 0.0), xp)
        rates, _, _ = task_priority(J1, v1 - J1 @ held, J2, v2 - J2 @ held, w, damping, xp=xp)
        rates = rates + held
        q_dot = rates[arm]
        out = ~fixed & ((q_dot < lo) | (q_dot > hi))
        fixed_rate = xp.where(out, xp.clip(q_dot, lo, hi), fixed_rate)
        fixed = fixed | out
        if xp is np and not out.any():  # the passes left would repeat this one (jit: a fixed count)
            break
    q_dot = rates[arm]
    above, below = q_dot > hi, q_dot < lo  # q̇ > hi ≥ 0 or q̇ < lo ≤ 0: q̇ ≠ 0 there
    factor = xp.where(above, hi / xp.where(above, q_dot, 1.0), xp.where(below, lo / xp.where(below, q_dot, 1.0), 1.0))
    return rates * xp.min(factor), xp.any(fixed) | xp.any(above | below)


def _set(a, idx, values):
    a = a.copy()
    a[idx] = values
    return a


def _scatter(a, idx, values, xp):
    return _set(a, idx, values) if xp is np else a.at[idx].set(values)


def link_motion(twists, q_dot, q_ddot, xp=np):
    """Velocities and accelerations of the links of a serial chain on a base at rest.

    Args:
      twists: ``(n, 6)`` the joints' spatial twists ``ξ'_j = [v'_j, ω'_j]`` at the present pose,
        in the base frame (:func:`uvms_jax.kin.kinematics`' ``twists``).
      q_dot, q_ddot: ``(n,)`` joint rates [rad/s] and accelerations [rad/s²].

    Returns:
      ``(V (n, 6), A (n, 6))``: each link's spatial velocity ``Σ_{j≤i} ξ'_j q̇_j`` and its time
      derivative ``Σ_{j≤i} (ξ'_j q̈_j + [V_{j−1}, ξ'_j] q̇_j)`` (the twist of joint j turns with
      the body carrying it: ``d ξ'_j/dt = ad(V_{j−1}) ξ'_j``), as ``[v, ω]`` — v the velocity of
      the body point at the base's origin.
    """
    terms = twists * q_dot[:, None]
    V = xp.cumsum(terms, axis=0)
    before = V - terms  # V_{j-1}: the body carrying joint j
    v_b, w_b, v_j, w_j = before[:, :3], before[:, 3:], twists[:, :3], twists[:, 3:]
    bracket = xp.concatenate([xp.cross(w_b, v_j) + xp.cross(v_b, w_j), xp.cross(w_b, w_j)], axis=-1)
    A = xp.cumsum(twists * q_ddot[:, None] + bracket * q_dot[:, None], axis=0)
    return V, A


def _part_poses(T_base, T_link, parts: ArmParts, xp=np):
    """``(R (P, 3, 3), com (P, 3), cob (P, 3))`` of the parts in the base frame; ``T_base``
    ``(4, 4)`` the arm's base, ``T_link`` ``(n, 4, 4)`` its links' frames."""
    T = xp.concatenate([T_base[None], T_link], axis=0)[parts.body + 1]
    R = T[:, :3, :3]
    return (R, T[:, :3, 3] + xp.einsum("pij,pj->pi", R, parts.com),
            T[:, :3, 3] + xp.einsum("pij,pj->pi", R, parts.cob))


def arm_momentum_rate(T_base, T_link, twists, q_dot, q_ddot, parts: ArmParts, xp=np):
    """``(6,)`` the rate of change of the arm's linear and angular momentum (about the frame's
    origin), the frame's base held at rest: ``(Σ m a_c, Σ c × m a_c + I α + ω × I ω)`` [N, N·m].

    With the hull held still this is the wrench the hull must give the arm beyond the arm's
    weight, buoyancy and drag: the inverse dynamics of the arm's motion, seen at its mount.

    Args:
      T_base: ``(4, 4)`` the arm's base (mount) in the frame [m]; T_link: ``(n, 4, 4)`` the
        links' frames; twists: ``(n, 6)`` the joints' spatial twists (all from
        :func:`uvms_jax.kin.kinematics` of a chain on that frame); q_dot, q_ddot: ``(n,)``.
      parts: the arm's mass properties (:func:`arm_parts`).
    """
    V, A = link_motion(twists, q_dot, q_ddot, xp=xp)
    zero = xp.zeros((1, 6), dtype=V.dtype)
    V, A = xp.concatenate([zero, V])[parts.body + 1], xp.concatenate([zero, A])[parts.body + 1]
    R, c, _ = _part_poses(T_base, T_link, parts, xp=xp)
    w, alpha = V[:, 3:], A[:, 3:]
    v_c = V[:, :3] + xp.cross(w, c)
    a_c = A[:, :3] + xp.cross(alpha, c) + xp.cross(w, v_c)
    I = R @ parts.inertia @ xp.swapaxes(R, -1, -2)
    force = parts.mass[:, None] * a_c
    moment = xp.cross(c, force) + xp.einsum("pij,pj->pi", I, alpha) + xp.cross(w, xp.einsum("pij,pj->pi", I, w))
    return xp.concatenate([force.sum(axis=0), moment.sum(axis=0)])


def hydrostatic_wrench(R_world_vehicle, T_base, T_link, parts: ArmParts, hull_mass, hull_volume, hull_cob, density,
                       gravity, xp=np):
    """``(6,)`` the weight and buoyancy of the hull and the arm, in V about V's origin [N, N·m].

    Args:
      R_world_vehicle: ``(3, 3)`` V's orientation (it sets the direction of gravity in V).
      T_base, T_link: the arm's base and links in V (:func:`arm_momentum_rate`).
      parts: the arm's mass properties; hull_mass [kg], hull_volume [m³], hull_cob ``(3,)`` [m in V].
      density: water [kg/m³]; gravity: [m/s²] along the world's −z.
    """
    g = R_world_vehicle.T @ xp.asarray([0.0, 0.0, -gravity], dtype=R_world_vehicle.dtype)  # in V
    _, com, cob = _part_poses(T_base, T_link, parts, xp=xp)
    points = xp.concatenate([xp.zeros((1, 3), dtype=com.dtype), xp.asarray(hull_cob, dtype=com.dtype)[None], com, cob])
    per_mass = xp.concatenate([xp.asarray([hull_mass, -density * hull_volume], dtype=com.dtype), parts.mass,
                               -density * parts.volume])
    forces = per_mass[:, None] * g[None, :]
    return xp.concatenate([forces.sum(axis=0), xp.cross(points, forces).sum(axis=0)])


def drag_wrench(R_world_vehicle, body_com, body_frame, box, body_cvel, root_com, current, density, viscosity, xp=np):
    """``(6,)`` MuJoCo's inertia-box drag on every body, the hull held still and the arm moving,
    in water moving at ``current``, in V about V's origin [N, N·m]
    (:func:`~uvms_jax.hover.fluid_xfrc`).

    Args:
      R_world_vehicle: ``(3, 3)`` V's orientation (turns the current into V).
      body_com ``(k, 3)`` [m] and body_frame ``(k, 3, 3)``: the bodies' centres of mass and
        inertia frames in V; box: ``(k, 3)`` their equivalent boxes [m]
        (:func:`~uvms_jax.hover.fluid_bodies`).
      body_cvel: ``(k, 6)`` their com-based velocities ``(ω, v)`` in V (``MjData.cvel``; zeros
        for bodies at rest) and root_com ``(k, 3)`` the point v is taken at [m, rad/s, m].
      current: ``(3,)`` the water's velocity in the world [m/s].
      density, viscosity: the water's [kg/m³], [Pa·s].
    """
    rows = fluid_xfrc(body_com, body_frame, body_cvel, root_com, box, density, viscosity, R_world_vehicle.T @ current,
                      xp=xp)
    return xp.concatenate([rows[:, :3].sum(axis=0), (rows[:, 3:] + xp.cross(body_com, rows[:, :3])).sum(axis=0)])
