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

from ._control import LIMIT_SLACK, control_steps, hold_pose, thrust_layout
from ._hydro import current_at
from ._model import VEHICLE_BODY, apply_buoyancy, buoyancy_bodies, hover_spec, servo_name, thruster_name
from ._settings import ControllerSettings, CurrentSettings, VehicleSettings

__all__ = ["HoverLog", "HoverSim", "HoverWorld", "arm_motion"]

# The hull's outline at the starting pose, fixed in the world: what a video shows the drift
# against.
START_OUTLINE = "start_outline"


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


class HoverWorld:
    """The hovering vehicle around an arm: its model, the water's forces on every body, and its
    station keeping, stepped by whoever drives the arm.

    :class:`HoverSim` drives the arm with position servos; the hardware runner's simulated arm
    (:class:`uvms_jax.hw.SimArm`, ``world=``: this class is an :class:`uvms_jax.hw.ArmWorld`)
    drives it with its own motor model and answers the BPL executor, so a plan runs on the
    hovering vehicle through the same executor and gates as on a fixed base. Every physics step
    sets the current (``opt.wind``) for its time and the bodies' buoyancy for their pose between
    MuJoCo's position stage and its acceleration stage (``mj_step1`` / ``mj_step2``), so the lift
    always matches the pose being integrated; every control period the station keeping sets the
    thrusts, and the state is recorded (:meth:`log`).

    Args:
      vehicle: hull, water and thrusters.
      controller: station keeping; its reference is the starting pose (:meth:`set_reference`).
      current: the water's velocity over time.
      xyz, rpy: the vehicle's starting pose [m; URDF roll, pitch, yaw, rad].
    """

    def __init__(self, vehicle: VehicleSettings = VehicleSettings(),
                 controller: ControllerSettings = ControllerSettings(), current: CurrentSettings = CurrentSettings(),
                 *, xyz: Sequence[float] = (0.0, 0.0, 0.0), rpy: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        self.vehicle, self.controller, self.current = vehicle, controller, current
        self.xyz, self.rpy = tuple(map(float, xyz)), tuple(map(float, rpy))
        self._current_times, self._current_values = current.profile()
        self._current_varies = len(self._current_times) > 1
        # Thrust configuration matrix about V's origin, its pseudo-inverse and the limits.
        self.B, self.B_pinv, self.limits = thrust_layout(vehicle)
        self.reference = np.array([*self.xyz, self.rpy[2]])
        self.integral = np.zeros(4)
        self.robot: Robot | None = None
        self._commanded = False  # a controller sets the thrusts (command_thrust), not the station keeping

    def current_velocity(self, t: float) -> np.ndarray:
        """(3,) the water's velocity at time ``t`` [m/s]."""
        return current_at(self._current_times, self._current_values, t)

    def set_reference(self, xyz: Sequence[float], yaw: float) -> None:
        """Hold V's origin at ``xyz`` [m] and its heading at ``yaw`` [rad] from now on (the
        integral state is kept)."""
        self.reference = np.concatenate([np.asarray(xyz, dtype=float), [float(yaw)]])

    # -- the model -----------------------------------------------------------------------------
    def spec(self, robot: Robot | None, physics_dt: float = 0.002, servos: bool = False) -> mujoco.MjSpec:
        """The vehicle's model carrying ``robot`` at its mount (:func:`hover_spec`; ``servos``:
        position servos on the arm's joints), at the starting pose and current."""
        self.robot = robot
        spec = hover_spec(robot, self.vehicle, xyz=self.xyz, rpy=self.rpy, current=self.current_velocity(0.0),
                          physics_dt=physics_dt, servos=servos)
        # The hull's outline at the starting pose, fixed in the world: what a video measures the
        # drift against. Drawn only (no mass, no contact, in no body: no force).
        spec.worldbody.add_geom(name=START_OUTLINE, type=mujoco.mjtGeom.mjGEOM_BOX, contype=0, conaffinity=0,
                                size=np.asarray(self.vehicle.size, dtype=float) / 2.0, pos=self.xyz,
                                quat=frames.matrix_quat(frames.rpy_matrix(self.rpy)), rgba=(1.0, 1.0, 1.0, 0.15))
        return spec

    def prepare(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Take ``model`` (compiled from :meth:`spec`, drives added or not) with ``data`` at the
        start: look up its parts, set the lift, record the first row."""
        robot, m = self.robot, model
        self.model, self.data = m, data
        self._steps = control_steps(self.controller.period, m.opt.timestep)
        self._thr = np.array([m.actuator(thruster_name(k)).id for k in range(len(self.vehicle.thrusters))])
        ids, volume, cob = buoyancy_bodies(m, robot, self.vehicle)
        # A body the arm's drive model holds up by gravity compensation floats already.
        floats = m.body_gravcomp[ids] == 0
        self._buoyant = ids[floats], volume[floats], cob[floats]
        self._vehicle = m.body(VEHICLE_BODY).id
        joints = robot.joint_names if robot is not None else ()
        self._qadr = np.array([m.jnt_qposadr[m.joint(j).id] for j in joints], dtype=int)
        self._tool = m.site(TOOL_SITE).id if joints else -1
        self._tick = 0
        mujoco.mj_forward(m, data)
        apply_buoyancy(m, data, self._buoyant, self.vehicle.water_density)
        self.start_log(m, data)

    def start_log(self, model: mujoco.MjModel, data: mujoco.MjData, q_target: np.ndarray | None = None) -> None:
        """Start a new log with the present state as its first row, thrusters off."""
        self._rows = {f.name: [] for f in dataclasses.fields(HoverLog)}
        self._last_demand = np.zeros(6)
        data.ctrl[self._thr] = 0.0
        self.record(model, data, q_target)

    def station_keeping(self, data: mujoco.MjData) -> np.ndarray:
        """Thrusts ``(n,)`` [N] for the present state, advancing the controller's integral by one
        period (the wrench is kept for the log)."""
        d = data
        u, self._last_demand, self.integral = hold_pose(
            self.reference, d.qpos[:3].copy(), d.qpos[3:7].copy(), d.xmat[self._vehicle].reshape(3, 3),
            d.qvel[:3].copy(), d.qvel[3:6].copy(), self.integral, self.controller, self.B_pinv, self.limits)
        return u

    def command(self, data: mujoco.MjData, thrust: np.ndarray | None, demand: np.ndarray | None = None) -> None:
        """Set the thrusts for the next period: ``thrust`` [N] open loop (beyond a thruster's
        limit raises; ``demand``: the wrench in V they were allocated for, for the log), or the
        station keeping's (None; zeros when it is off)."""
        self._last_demand = np.zeros(6) if demand is None else np.asarray(demand, dtype=float).copy()
        if thrust is not None:
            u = np.asarray(thrust, dtype=float)
            if u.shape != self.limits.shape or not np.all(np.abs(u) <= self.limits + LIMIT_SLACK):
                raise ValueError(f"thrust must be {self.limits.size} values within ±{self.limits.tolist()} N, "
                                 f"got {u!r}")
        elif self.controller.enabled:
            u = self.station_keeping(data)
        else:
            u = np.zeros(self.limits.size)
        data.ctrl[self._thr] = u

    def command_thrust(self, thrust: np.ndarray, demand: np.ndarray | None = None) -> None:
        """A controller sets the thrusts [N] from now on (beyond a thruster's limit raises
        ValueError), held until its next command; the station keeping stands by until
        :meth:`release_thrust`."""
        self.command(self.data, thrust, demand)
        self._commanded = True

    @property
    def thrust_commanded(self) -> bool:
        """A controller sets the thrusts (:meth:`command_thrust`), not the station keeping."""
        return self._commanded

    def release_thrust(self) -> None:
        """Hand the thrusters back to the station keeping on its reference (a controller's run
        ended, or stopped): from the next control period on."""
        self._commanded = False

    def physics_step(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """One physics step with the current and the buoyancy of the pose being integrated."""
        if self._current_varies:
            model.opt.wind[:] = self.current_velocity(data.time)
        mujoco.mj_step1(model, data)  # positions and velocities: the pose the lift is for
        apply_buoyancy(model, data, self._buoyant, self.vehicle.water_density)
        mujoco.mj_step2(model, data)

    def step(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """One physics step of a world whose arm another simulator drives: at each control
        period's start the state is recorded (after the first) and the station keeping sets the
        thrusts (unless a controller commands them, :meth:`command_thrust`)."""
        if self._tick % self._steps == 0:
            if self._tick:
                self.record(model, data)
            if not self._commanded:
                self.command(data, None)
        self.physics_step(model, data)
        self._tick += 1

    # -- the record ----------------------------------------------------------------------------
    def record(self, model: mujoco.MjModel, data: mujoco.MjData, q_target: np.ndarray | None = None) -> None:
        """Add the present state to the log (``q_target``: the arm's servo targets, NaN when the
        arm's drives are not this world's)."""
        m, d, rows = model, data, self._rows
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
        rows["q_target"].append(np.full(self._qadr.size, np.nan) if q_target is None else q_target.copy())
        rows["tool"].append(d.site_xpos[self._tool].copy() if self._tool >= 0 else np.full(3, np.nan))
        rows["com"].append(d.subtree_com[0].copy())
        rows["current"].append(m.opt.wind.copy())

    def log(self) -> HoverLog:
        """What was recorded since :meth:`prepare` (the rows up to the last control period)."""
        return HoverLog(**{k: np.array(v, dtype=float) for k, v in self._rows.items()})

    def replay_qpos(self, log: HoverLog) -> np.ndarray:
        """``(k, model.nq)`` the model's positions at the rows of ``log`` (this world's record):
        the vehicle's pose and the arm's angles; other joints, e.g. the jaws, at their
        reference positions. What a video of the run replays."""
        m = self.model
        qpos = np.tile(m.qpos0, (len(log.time), 1))
        qpos[:, :3], qpos[:, 3:7], qpos[:, self._qadr] = log.position, log.quat, log.q
        return qpos


class HoverSim:
    """The vehicle with its arm on position servos in open water, station keeping on (x, y, z, ψ).

    It runs in control periods: at each tick the station keeping reads the vehicle's pose and
    sets the thrusts (or takes commanded thrusts), the arm's joint targets are set, then
    ``period / physics_dt`` physics steps of its :class:`HoverWorld` follow.

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
        self._steps = control_steps(controller.period, physics_dt)
        self.robot, self.vehicle, self.controller, self.current = robot, vehicle, controller, current
        self.world = HoverWorld(vehicle, controller, current, xyz=xyz, rpy=rpy)
        self.model = self.world.spec(robot, physics_dt, servos=True).compile()
        self.data = mujoco.MjData(self.model)
        m = self.model
        n = robot.n_joints if robot is not None else 0
        self._qadr = np.array([m.jnt_qposadr[m.joint(j).id] for j in robot.joint_names] if n else [], dtype=int)
        self._servo = np.array([m.actuator(servo_name(j)).id for j in robot.joint_names] if n else [], dtype=int)
        if n:
            q0 = (robot.lower + robot.upper) / 2.0 if q0 is None else np.asarray(q0, dtype=float)
            self._check_targets(q0)
            self.data.qpos[self._qadr] = q0
            self.data.ctrl[self._servo] = q0
        self.world.prepare(m, self.data)

    # -- state -------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    def current_velocity(self, t: float) -> np.ndarray:
        """(3,) the water's velocity at time ``t`` [m/s]."""
        return self.world.current_velocity(t)

    def set_reference(self, xyz: Sequence[float], yaw: float) -> None:
        """Hold V's origin at ``xyz`` [m] and its heading at ``yaw`` [rad] from now on (the
        integral state is kept)."""
        self.world.set_reference(xyz, yaw)

    def _check_targets(self, q: np.ndarray) -> None:
        r = self.robot
        if q.shape != (r.n_joints,) or not np.all(np.isfinite(q)):
            raise ValueError(f"arm targets must be {r.n_joints} finite joint angles, got {q!r}")
        bad = (q < r.lower - LIMIT_SLACK) | (q > r.upper + LIMIT_SLACK)
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(f"arm target {r.joint_names[k]} = {q[k]} outside [{r.lower[k]}, {r.upper[k]}]")

    # -- control -----------------------------------------------------------------------------
    def step(self, arm_targets: Sequence[float] | None = None, thrust: Sequence[float] | None = None,
             demand: Sequence[float] | None = None) -> None:
        """One control period: thrusts and arm targets set, then the physics steps.

        Args:
          arm_targets: ``(n_joints,)`` new servo targets [rad] (None: keep them); outside the
            joint limits raises.
          thrust: ``(n_thrusters,)`` thrusts to command open loop [N] (None: the station
            keeping's, or zeros when it is off); beyond a thruster's limit raises.
          demand: ``(6,)`` the wrench in V a controller allocated ``thrust`` for, logged.
        """
        if arm_targets is not None:
            q = np.asarray(arm_targets, dtype=float)
            self._check_targets(q)
            self.data.ctrl[self._servo] = q
        self.world.command(self.data, thrust, demand)
        for _ in range(self._steps):
            self.world.physics_step(self.model, self.data)

    # -- runs --------------------------------------------------------------------------------
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
        w = self.world
        w.start_log(self.model, self.data, self.data.ctrl[self._servo])
        for _ in range(periods):
            t = self.time
            targets = None if arm_trajectory is None else arm_trajectory(t)
            u = thrust(t) if callable(thrust) else thrust
            self.step(targets, u)
            w.record(self.model, self.data, self.data.ctrl[self._servo])
        return w.log()
