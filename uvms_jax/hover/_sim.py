"""The hovering vehicle in MuJoCo on the CPU: physics steps, buoyancy, current, station keeping.

:class:`HoverSim` owns one ``MjModel``/``MjData`` (:func:`~uvms_jax.hover.hover_model`) and runs
it in control periods: at each tick it reads the vehicle's pose, computes the station-keeping
wrench and the thrusts (or takes commanded thrusts), sets the arm's joint targets, then takes
``period / physics_dt`` physics steps. Every physics step sets the current (``opt.wind``) for
its time and the bodies' buoyancy for their pose between MuJoCo's position stage and its
acceleration stage (``mj_step1`` / ``mj_step2``), so the lift always matches the pose being
integrated. The formulas are the pure functions of :mod:`uvms_jax.hover._hydro` and
:mod:`uvms_jax.hover._control`; this class only moves arrays in and out of MuJoCo.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.robot import TOOL_SITE, Robot

from ._control import control_steps, hold_pose, thrust_layout
from ._hydro import current_at
from ._model import VEHICLE_BODY, apply_buoyancy, buoyancy_bodies, hover_model, servo_name, thruster_name
from ._settings import ControllerSettings, CurrentSettings, VehicleSettings

__all__ = ["HoverLog", "HoverSim", "arm_motion"]

_LIMIT_SLACK = 1e-9  # [N; rad] float rounding allowed on a commanded thrust or joint target


@dataclasses.dataclass(frozen=True)
class HoverLog:
    """What :meth:`HoverSim.run` records: the state at the start and after every control period.

    Attributes (k rows; world frame W unless said):
      time: ``(k,)`` [s].
      position: ``(k, 3)`` V's origin (the hull's centre of mass) [m].
      quat: ``(k, 4)`` V's orientation ``(w, x, y, z)``.
      rpy: ``(k, 3)`` the same as URDF roll, pitch, yaw [rad].
      velocity: ``(k, 3)`` V's origin's linear velocity [m/s].
      angular_velocity: ``(k, 3)`` V's angular velocity, in V [rad/s].
      thrust: ``(k, n_thrusters)`` thrust commands held over the period that ends at the row
        [N] (the first row: zeros).
      demand: ``(k, 6)`` the station keeping's wrench in V for that period [N, N·m] (zeros
        when it is off or thrusts were commanded).
      q: ``(k, n_joints)`` arm joint angles [rad]; q_target: their servo targets [rad].
      tool: ``(k, 3)`` the arm's tool frame origin (``uvms_jax.robot.TOOL_SITE``) [m]; NaN
        without an arm.
      com: ``(k, 3)`` the whole system's centre of mass [m].
      current: ``(k, 3)`` the water's velocity [m/s].
    """

    time: np.ndarray
    position: np.ndarray
    quat: np.ndarray
    rpy: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    thrust: np.ndarray
    demand: np.ndarray
    q: np.ndarray
    q_target: np.ndarray
    tool: np.ndarray
    com: np.ndarray
    current: np.ndarray


def arm_motion(q_from: Sequence[float], q_to: Sequence[float], t_start: float,
               t_end: float) -> Callable[[float], np.ndarray]:
    """Joint targets that move from ``q_from`` to ``q_to`` [rad] between ``t_start`` and
    ``t_end`` [s] along the minimum-jerk blend ``10s³ − 15s⁴ + 6s⁵`` (zero speed and
    acceleration at both ends), held outside that interval: an ``arm_trajectory`` for
    :meth:`HoverSim.run`."""
    a, b = np.asarray(q_from, dtype=float), np.asarray(q_to, dtype=float)
    if a.shape != b.shape or not t_end > t_start:
        raise ValueError(f"arm_motion: q_from {a.shape} and q_to {b.shape} must match, t_end > t_start")

    def target(t: float) -> np.ndarray:
        s = min(max((t - t_start) / (t_end - t_start), 0.0), 1.0)
        return a + (b - a) * (s ** 3 * (10.0 - 15.0 * s + 6.0 * s * s))

    return target


class HoverSim:
    """The vehicle with its arm in open water, station keeping on (x, y, z, ψ).

    Args:
      robot: the arm, or None (the hull alone).
      vehicle: hull, water and thrusters.
      controller: station keeping; its reference is the starting pose (:meth:`set_reference`).
      current: the water's velocity over time.
      xyz, rpy: the vehicle's starting pose [m; URDF roll, pitch, yaw, rad].
      q0: ``(n_joints,)`` the arm's starting angles and servo targets [rad] (default: the middle
        of its joint ranges).
      physics_dt: MuJoCo's step [s]; ``controller.period`` must be a whole number of them.
    """

    def __init__(self, robot: Robot | None, vehicle: VehicleSettings = VehicleSettings(),
                 controller: ControllerSettings = ControllerSettings(), current: CurrentSettings = CurrentSettings(),
                 *, xyz: Sequence[float] = (0.0, 0.0, 0.0), rpy: Sequence[float] = (0.0, 0.0, 0.0),
                 q0: Sequence[float] | None = None, physics_dt: float = 0.002) -> None:
        steps = control_steps(controller.period, physics_dt)
        self.robot, self.vehicle, self.controller, self.current = robot, vehicle, controller, current
        self._steps = steps
        self._current_times, self._current_values = current.profile()
        self._current_varies = len(self._current_times) > 1
        self.model = hover_model(robot, vehicle, xyz=xyz, rpy=rpy, physics_dt=physics_dt,
                                 current=self.current_velocity(0.0))
        self.data = mujoco.MjData(self.model)
        m = self.model
        self._thr = np.array([m.actuator(thruster_name(k)).id for k in range(len(vehicle.thrusters))])
        # Thrust configuration matrix about V's origin, its pseudo-inverse and the limits.
        self.B, self.B_pinv, self.limits = thrust_layout(vehicle)
        self._buoyant = buoyancy_bodies(m, robot, vehicle)
        self._vehicle = m.body(VEHICLE_BODY).id
        n = robot.n_joints if robot is not None else 0
        self._qadr = np.array([m.jnt_qposadr[m.joint(j).id] for j in robot.joint_names] if n else [], dtype=int)
        self._servo = np.array([m.actuator(servo_name(j)).id for j in robot.joint_names] if n else [], dtype=int)
        self._tool = m.site(TOOL_SITE).id if n else -1
        if n:
            q0 = (robot.lower + robot.upper) / 2.0 if q0 is None else np.asarray(q0, dtype=float)
            self._check_targets(q0)
            self.data.qpos[self._qadr] = q0
            self.data.ctrl[self._servo] = q0
        mujoco.mj_forward(m, self.data)
        self.reference = np.concatenate([np.asarray(xyz, dtype=float), [float(rpy[2])]])
        self.integral = np.zeros(4)
        self._last_demand = np.zeros(6)

    # -- state -------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    def current_velocity(self, t: float) -> np.ndarray:
        """(3,) the water's velocity at time ``t`` [m/s]."""
        return current_at(self._current_times, self._current_values, t)

    def set_reference(self, xyz: Sequence[float], yaw: float) -> None:
        """Hold V's origin at ``xyz`` [m] and its heading at ``yaw`` [rad] from now on (the
        integral state is kept)."""
        self.reference = np.concatenate([np.asarray(xyz, dtype=float), [float(yaw)]])

    def _check_targets(self, q: np.ndarray) -> None:
        r = self.robot
        if q.shape != (r.n_joints,) or not np.all(np.isfinite(q)):
            raise ValueError(f"arm targets must be {r.n_joints} finite joint angles, got {q!r}")
        bad = (q < r.lower - _LIMIT_SLACK) | (q > r.upper + _LIMIT_SLACK)
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(f"arm target {r.joint_names[k]} = {q[k]} outside [{r.lower[k]}, {r.upper[k]}]")

    # -- control -----------------------------------------------------------------------------
    def station_keeping_thrust(self) -> tuple[np.ndarray, np.ndarray]:
        """``(thrust (n,) [N], demand (6,) [N, N·m])`` for the present state, advancing the
        controller's integral by one period."""
        d = self.data
        u, demand, self.integral = hold_pose(self.reference, d.qpos[:3].copy(), d.qpos[3:7].copy(),
                                             d.xmat[self._vehicle].reshape(3, 3), d.qvel[:3].copy(),
                                             d.qvel[3:6].copy(), self.integral, self.controller, self.B_pinv,
                                             self.limits)
        return u, demand

    def step(self, arm_targets: Sequence[float] | None = None, thrust: Sequence[float] | None = None) -> None:
        """One control period: thrusts and arm targets set, then the physics steps.

        Args:
          arm_targets: ``(n_joints,)`` new servo targets [rad] (None: keep them); outside the
            joint limits raises.
          thrust: ``(n_thrusters,)`` thrusts to command open loop [N] (None: the station
            keeping's, or zeros when it is off); beyond a thruster's limit raises.
        """
        m, d = self.model, self.data
        if arm_targets is not None:
            q = np.asarray(arm_targets, dtype=float)
            self._check_targets(q)
            d.ctrl[self._servo] = q
        demand = np.zeros(6)
        if thrust is not None:
            u = np.asarray(thrust, dtype=float)
            if u.shape != self.limits.shape or not np.all(np.abs(u) <= self.limits + _LIMIT_SLACK):
                raise ValueError(f"thrust must be {self.limits.size} values within ±{self.limits.tolist()} N, "
                                 f"got {u!r}")
        elif self.controller.enabled:
            u, demand = self.station_keeping_thrust()
        else:
            u = np.zeros(self.limits.size)
        d.ctrl[self._thr] = u
        self._last_demand = demand
        buoyant, rho = self._buoyant, self.vehicle.water_density
        for _ in range(self._steps):
            if self._current_varies:
                m.opt.wind[:] = self.current_velocity(d.time)
            mujoco.mj_step1(m, d)  # positions and velocities: the pose the lift is for
            apply_buoyancy(m, d, buoyant, rho)
            mujoco.mj_step2(m, d)

    # -- runs --------------------------------------------------------------------------------
    def _record(self, rows: dict[str, list]) -> None:
        m, d = self.model, self.data
        mujoco.mj_kinematics(m, d)  # after mj_step2 the kinematics are the step's start's
        mujoco.mj_comPos(m, d)
        quat = d.qpos[3:7].copy()
        rows["time"].append(d.time)
        rows["position"].append(d.qpos[:3].copy())
        rows["quat"].append(quat)
        rows["rpy"].append(frames.matrix_rpy(frames.quat_matrix(quat)))
        rows["velocity"].append(d.qvel[:3].copy())
        rows["angular_velocity"].append(d.qvel[3:6].copy())
        rows["thrust"].append(d.ctrl[self._thr].copy())
        rows["demand"].append(self._last_demand.copy())
        rows["q"].append(d.qpos[self._qadr].copy())
        rows["q_target"].append(d.ctrl[self._servo].copy())
        rows["tool"].append(d.site_xpos[self._tool].copy() if self._tool >= 0 else np.full(3, np.nan))
        rows["com"].append(d.subtree_com[0].copy())
        rows["current"].append(m.opt.wind.copy())

    def run(self, duration: float, arm_trajectory: Callable[[float], Sequence[float]] | None = None,
            thrust: Sequence[float] | Callable[[float], Sequence[float]] | None = None) -> HoverLog:
        """Run for ``duration`` [s] (a whole number of control periods, rounded), recording the
        state at the start and after every period.

        Args:
          arm_trajectory: time [s] → ``(n_joints,)`` servo targets [rad], read at each tick
            (e.g. :func:`arm_motion`); None: the targets stay.
          thrust: open-loop thrusts [N], fixed or a function of time (see :meth:`step`);
            None: the station keeping.
        """
        periods = round(duration / self.controller.period)
        if periods < 0 or not math.isfinite(duration):
            raise ValueError(f"duration must be >= 0 [s], got {duration}")
        rows: dict[str, list] = {f.name: [] for f in dataclasses.fields(HoverLog)}
        self._last_demand = np.zeros(6)
        self.data.ctrl[self._thr] = 0.0
        self._record(rows)
        for _ in range(periods):
            t = self.time
            targets = None if arm_trajectory is None else arm_trajectory(t)
            u = thrust(t) if callable(thrust) else thrust
            self.step(targets, u)
            self._record(rows)
        return HoverLog(**{k: np.array(v, dtype=float) for k, v in rows.items()})
