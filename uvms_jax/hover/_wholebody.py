"""The whole-body controller of one plan at one docked pose: its constants, the plan's data per
control period, and one control period's commands (:class:`WholeBody`).

The formulas are the pure functions of :mod:`uvms_jax.hover._wbc`; this module computes what
they need once per plan (the tool's planned poses, the arm's inverse dynamics along the plan,
the bodies' poses for the drag) and, each period, the vehicle's displacement from a navigation
estimate and the kinematics of :func:`uvms_jax.kin.uvms` at it.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from uvms_jax import frames, kin
from uvms_jax.robot import Robot

from ._control import LIMIT_SLACK, allocate_thrust, level_attitude, station_keeping, thrust_layout, wrap_angle
from ._hydro import fluid_bodies
from ._model import VEHICLE_BODY
from ._settings import ControllerSettings, NavigationSettings, VehicleSettings, WholeBodySettings
from ._wbc import (ArmParts, arm_momentum_rate, drag_wrench, hydrostatic_wrench, limited_rates, pose_error)

# The tool's pose and Jacobian in one compiled pass, without kin.fk's input checks: the
# controller builds ζ itself, every period (one dispatch instead of two checked ones).
_pose_and_jacobian = jax.jit(kin.pose_and_jacobian_of)

__all__ = ["NavigationEstimate", "WholeBody", "WholeBodyCommand", "arm_parts", "euler_xyz"]

_VEHICLE = 6  # the vehicle's coordinates in ζ = (η, q)


def arm_parts(robot: Robot) -> ArmParts:
    """The arm's mass properties (``robot.inertials``) as arrays (:class:`ArmParts`)."""
    parts = [p for p in robot.inertials if p.mass > 0]
    inertia = [np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) for xx, yy, zz, xy, xz, yz in
               (p.inertia for p in parts)]
    return ArmParts(body=np.array([p.body for p in parts], dtype=int), mass=np.array([p.mass for p in parts]),
                    com=np.array([p.com for p in parts], dtype=float).reshape(-1, 3),
                    inertia=np.array(inertia).reshape(-1, 3, 3), volume=np.array([p.volume for p in parts]),
                    cob=np.array([p.cob if p.volume > 0 else p.com for p in parts], dtype=float).reshape(-1, 3))


def euler_xyz(R, xp=np):
    """``(3,)`` XYZ Euler angles [rad] of ``R = Rx(a) Ry(b) Rz(c)`` (|b| < π/2)."""
    return xp.stack([xp.arctan2(-R[1, 2], R[2, 2]), xp.arcsin(xp.clip(R[0, 2], -1.0, 1.0)),
                     xp.arctan2(-R[0, 1], R[0, 0])])


class WholeBodyCommand(NamedTuple):
    """One control period's commands.

    Attributes:
      target: ``(n,)`` the arm's joint targets [rad], within the joint limits.
      reference: ``(n,)`` the arm's reference at the period's end [rad] (the next state).
      thrust: ``(n_thrusters,)`` [N], within the thrusters' limits; demand: ``(6,)`` the wrench
        asked for in V [N, N·m]; integral: ``(4,)`` the station keeping's next state.
      joint_limited, thrust_limited: (bool scalars) a joint rate bound was active; the
        allocation scaled the demand down to the thrusters' limits.
    """

    target: np.ndarray
    reference: np.ndarray
    thrust: np.ndarray
    demand: np.ndarray
    integral: np.ndarray
    joint_limited: np.ndarray
    thrust_limited: np.ndarray


class WholeBody:
    """The whole-body controller for ``q_plan`` at the docked ``pose``.

    Args:
      robot: the arm; vehicle: the vehicle as ballasted (its hull's mass, volume and centre of
        buoyancy are the hydrostatics' feed-forward), its mount the docking problem's.
      controller: the thrusters' PID, levelling and period; settings: the whole-body controller.
      pose: ``(4,)`` the docked pose ``[x, y, z, ψ]`` [m, rad].
      q_plan: ``(K, n)`` the plan's joint angles at every control period [rad]: the tool's path
        is the docked arm's forward kinematics along it.
      model: the hovering vehicle's MuJoCo model (the bodies' equivalent boxes for the drag).
    """

    def __init__(self, robot: Robot, vehicle: VehicleSettings, controller: ControllerSettings,
                 settings: WholeBodySettings, pose, q_plan: np.ndarray, model: mujoco.MjModel) -> None:
        self.robot, self.vehicle, self.controller, self.settings = robot, vehicle, controller, settings
        pose = np.asarray(pose, dtype=float)
        self.pose, self.dt = pose, controller.period
        self.T_dock = frames.pose(frames.rot_z(pose[3]), pose[:3])
        self.T_base = frames.rpy_pose(vehicle.mount_xyz, vehicle.mount_rpy)
        self.chain = kin.uvms(robot.chain, mount=self.T_base)
        self.parts = arm_parts(robot)
        _, self.B_pinv, self.thrust_limits = thrust_layout(vehicle)
        n = robot.n_joints
        self.arm = np.arange(_VEHICLE, _VEHICLE + n)
        self.w_inv_sqrt = np.sqrt(np.concatenate([np.full(_VEHICLE, settings.vehicle_weight), np.ones(n)]))
        self.J2 = np.concatenate([np.eye(_VEHICLE), np.zeros((_VEHICLE, n))], axis=1)
        self.lower, self.upper = np.asarray(robot.lower, float), np.asarray(robot.upper, float)
        self.rate_limit = np.asarray(robot.chain.velocity_limits, dtype=float)
        self.gains = [np.asarray(g, dtype=float) for g in (controller.kp, controller.kd, controller.ki,
                                                           controller.integral_limit, controller.integral_band)]
        self._plan(np.asarray(q_plan, dtype=float), model)

    def _plan(self, q: np.ndarray, model: mujoco.MjModel) -> None:
        """The plan's data per period, the vehicle at the docked pose: the tool's poses in V₀
        and their rate, the arm's momentum rate, its links' frames, the bodies' poses and
        velocities in V."""
        dt = self.dt
        smooth = _smoothed(q, round(self.settings.smoothing_s / dt))
        padded = np.concatenate([smooth[:1], smooth, smooth[-1:]])
        q_dot, q_ddot = (padded[2:] - padded[:-2]) / (2 * dt), (padded[2:] - 2 * smooth + padded[:-2]) / dt ** 2
        self.q_dot, self.q_ddot = q_dot, q_ddot
        zeta = np.concatenate([np.zeros((len(q), _VEHICLE)), q], axis=1)
        k = kin.kinematics(self.chain, zeta)
        self.T_tool = np.asarray(k.T_base_tool, dtype=float)
        self.T_link = np.asarray(k.T_base_joint, dtype=float)[:, _VEHICLE:]
        twists = np.asarray(k.twists, dtype=float)[:, _VEHICLE:]
        ahead = np.concatenate([self.T_tool[1:], self.T_tool[-1:]])
        self.tool_rate = pose_error(ahead, self.T_tool) / dt
        self.momentum_rate = np.array([arm_momentum_rate(self.T_base, T, tw, qd, qdd, self.parts)
                                       for T, tw, qd, qdd in zip(self.T_link, twists, q_dot, q_ddot)])
        # The bodies' centres of mass, inertia frames and velocities in V (the vehicle held still at
        # V's origin, level), as MuJoCo's kinematics give them: what the drag acts on.
        ids, self.box = fluid_bodies(model)
        data = mujoco.MjData(model)
        joints = [model.joint(j) for j in self.robot.joint_names]
        qadr, dadr = [model.jnt_qposadr[j.id] for j in joints], [model.jnt_dofadr[j.id] for j in joints]
        free = model.jnt_qposadr[model.body(VEHICLE_BODY).jntadr[0]]
        rows = []
        for row, rate in zip(q, q_dot):
            data.qpos[free:free + 7] = (0, 0, 0, 1, 0, 0, 0)
            data.qpos[qadr], data.qvel[:], data.qvel[dadr] = row, 0.0, rate
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)
            mujoco.mj_comVel(model, data)
            rows.append((data.xipos[ids].copy(), data.ximat[ids].reshape(-1, 3, 3).copy(), data.cvel[ids].copy(),
                         data.subtree_com[model.body_rootid[ids]].copy()))
        self.body_com, self.body_frame, self.body_cvel, self.root_com = map(np.array, zip(*rows))

    def _at(self, table: np.ndarray, k, xp):
        """Row ``k`` (clamped to the plan's last) of a per-period table, a traced index under ``jit``."""
        return xp.asarray(table)[xp.minimum(k, len(table) - 1)]

    def feed_forward(self, k, R_world_vehicle, current, current_rate, xp=np):
        """``(6,)`` the wrench in V that holds the hull still at period ``k`` of the plan
        [N, N·m]: ``ṗ_arm − w_hydrostatic − w_drag − w_added_mass`` (module docstring of
        :mod:`uvms_jax.hover._wbc`), with the water at ``current`` [m/s] changing at
        ``current_rate`` [m/s²] (world frame)."""
        v, at = self.vehicle, functools.partial(self._at, k=k, xp=xp)
        hydro = hydrostatic_wrench(R_world_vehicle, self.T_base, at(self.T_link), self.parts, v.mass, v.volume,
                                   v.cob, v.water_density, v.gravity, xp=xp)
        drag = drag_wrench(R_world_vehicle, at(self.body_com), at(self.body_frame), self.box, at(self.body_cvel),
                           at(self.root_com), current, v.water_density, v.viscosity, xp=xp)
        added = xp.concatenate([xp.asarray(self.settings.added_mass) * (R_world_vehicle.T @ current_rate),
                                xp.zeros(3)])
        return at(self.momentum_rate) - hydro - drag - added

    def displacement(self, position, R_world_vehicle, xp=np):
        """``(6,)`` η: the vehicle's displacement from the docked pose, in V₀ (translation [m],
        XYZ Euler angles [rad]), from its position [m] and orientation in the world."""
        R_dock = xp.asarray(self.T_dock[:3, :3])
        return xp.concatenate([R_dock.T @ (position - self.T_dock[:3, 3]),
                               euler_xyz(R_dock.T @ R_world_vehicle, xp=xp)])

    def step(self, k, position, R_world_vehicle, velocity, angular_velocity, q_ref, integral, current, current_rate,
             xp=np) -> WholeBodyCommand:
        """The commands of control period ``k`` from the navigation estimate (``xp``: ``numpy``, or
        ``jax.numpy`` under ``jit`` with ``k`` traced too).

        Args:
          position, R_world_vehicle: V's origin [m] and orientation in the world; velocity:
            ``(3,)`` its linear velocity in the world [m/s]; angular_velocity: ``(3,)`` in V
            [rad/s].
          q_ref: ``(n,)`` the arm's reference [rad] (within the limits); integral: ``(4,)``.
          current, current_rate: the water's velocity [m/s] and its rate [m/s²] as measured.
        """
        s, dt, R = self.settings, self.dt, R_world_vehicle
        R_dock = xp.asarray(self.T_dock[:3, :3])
        eta = self.displacement(position, R, xp=xp)
        # η̇: the translations along V₀; the Euler rates taken as V₀'s angular velocity (the
        # vehicle stays within a few degrees of level and of the docked heading).
        eta_dot = xp.concatenate([R_dock.T @ velocity, R_dock.T @ (R @ angular_velocity)])
        zeta = xp.concatenate([eta + s.prediction_s * eta_dot, q_ref])
        T, J = (xp.asarray(a) for a in _pose_and_jacobian(self.chain, zeta))
        v1 = self._at(self.tool_rate, k, xp) + s.tool_gain / dt * pose_error(self._at(self.T_tool, k, xp), T, xp=xp)
        lead = dt + s.servo_lead_s
        # Bounds LIMIT_SLACK inside the limits: the target then lies inside them exactly, rounding
        # included (a demand one ulp past a limit is refused by the arm's client).
        lo = xp.minimum(0.0, xp.maximum(-self.rate_limit, (self.lower + LIMIT_SLACK - q_ref) / lead))
        hi = xp.maximum(0.0, xp.minimum(self.rate_limit, (self.upper - LIMIT_SLACK - q_ref) / lead))
        S = xp.asarray([1.0, 1.0, 1.0] + [s.orientation_length] * 3)  # rows in [m/s]: position first
        rates, joint_limited = limited_rates(S[:, None] * J, S * v1, self.J2, -s.station_gain * eta, self.w_inv_sqrt,
                                             s.damping, self.arm, lo, hi, xp=xp)
        q_dot = rates[self.arm]
        thrust, demand, integral, saturated = self.thrust(k, position, R, velocity, angular_velocity, integral,
                                                          current, current_rate, rates[:_VEHICLE], xp=xp)
        return WholeBodyCommand(target=q_ref + lead * q_dot, reference=q_ref + dt * q_dot, thrust=thrust,
                                demand=demand, integral=integral, joint_limited=joint_limited,
                                thrust_limited=saturated)

    def thrust(self, k, position, R_world_vehicle, velocity, angular_velocity, integral, current, current_rate,
               vehicle_rates=None, xp=np) -> tuple:
        """The thrusters' part of period ``k`` (arguments as :meth:`step`): the PID holding the
        docked pose while tracking ``vehicle_rates`` ``(6,)`` (the vehicle's share of the tasks'
        rates, η̇ in V₀; None: at rest), the levelling and, with ``settings.feed_forward``, the
        feed-forward wrench, allocated.

        Returns:
          ``(thrust (n_thrusters,) [N], demand (6,) [N, N·m] in V, integral (4,), limited)``:
          limited (a bool scalar) when the allocation scaled the demand down to the limits.
        """
        R, R_dock = R_world_vehicle, xp.asarray(self.T_dock[:3, :3])
        rates = xp.zeros(_VEHICLE) if vehicle_rates is None else vehicle_rates
        yaw_error = wrap_angle(self.pose[3] - xp.arctan2(R[1, 0], R[0, 0]))
        error = xp.concatenate([self.pose[:3] - position, xp.reshape(yaw_error, (1,))])
        yaw_rate = (R @ angular_velocity)[2]
        demand, integral = station_keeping(error, velocity - R_dock @ rates[:3], yaw_rate - rates[5], integral, R,
                                           *self.gains, self.dt, xp=xp)
        demand = demand + xp.concatenate([xp.zeros(3), level_attitude(R, angular_velocity, self.controller.level_kp,
                                                                      self.controller.level_kd, xp=xp)])
        if self.settings.feed_forward:
            demand = demand + self.feed_forward(k, R, current, current_rate, xp=xp)
        saturated = xp.max(xp.abs(self.B_pinv @ demand) / self.thrust_limits) > 1.0
        return allocate_thrust(demand, self.B_pinv, self.thrust_limits, xp=xp), demand, integral, saturated


def _smoothed(q: np.ndarray, width: int) -> np.ndarray:
    """``q (K, n)`` averaged over ``width`` rows twice (a box, twice: triangular weights of
    ``2 width − 1`` rows), its first and last rows held beyond its ends; ``width ≤ 1``: ``q``."""
    if width <= 1:
        return q
    box = np.ones(width) / width
    for _ in range(2):
        padded = np.concatenate([np.repeat(q[:1], width // 2, 0), q, np.repeat(q[-1:], (width - 1) // 2, 0)])
        q = np.stack([np.convolve(padded[:, j], box, mode="valid") for j in range(q.shape[1])], axis=1)
    return q


def _rotation(rotvec) -> np.ndarray:
    """``(3, 3)`` the rotation by the rotation vector ``rotvec`` (axis × angle [rad])."""
    return Rotation.from_rotvec(rotvec).as_matrix()


class NavigationEstimate:
    """The vehicle's pose as a navigation with :class:`NavigationSettings` estimates it.

    A fix describes the true pose at its instant (fixes every ``1 / rate_hz`` s; the pose
    recorded last at or before that instant, a control period's), with Gaussian noise on the
    position and a rotation of Gaussian angles about V's axes, and arrives ``latency_s`` later.
    The estimate is carried forward from call to call by the vehicle's own motion (dead
    reckoning: the change of pose since the last call, as a DVL and a gyro integrated at their
    own high rate give it, taken as exact here; sampling their velocities once per control
    period would alias the hull's vibration into drift); each fix that arrives corrects it
    by ``fix_gain`` of its innovation (the fix less the estimate of the fix's instant), a
    complementary filter: with exact dead reckoning its error is the fixes' noise averaged, of
    standard deviation ``sqrt(g / (2 − g))`` times theirs for gain g (1: the newest fix carried
    forward). It starts at the true starting pose (the vehicle starts docked, where it knows
    its pose).
    """

    def __init__(self, settings: NavigationSettings, position, R_world_vehicle) -> None:
        self.settings = settings
        self._rng = np.random.default_rng(settings.seed)
        self._truth: list[tuple[float, np.ndarray, np.ndarray]] = []
        self._estimates: list[tuple[float, np.ndarray, np.ndarray]] = []
        start = (np.asarray(position, dtype=float), np.asarray(R_world_vehicle, dtype=float))
        self._state, self._last_truth = start, start
        self._next = 0  # the next fix's number

    def estimate(self, t: float, position, R_world_vehicle) -> tuple[np.ndarray, np.ndarray]:
        """``(position (3,) [m], R (3, 3))`` at time ``t`` [s], given the true pose now (its
        change since the last call is the dead reckoning; recorded for the fixes to come)."""
        s = self.settings
        position, R_true = np.asarray(position, dtype=float), np.asarray(R_world_vehicle, dtype=float)
        (p, R), (p_last, R_last) = self._state, self._last_truth
        p, R = p + (position - p_last), R @ (R_last.T @ R_true)  # the move in the world, the turn in V
        self._last_truth = (position, R_true)
        self._truth.append((t, position, R_true))
        self._estimates.append((t, p, R))
        while self._next / s.rate_hz + s.latency_s <= t + 1e-12:
            t_fix = self._next / s.rate_hz
            row = next(i for i in range(len(self._truth) - 1, -1, -1) if self._truth[i][0] <= t_fix + 1e-12)
            _, p_true, R_true = self._truth[row]
            p_fix = p_true + self._rng.normal(0.0, s.position_noise_m, 3)
            R_fix = R_true @ _rotation(self._rng.normal(0.0, np.radians(s.angle_noise_deg), 3))
            _, p_then, R_then = self._estimates[row]
            p = p + s.fix_gain * (p_fix - p_then)
            R = R @ _rotation(s.fix_gain * Rotation.from_matrix(R_then.T @ R_fix).as_rotvec())
            self._next += 1
        self._state = (p, R)
        return p, R
