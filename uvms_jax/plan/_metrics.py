"""Per-edge metrics of the thesis (4.7.4): planning time, joint movement, end-effector
distance, security (minimum clearance) and maximum static joint torque (the arm's own weight
and buoyancy, and the held object's)."""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax import kin, sched
from uvms_jax import robot as robots

__all__ = ["EdgeMetrics", "static_torques", "trajectory_metrics"]

_EXACT = jax.lax.Precision.HIGHEST  # full float32 products on GPUs too (their default is TF32)

#: The five metrics of one edge (thesis definitions 1–5), fields named and ordered as
#: ``uvms_jax.sched.METRICS``: ``planning_time`` (planner wall time [s]), ``joint_movement``
#: (Σ over consecutive points and joints of |Δq| [rad]), ``ee_distance`` (Σ over consecutive
#: points of |Δp| of the tool point [m]), ``security`` (smallest arm–scene clearance along the
#: trajectory [m]) and ``max_torque`` (max over points and joints of the static |τ| of the
#: links' weight and buoyancy and the held object's net force [N·m], :func:`static_torques`).
#: ``tuple(m)`` is the metric row in ``sched.METRICS`` order.
EdgeMetrics = NamedTuple("EdgeMetrics", [(name, float) for name in sched.METRICS])
EdgeMetrics.__doc__ = "The five metrics of one edge, fields in ``uvms_jax.sched.METRICS`` order (see above)."


# Joint points per call of the compiled load torques: any path runs as calls of this many rows
# (the last padded with its last point), so one program serves every edge of every stage (each
# row count compiled the kinematics anew, ~1 s on a CPU).
ROWS = 64


def _pad(q: np.ndarray) -> np.ndarray:
    """Pad rows to a whole number of :data:`ROWS` with the last row."""
    return np.concatenate([q, np.repeat(q[-1:], -len(q) % ROWS, axis=0)])


def _point_loads(robot: robots.Robot, gravity_base, water_density: float, force_base):
    """The static point loads on the arm: ``(body (P,), local (P, 3) [m], force (P, 3) [N])``.

    ``body`` numbers the frame a point is fixed to: i < n the link turned by joint i (its
    frame ``T_base_joint[i]``), n the tool frame. Each link carries its weight ``m g`` at its
    centre of mass and its buoyancy ``−ρ V g`` at its centre of buoyancy (``robot.inertials``;
    an arm whose description has no mass properties carries none); the base link's loads turn
    no joint. The held object's force acts at the tool point.
    """
    g = np.asarray(gravity_base, dtype=float)
    if g.shape != (3,) or not np.all(np.isfinite(g)):
        raise ValueError(f"gravity_base must be a finite (3,) vector [m/s²], got {g}")
    if not (np.isfinite(water_density) and water_density >= 0):
        raise ValueError(f"water_density must be finite and non-negative [kg/m³], got {water_density}")
    n = robot.n_joints
    body, local, force = [n], [np.zeros(3)], [np.zeros(3) if force_base is None else np.asarray(force_base, float)]
    if force[0].shape != (3,) or not np.all(np.isfinite(force[0])):
        raise ValueError(f"force_base must be a finite (3,) vector [N] or None, got {force[0]}")
    if np.any(g != 0):
        for inertial in robot.inertials:
            if inertial.body == robots.BASE:
                continue
            body += [inertial.body, inertial.body]
            local += [np.asarray(inertial.com), np.asarray(inertial.cob)]
            force += [inertial.mass * g, -water_density * inertial.volume * g]
    return np.array(body), np.stack(local), np.stack(force)


@jax.jit
def _load_torques(chain: kin.Chain, q, body, local, force):
    """``(k, n)`` τ = Σ_points J_p(q)ᵀ f_p: each joint's static torque from the point loads
    fixed to the links it turns (arguments as :func:`_point_loads`, ``q (k, n)``), and the
    tool points ``(k, 3)`` [m] (one compiled call for both metrics that need kinematics)."""
    k = kin.kinematics(chain, q)
    frames = jnp.concatenate([k.T_base_joint, k.T_base_tool[..., None, :, :]], axis=-3)[..., body, :, :]
    p = jnp.einsum("...pij,pj->...pi", frames[..., :3, :3], local, precision=_EXACT) + frames[..., :3, 3]  # (k, P, 3)
    v, w = k.twists[..., None, :3], k.twists[..., None, 3:]  # (k, n, 1, 3)
    velocity = v + jnp.cross(w, p[..., None, :, :])  # (k, n, P, 3): point p under a unit rate of joint i
    turned = body[None, :] >= jnp.arange(chain.n_joints)[:, None]  # (n, P): joint i turns the links ≥ i
    tau = jnp.einsum("...ipc,pc,ip->...i", velocity, force.astype(velocity.dtype), turned.astype(velocity.dtype),
                     precision=_EXACT)
    return tau, k.T_base_tool[..., :3, 3]


def static_torques(robot: robots.Robot, q, *, gravity_base, water_density: float, force_base=None):
    """Static joint torques of the arm's weight and buoyancy and of a held object, ``(k, n)`` [N·m].

    ``τ = Σ_p J_p(q)ᵀ f_p`` over the point loads (thesis eq. 4.10 at every load point): each
    link's weight ``m g`` at its centre of mass and buoyancy ``−ρ V g`` at its centre of
    buoyancy (``robot.inertials``), and the held
    object's net force at the tool point; ``J_p`` is the point Jacobian (linear rows) of the
    load point. τ is the torque the loads put on the joints: the drives hold the pose with
    ``−τ`` (= MuJoCo's ``qfrc_bias`` at rest, = ∂U/∂q of the potential energy U).

    Args:
      robot: the arm.
      q: ``(k, n)`` joint points [rad].
      gravity_base: ``(3,)`` gravitational acceleration in the arm's base frame [m/s²]
        (``R_base_world @ [0, 0, −g]``; zeros: a weightless arm, only ``force_base`` counts).
      water_density: density of the water around the arm [kg/m³] (0: in air).
      force_base: ``(3,)`` net force of the held object on the tool point in the base frame
        [N] (``[0, 0, F_b − F_g]`` rotated into the base frame), or None (nothing held).

    Returns:
      ``(k, n)`` NumPy array of joint torques [N·m].
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[1] != robot.n_joints or not np.all(np.isfinite(q)):
        raise ValueError(f"q must be a finite (k, {robot.n_joints}) array, got shape {q.shape}")
    return _torques_and_tool(robot, q, gravity_base, water_density, force_base)[0]


def _torques_and_tool(robot: robots.Robot, q: np.ndarray, gravity_base, water_density: float, force_base):
    """:func:`static_torques` ``(k, n)`` and the tool points ``(k, 3)`` of checked ``q (k, n)``."""
    body, local, force = _point_loads(robot, gravity_base, water_density, force_base)
    dtype = jax.dtypes.canonicalize_dtype(np.float64)  # float64 where JAX has it enabled; cast on the host
    qp = _pad(q).astype(dtype)
    loads = jnp.asarray(body), jnp.asarray(local.astype(dtype)), jnp.asarray(force.astype(dtype))
    parts = [_load_torques(robot.chain, jnp.asarray(qp[i:i + ROWS]), *loads) for i in range(0, len(qp), ROWS)]
    tau, p = (np.concatenate([np.asarray(part[j]) for part in parts])[: len(q)] for j in range(2))
    return tau, p


def trajectory_metrics(
    robot: robots.Robot,
    q,
    force_base=None,
    *,
    gravity_base,
    water_density: float,
) -> tuple[float, float, float]:
    """Joint movement, end-effector distance and max static joint torque of a sequence of points.

    The sums run over consecutive points as given (pass the densely interpolated path to
    measure the arc length of the tool).

    Args:
      robot: the arm.
      q: ``(k, n)`` joint points [rad], k ≥ 1.
      force_base: ``(3,)`` force of the held object on the tool point in the arm's base frame
        [N] (``[0, 0, F_b − F_g]`` rotated into the base frame), or None (nothing held).
      gravity_base: ``(3,)`` gravitational acceleration in the arm's base frame [m/s²]
        (zeros: the arm's weight and buoyancy ignored).
      water_density: density of the water around the arm [kg/m³].

    Returns:
      ``(joint_movement [rad], ee_distance [m], max_torque [N·m])``, max_torque the largest
      |τ| over points and joints of :func:`static_torques`.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] != robot.n_joints or not np.all(np.isfinite(q)):
        raise ValueError(f"q must be a finite (k >= 1, {robot.n_joints}) array, got shape {q.shape}")
    joint_movement = float(np.sum(np.abs(np.diff(q, axis=0))))
    tau, p = _torques_and_tool(robot, q, gravity_base, water_density, force_base)
    ee_distance = float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))
    return joint_movement, ee_distance, float(np.max(np.abs(tau)))
