"""Station keeping on (x, y, z, ψ) and thrust allocation, as pure functions of arrays.

The controller is a PID per axis on the pose error in the world frame (position, and yaw
wrapped to (-π, π]); the demanded world force and yaw torque are turned into the vehicle frame
V, where the thrusters are fixed. Allocation solves ``B u = w`` for the thrusts ``u`` with the
pseudo-inverse of the thrust configuration matrix ``B`` (6 × n: each column a thruster's force
and its moment about V's origin) — the smallest thrusts in the 2-norm that give the wrench. A
solution that asks any thruster for more than its limit is scaled down as a whole, to the
largest multiple that fits: the wrench keeps its direction and loses magnitude, and no thrust
ever exceeds its limit. (A bounded least-squares solver would reach more of the thrusters'
attainable set; the scaled pseudo-inverse is exact inside ``{w : |B⁺w| ≤ u_max}``, cheap, and
the same code under ``jit``/``vmap``.)

Every function takes ``xp`` (``numpy`` or ``jax.numpy``) and accepts leading batch axes where
its docstring says so.
"""

from __future__ import annotations

import numpy as np

__all__ = ["allocate_thrust", "control_steps", "hold_pose", "level_attitude", "station_keeping", "thrust_layout",
           "thrust_matrix", "wrap_angle", "yaw_of_quat"]

# Float rounding allowed on a commanded thrust [N] or a joint target [rad] before it counts
# as outside its limit: a target computed on a limit may land 1 ulp beyond it.
LIMIT_SLACK = 1e-9


def thrust_matrix(positions, directions, xp=np):
    """The thrust configuration matrix of a thruster layout.

    Args:
      positions: ``(n, 3)`` thrusters' points of action in V [m].
      directions: ``(n, 3)`` thrust directions in V (normalised here).

    Returns:
      ``(6, n)`` B: column i is thruster i's wrench per newton, ``(d_i, p_i × d_i)`` (force, then
      moment about V's origin), so that ``B @ u`` is the wrench of thrusts ``u`` [N].
    """
    d = directions / xp.linalg.norm(directions, axis=-1, keepdims=True)
    return xp.concatenate([d, xp.cross(positions, d)], axis=-1).T


def allocate_thrust(wrench, B_pinv, limits, xp=np):
    """Thrusts that give ``wrench``, within the limits (scaled pseudo-inverse, module docstring).

    Args:
      wrench: ``(..., 6)`` demanded force [N] and moment about V's origin [N·m], in V.
      B_pinv: ``(n, 6)`` the pseudo-inverse of :func:`thrust_matrix`.
      limits: ``(n,)`` thrust limits [N] (> 0), the same both ways.

    Returns:
      ``(..., n)`` thrusts [N], ``|u_i| ≤ limits_i``: ``B⁺ w`` where that fits, otherwise
      ``B⁺ w / s`` with ``s = max_i |(B⁺w)_i| / limits_i`` (one thruster at its limit).
    """
    u = wrench @ B_pinv.T
    ratio = xp.max(xp.abs(u) / limits, axis=-1, keepdims=True)
    return u / xp.maximum(ratio, 1.0)


def wrap_angle(a):
    """Angles ``a`` [rad] wrapped to [-π, π) (NumPy or JAX arrays alike)."""
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def yaw_of_quat(quat, xp=np):
    """Yaw ψ [rad] of unit quaternions ``(..., 4)`` ``(w, x, y, z)``: the z angle of the URDF
    roll-pitch-yaw ``R = Rz(ψ) Ry(θ) Rx(φ)``."""
    w, x, y, z = quat[..., 0], quat[..., 1], quat[..., 2], quat[..., 3]
    return xp.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def station_keeping(error, velocity, yaw_rate, integral, R_world_vehicle, kp, kd, ki, integral_limit, integral_band,
                    dt, xp=np):
    """One step of the (x, y, z, ψ) PID: the wrench to demand in V and the next integral state.

    Args:
      error: ``(4,)`` reference less actual, world frame: position [m] and wrapped yaw [rad].
      velocity: ``(3,)`` the vehicle's linear velocity in the world [m/s].
      yaw_rate: the vehicle's angular velocity about the world's z [rad/s].
      integral: ``(4,)`` the error's running integral [m·s, rad·s] (the controller's state).
      R_world_vehicle: ``(3, 3)`` orientation of V in the world.
      kp, kd, ki, integral_limit, integral_band: ``(4,)`` gains, integral bounds and the
        errors within which the integral runs, of :class:`~uvms_jax.hover.ControllerSettings`.
      dt: control period [s].

    Returns:
      ``(wrench (6,), integral (4,))``: the demanded force [N] and moment [N·m] in V — the world
      force turned into V, and the yaw torque about the world's z turned into V (so at a tilt
      part of it lies on V's x and y) — and the updated integral: it grows on an axis only
      while that error is within ``integral_band`` (a large step is the P and D terms' work;
      integrating it too would overshoot and settle slowly), clamped so that
      ``ki · integral`` stays within ``integral_limit``.
    """
    bound = integral_limit / xp.maximum(ki, 1e-12)  # ki = 0: no bound needed, the term is 0
    growth = xp.where(xp.abs(error) <= integral_band, error, 0.0) * dt
    integral = xp.clip(integral + growth, -bound, bound)
    rate = xp.concatenate([velocity, xp.reshape(yaw_rate, (1,))])
    demand = kp * error - kd * rate + ki * integral  # (4,): world force, torque about world z
    zero2 = xp.zeros(2, dtype=demand.dtype)
    force = R_world_vehicle.T @ demand[:3]
    moment = R_world_vehicle.T @ xp.concatenate([zero2, demand[3:]])
    return xp.concatenate([force, moment]), integral


def level_attitude(R_world_vehicle, angular_velocity, kp, kd, xp=np):
    """The moment in V that levels the vehicle: a PD on roll and pitch, nothing about yaw.

    The hydrostatic restoring moment alone (centre of buoyancy a few cm above the centre of
    mass) lets an arm reaching out tilt the vehicle by many degrees, which the lever of the
    arm turns into centimetres at the tool; the vertical thrusters can hold it level.

    Args:
      R_world_vehicle: ``(3, 3)`` orientation of V in the world.
      angular_velocity: ``(3,)`` V's angular velocity in V [rad/s].
      kp, kd: gains [N·m/rad, N·m·s/rad] (0, 0: the hydrostatics alone).

    Returns:
      ``(3,)`` moment about V's x and y [N·m] (its z component 0): ``−kp (φ, θ) − kd (ω_x, ω_y)``
      with φ, θ the URDF roll and pitch of ``R``.
    """
    roll = xp.arctan2(R_world_vehicle[2, 1], R_world_vehicle[2, 2])
    pitch = -xp.arcsin(xp.clip(R_world_vehicle[2, 0], -1.0, 1.0))
    tilt = xp.stack([roll, pitch])
    return xp.concatenate([-kp * tilt - kd * angular_velocity[:2], xp.zeros(1, dtype=tilt.dtype)])


def thrust_layout(vehicle) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(B (6, n), B⁺ (n, 6), limits (n,) [N])`` of a vehicle's thrusters (:func:`thrust_matrix`)."""
    B = thrust_matrix(np.array([t.pos for t in vehicle.thrusters], dtype=float),
                      np.array([t.direction for t in vehicle.thrusters], dtype=float))
    return B, np.linalg.pinv(B), np.array([t.max_thrust for t in vehicle.thrusters], dtype=float)


def control_steps(period: float, physics_dt: float) -> int:
    """Physics steps per control period; raises ValueError unless ``period`` is a whole number
    of ``physics_dt`` [s]."""
    steps = round(period / physics_dt)
    if steps < 1 or abs(steps * physics_dt - period) > 1e-9:
        raise ValueError(f"controller period {period} s is not a whole number of physics steps of {physics_dt} s")
    return steps


def hold_pose(reference, position, quat, R_world_vehicle, velocity, angular_velocity, integral, controller, B_pinv,
              limits, xp=np):
    """One control period of the vehicle holding ``reference`` ``(4,) = [x, y, z, ψ]``:
    :func:`station_keeping` plus :func:`level_attitude`, allocated (:func:`allocate_thrust`).

    Args:
      position, quat: ``(3,)`` V's origin [m] and ``(4,)`` orientation ``(w, x, y, z)``;
        R_world_vehicle ``(3, 3)`` the same orientation.
      velocity: ``(3,)`` linear velocity in the world [m/s]; angular_velocity: ``(3,)`` in V
        [rad/s] (a free joint's ``qvel``).
      integral: ``(4,)`` the station keeping's state; controller: its
        :class:`~uvms_jax.hover.ControllerSettings`; B_pinv, limits: of :func:`thrust_layout`.

    Returns:
      ``(thrust (n,) [N], demand (6,) wrench in V [N, N·m], integral (4,))``.
    """
    c = controller
    gains = [xp.asarray(g, dtype=position.dtype) for g in (c.kp, c.kd, c.ki, c.integral_limit, c.integral_band)]
    error = xp.concatenate([reference[:3] - position, wrap_angle(reference[3:] - yaw_of_quat(quat, xp=xp))])
    yaw_rate = (R_world_vehicle @ angular_velocity)[2]
    demand, integral = station_keeping(error, velocity, yaw_rate, integral, R_world_vehicle, *gains, c.period, xp=xp)
    level = level_attitude(R_world_vehicle, angular_velocity, c.level_kp, c.level_kd, xp=xp)
    demand = demand + xp.concatenate([xp.zeros(3, dtype=demand.dtype), level])
    return allocate_thrust(demand, B_pinv, limits, xp=xp), demand, integral

