"""Per-edge metrics of the thesis (4.7.4): planning time, joint movement, end-effector
distance, security (minimum clearance) and maximum joint torque from the held object."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from uvms_jax import indices, kin, sched

__all__ = ["EdgeMetrics", "trajectory_metrics"]

#: The five metrics of one edge (thesis definitions 1–5), fields named and ordered as
#: ``uvms_jax.sched.METRICS``: ``planning_time`` (planner wall time [s]), ``joint_movement``
#: (Σ over consecutive points and joints of |Δq| [rad]), ``ee_distance`` (Σ over consecutive
#: points of |Δp| of the tool point [m]), ``security`` (smallest arm–scene clearance along the
#: trajectory [m]) and ``max_torque`` (max over points and joints of |τ|, τ = Jᵀ w, w the held
#: object's wrench [N·m]). ``tuple(m)`` is the metric row in ``sched.METRICS`` order.
EdgeMetrics = NamedTuple("EdgeMetrics", [(name, float) for name in sched.METRICS])
EdgeMetrics.__doc__ = "The five metrics of one edge, fields in ``uvms_jax.sched.METRICS`` order (see above)."


def _pad(q: np.ndarray) -> np.ndarray:
    """Pad rows to the next power of two (≥ 64) so that jitted FK compiles for few shapes."""
    n = max(64, 1 << int(np.ceil(np.log2(max(len(q), 1)))))
    return np.concatenate([q, np.repeat(q[-1:], n - len(q), axis=0)])


def trajectory_metrics(
    chain: kin.Chain,
    q,
    force_base=None,
) -> tuple[float, float, float]:
    """Joint movement, end-effector distance and max joint torque of a sequence of points.

    The sums run over consecutive points as given (pass the densely interpolated path to
    measure the arc length of the tool).

    Args:
      chain: the arm (``kin.bravo7()``).
      q: ``(k, n)`` joint points [rad], k ≥ 1.
      force_base: ``(3,)`` force of the held object on the tool point in the arm's base frame
        [N] (``[0, 0, F_b − F_g]`` rotated into the base frame), or None (nothing held: 0).

    Returns:
      ``(joint_movement [rad], ee_distance [m], max_torque [N·m])``.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] != chain.n_joints or not np.all(np.isfinite(q)):
        raise ValueError(f"q must be a finite (k >= 1, {chain.n_joints}) array, got shape {q.shape}")
    joint_movement = float(np.sum(np.abs(np.diff(q, axis=0))))
    qp = jnp.asarray(_pad(q))
    p = np.asarray(kin.fk(chain, qp))[: len(q), :3, 3]
    ee_distance = float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))
    if force_base is None:
        return joint_movement, ee_distance, 0.0
    wrench = jnp.concatenate([jnp.asarray(force_base, dtype=qp.dtype), jnp.zeros(3, dtype=qp.dtype)])
    tau = np.asarray(indices.joint_torques(kin.jacobian(chain, qp), wrench))[: len(q)]
    return joint_movement, ee_distance, float(np.max(np.abs(tau)))
