"""A scheduled plan's motion on the hovering vehicle: how good is a docking pose if the vehicle
only hovers there?

:func:`run_plan_hovering` runs a ``plan.json`` (:class:`uvms_jax.planfile.Plan`) on
:class:`~uvms_jax.hover.HoverSim`, dwelling at the end of every segment (where the executor
waits for its gate) and during every gripper step, in the given current: either the arm's
servos replay the plan's timed waypoints while the station keeping's PID holds the docked pose,
or the whole-body controller (:class:`~uvms_jax.hover.WholeBody`) drives the arm and the
thrusters so that the tool follows the docked arm's path. At each gate it compares the tool
with where the docked arm puts it on the plan: the vehicle's motion, seen at the tool.
"""

from __future__ import annotations

import dataclasses

import functools

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax import frames, kin
from uvms_jax.hw import ExecutorSettings, HwRun, SimSettings, run_plan
from uvms_jax.planfile import Plan
from uvms_jax.robot import TOOL_SITE, Robot

from ._model import VEHICLE_BODY, trimmed
from ._settings import ControllerSettings, CurrentSettings, NavigationSettings, VehicleSettings, WholeBodySettings
from ._sim import HoverLog, HoverSim, HoverWorld
from ._executed import ExecutorWholeBody, executor_settings
from ._wbc import pose_error
from ._wholebody import NavigationEstimate, WholeBody

__all__ = ["HoverRun", "docked_tool", "execute_plan_hovering", "follow_tool_path", "plan_targets", "run_plan_hovering", "vehicle_arm_chain",
           "vehicle_displacement"]


def plan_targets(plan: Plan, dwell_s: float, gripper_s: float):
    """The plan's arm motion as servo targets over time.

    Each segment's waypoints are followed at their times (linear between them); its last
    waypoint is held for ``dwell_s`` [s] (the gate) and a gripper-only step for ``gripper_s``.

    Returns:
      ``(targets, gate_times (g,) [s], duration [s])``: ``targets(t)`` gives the ``(n,)`` joint
      targets [rad] at time ``t``; a gate time is the end of a segment's dwell.
    """
    times, qs, gates = [], [], []
    t0 = 0.0
    q_last = np.asarray(plan.segments[0].q[0], dtype=float)
    for seg in plan.segments:
        if len(seg.q):
            t = t0 + np.asarray(seg.t, dtype=float)
            times.append(t)
            qs.append(np.asarray(seg.q, dtype=float))
            t0, q_last = float(t[-1]) + dwell_s, qs[-1][-1]
            gates.append(t0)
        else:  # a gripper step: the arm holds still
            t0 += gripper_s
        times.append(np.array([t0]))
        qs.append(q_last[None])
    t_all, q_all = np.concatenate(times), np.concatenate(qs)

    def targets(t: float) -> np.ndarray:
        return np.array([np.interp(t, t_all, q_all[:, j]) for j in range(q_all.shape[1])])

    return targets, np.asarray(gates), t0


def docked_tool(robot: Robot, vehicle: VehicleSettings, pose, q) -> np.ndarray:
    """``(..., 3)`` where the arm holds its tool [m, world] at joint angles ``q (..., n)`` with the
    vehicle docked at ``pose = [x, y, z, ψ]`` (its base on ``vehicle``'s mount): the reference
    a hovering run is measured against."""
    T = _docked_base(vehicle, pose)
    return np.asarray(kin.fk(robot.chain, np.asarray(q)))[..., :3, 3] @ T[:3, :3].T + T[:3, 3]


def _vehicle_pose(pose) -> np.ndarray:
    """``(4, 4)`` the vehicle frame V in the world for a docking pose ``[x, y, z, ψ]`` [m, rad]."""
    pose = np.asarray(pose, dtype=float)
    return frames.pose(frames.rot_z(pose[3]), pose[:3])


def _docked_base(vehicle: VehicleSettings, pose) -> np.ndarray:
    """``(4, 4)`` the arm's base in the world with the vehicle docked at ``pose``, on its mount."""
    return _vehicle_pose(pose) @ frames.rpy_pose(vehicle.mount_xyz, vehicle.mount_rpy)


@dataclasses.dataclass(frozen=True)
class HoverRun:
    """A plan's motion on the hovering vehicle (:func:`run_plan_hovering`).

    Attributes:
      log: the simulator's record (world frame, SI).
      gate_times: ``(g,)`` [s]; gate_tool_error: ``(g,)`` the tool's distance from its docked
        position at each gate [m]; gate_joint_error: ``(g,)`` the largest joint error from the
        gate's waypoint [rad].
      tool_error: ``(k,)`` the tool's distance from where the docked arm holds it on the plan
        (the arm's forward kinematics at the docked base), per logged row [m]; over BPL with the
        whole-body controller, from the planned path over the :data:`TRAIL_S` up to the row in
        force (the arm trails its speed-limited profile), the gates still on their poses.
      tool_target: ``(k, 3)`` that docked position, per logged row [m, world].
      drift: ``(k,)`` the vehicle's distance from the docked pose [m].
      tool_tolerance_m, joint_tolerance_rad: a gate is reached within both.
      current: ``(3,)`` the water's velocity at the start [m/s].
      coordinated: the whole-body controller drove the arm and the thrusters (the arm leaves
        the plan's joint angles on purpose: gates judged by the tool alone, position and angle).
      gate_tool_angle: ``(g,)`` the tool's angle from its docked orientation at each gate [rad]
        (None: not measured); tool_tolerance_rad: a gate's tolerance on it.
      thrust_limited_periods, joint_limited_periods: control periods in which a thruster was
        at its limit (the allocation scaled the demand down), and in which one of the arm's
        rate bounds was active (None: the arm followed the plan's targets, no bounds of its own).
      world: the run's vehicle and its model (e.g. for :func:`write_hover_video`).
      planned_gates: the plan's gates (an executed run: the executor's count, gripper steps
        included).
      executed: the BPL executor's run that drove the arm (:func:`execute_plan_hovering`: its
        gates are the run's, judged on the joints as on a fixed base, and its result the run's
        status), or None for a replay (:func:`run_plan_hovering`: gates judged here, on the
        joints and the tool).
    """

    log: HoverLog
    gate_times: np.ndarray
    gate_tool_error: np.ndarray
    gate_joint_error: np.ndarray
    tool_error: np.ndarray
    drift: np.ndarray
    tool_tolerance_m: float
    joint_tolerance_rad: float
    current: np.ndarray
    tool_target: np.ndarray
    coordinated: bool = False
    executed: HwRun | None = None
    planned_gates: int = 0
    world: HoverWorld | None = None
    gate_tool_angle: np.ndarray | None = None
    tool_tolerance_rad: float = np.inf
    thrust_limited_periods: int = 0
    joint_limited_periods: int | None = None

    @property
    def _angles_checked(self) -> np.ndarray:
        if self.gate_tool_angle is None:
            return np.ones(len(self.gate_times), dtype=bool)
        return self.gate_tool_angle <= self.tool_tolerance_rad

    @property
    def _joints_checked(self) -> np.ndarray:
        return self.coordinated | (self.gate_joint_error <= self.joint_tolerance_rad)

    @property
    def gates_reached(self) -> int:
        """Gates passed: the executor's, or in a replay those within both tolerances."""
        if self.executed is not None:
            return len(self.gate_times)
        return int(np.sum((self.gate_tool_error <= self.tool_tolerance_m) & self._angles_checked
                          & self._joints_checked))

    @property
    def status(self) -> tuple[str, str]:
        """The executor's ``(status, reason)``; in a replay ``("completed", "")`` when every gate
        is reached, else ``("held", reason)``: an executor waiting at that gate holds the arm
        there."""
        if self.executed is not None:
            r = self.executed.result
            return self.executed.status, "" if r.ok else r.reason
        limits = (f"; the thrusters were at their limit in {self.thrust_limited_periods} control periods"
                  if self.thrust_limited_periods else "")
        gates = zip(self.gate_tool_error, self.gate_joint_error, self._angles_checked)
        for i, (e_tool, e_joint, ok) in enumerate(gates):
            if e_tool > self.tool_tolerance_m:
                return "held", (f"gate {i + 1} of {len(self.gate_times)}: the tool is {1e3 * e_tool:.1f} mm from its "
                                f"docked position (tolerance {1e3 * self.tool_tolerance_m:.0f} mm){limits}")
            if not ok:
                return "held", (f"gate {i + 1} of {len(self.gate_times)}: the tool is turned "
                                f"{np.degrees(self.gate_tool_angle[i]):.2f}° from its docked orientation (tolerance "
                                f"{np.degrees(self.tool_tolerance_rad):.2f}°){limits}")
            if e_joint > self.joint_tolerance_rad and not self.coordinated:
                return "held", (f"gate {i + 1} of {len(self.gate_times)}: a joint is {e_joint:.4f} rad from its "
                                f"waypoint (tolerance {self.joint_tolerance_rad} rad)")
        return "completed", ""

    def summary(self) -> dict:
        """The figures of ``results.json``'s ``hover`` entry (SI units)."""
        status, reason = self.status
        rpy = self.log.rpy
        gates = len(self.gate_times) if self.executed is None else self.planned_gates
        driver = "whole-body controller" if self.coordinated else "replay"
        if self.executed is not None:
            driver = "BPL executor, whole-body controller" if self.coordinated else "BPL executor"
        return {"driver": driver,
                "current_m_s": self.current.tolist(), "coordinated": self.coordinated, "status": status, "reason": reason,
                "gates": gates, "gates_reached": self.gates_reached,
                "gates_tool_within_tolerance": int(np.sum(self.gate_tool_error <= self.tool_tolerance_m)),
                "max_drift_m": float(self.drift.max()), "max_tool_error_m": float(self.tool_error.max()),
                "max_gate_tool_error_m": float(self.gate_tool_error.max(initial=0.0)),
                "max_tilt_deg": float(np.degrees(np.abs(rpy[:, :2]).max())),
                "peak_thrust_N": float(np.abs(self.log.thrust).max()),
                "simulated_s": float(self.log.time[-1]),
                "gate_tool_error_m": self.gate_tool_error.tolist(),
                **({} if self.gate_tool_angle is None else {
                    "gate_tool_angle_deg": np.degrees(self.gate_tool_angle).tolist(),
                    "tool_tolerance_deg": float(np.degrees(self.tool_tolerance_rad))}),
                "thrust_limited_periods": self.thrust_limited_periods,
                "joint_limited_periods": self.joint_limited_periods}


def run_plan_hovering(robot: Robot, plan: Plan, pose, vehicle: VehicleSettings = VehicleSettings(),
                      controller: ControllerSettings = ControllerSettings(),
                      current: CurrentSettings = CurrentSettings(), *, dwell_s: float = 0.5,
                      gripper_s: float = 1.0, tool_tolerance_m: float = 0.01,
                      joint_tolerance_rad: float = 0.01, control: str = "pid",
                      whole_body: WholeBodySettings = WholeBodySettings(), tool_tolerance_deg: float = 2.0,
                      navigation: NavigationSettings | None = None) -> HoverRun:
    """Run ``plan`` with the vehicle hovering at the docked ``pose`` ``(4,) = [x, y, z, ψ]``
    [m, rad] instead of fixed there.

    The vehicle is ballasted for the arm at the plan's first waypoint (:func:`trimmed`: neutral
    and level) and starts at rest at ``pose``. ``vehicle``'s mount must be the docking
    problem's, so that the docked base is where the plan was made for.

    ``control``:

    - ``"pid"``: the arm's servos replay the plan's timed waypoints and the station keeping's
      PID holds the docked pose; a gate is judged on the joints and on the tool's position.
    - ``"feed_forward"``: the same replay, the PID's thrusts with the whole-body controller's
      feed-forward wrench added (:meth:`~uvms_jax.hover.WholeBody.thrust`); gates as ``"pid"``.
    - ``"whole_body"``: the whole-body controller (:class:`~uvms_jax.hover._wholebody.WholeBody`,
      ``whole_body``) drives the arm's servos and the thrusters so that the tool follows the
      plan's docked path; the arm leaves the plan's joint angles on purpose, and a gate is judged
      on the tool's world pose alone: within ``tool_tolerance_m`` [m] and
      ``tool_tolerance_deg`` [°] of its docked pose. It sees the vehicle's pose through
      ``navigation`` (:class:`~uvms_jax.hover._wholebody.NavigationEstimate`; None: exactly).

    Raises:
      ValueError: a plan for other joints than the robot's, a waypoint outside its limits, or
        an unknown ``control``.
    """
    if tuple(plan.joint_names) != tuple(robot.joint_names):
        raise ValueError(f"the plan moves {plan.joint_names}, the arm has {robot.joint_names}")
    if control not in _CONTROLS:
        raise ValueError(f"control must be one of {_CONTROLS}, got {control!r}")
    pose = np.asarray(pose, dtype=float)
    targets, gate_times, duration = plan_targets(plan, dwell_s, gripper_s)
    q0 = targets(0.0)
    sim = HoverSim(robot, trimmed(vehicle, robot, q0), controller, current, xyz=pose[:3], rpy=(0.0, 0.0, pose[3]),
                   q0=q0)
    # The plan at every control tick, and where the docked arm holds the tool along it.
    period = controller.period
    times = period * np.arange(round(duration / period) + 2)
    q_plan = np.array([targets(t) for t in times])
    p_docked = docked_tool(robot, vehicle, pose, q_plan)
    angle = None
    if control == "whole_body":
        log, angle, limited = _run_whole_body(sim, robot, controller, whole_body, pose, q_plan, navigation)
    elif control == "feed_forward":
        log, _, limited = _run_whole_body(sim, robot, controller, dataclasses.replace(whole_body, feed_forward=True),
                                          pose, q_plan, navigation, replay=True)
    else:
        log = sim.run(times[-1], arm_trajectory=lambda t: q_plan[round(t / period)])
        limited = (_saturated_periods(log, sim.world.limits), None)
    tool_target = p_docked[: len(log.time)]
    tool_error = np.linalg.norm(log.tool - tool_target, axis=-1)
    rows = np.searchsorted(log.time, gate_times - 1e-9).clip(max=len(log.time) - 1)
    joint_error = np.abs(log.q[rows] - np.array([targets(t) for t in gate_times])).max(axis=-1) \
        if len(rows) else np.zeros(0)
    return HoverRun(log=log, gate_times=gate_times, gate_tool_error=tool_error[rows], gate_joint_error=joint_error,
                    tool_error=tool_error, drift=np.linalg.norm(log.position - pose[:3], axis=-1),
                    tool_tolerance_m=float(tool_tolerance_m), joint_tolerance_rad=float(joint_tolerance_rad),
                    current=sim.current_velocity(0.0), tool_target=tool_target, coordinated=control == "whole_body",
                    gate_tool_angle=None if angle is None else angle[rows],
                    tool_tolerance_rad=float(np.radians(tool_tolerance_deg)), thrust_limited_periods=limited[0],
                    joint_limited_periods=limited[1])


_CONTROLS = ("pid", "feed_forward", "whole_body")


def _saturated_periods(log: HoverLog, limits: np.ndarray) -> int:
    """Control periods in ``log`` whose thrusts put a thruster at its limit ``limits (n,)`` [N]
    (the scaled allocation puts one exactly there; 1e-9 N of rounding allowed)."""
    return int(np.sum(np.any(np.abs(log.thrust[1:]) >= limits - 1e-9, axis=-1)))


def _run_whole_body(sim: HoverSim, robot: Robot, controller: ControllerSettings, settings: WholeBodySettings,
                    pose: np.ndarray, q_plan: np.ndarray, navigation: NavigationSettings | None,
                    replay: bool = False) -> tuple[HoverLog, np.ndarray, tuple[int, int | None]]:
    """``sim`` driven by the whole-body controller along ``q_plan`` ``(K, n)`` (one row per
    control period) for ``K − 1`` periods, seeing the vehicle's pose through ``navigation``
    (None: exactly); ``replay``: the arm's servos follow ``q_plan`` and the controller sets the
    thrusts alone.

    Returns:
      ``(log, tool_angle (K,) [rad], (thrust-limited periods, joint-limited periods or None))``:
      the tool's angle from its docked orientation on the plan at every logged row.
    """
    m, d, w = sim.model, sim.data, sim.world
    wb = WholeBody(robot, sim.vehicle, controller, settings, pose, q_plan, m)
    site, hull = m.site(TOOL_SITE).id, m.body(VEHICLE_BODY).id
    R_docked = wb.T_dock[:3, :3] @ wb.T_tool[:, :3, :3]  # (K, 3, 3) the tool's planned orientation in the world
    q_ref, integral = q_plan[0].copy(), np.zeros(4)
    period, counts, angles = controller.period, np.zeros(2, dtype=int), []

    def angle(k: int) -> float:
        R = R_docked[k].T @ d.site_xmat[site].reshape(3, 3)
        return float(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)))

    w.start_log(m, d, q_ref)
    angles.append(angle(0))
    nav = None if navigation is None else NavigationEstimate(navigation, d.qpos[:3], d.xmat[hull].reshape(3, 3))
    for k in range(len(q_plan) - 1):
        t = sim.time
        current = sim.current_velocity(t)
        rate = (sim.current_velocity(t + period) - current) / period
        position, R, velocity, omega = d.qpos[:3].copy(), d.xmat[hull].reshape(3, 3).copy(), d.qvel[:3].copy(), \
            d.qvel[3:6].copy()
        if nav is not None:
            position, R = nav.estimate(t, position, R)
        if replay:
            thrust, demand, integral, limited = wb.thrust(k, position, R, velocity, omega, integral, current, rate)
            target = q_plan[k]  # as the PID's replay: the plan's angles of the period's start
            counts[0] += bool(limited)
        else:
            cmd = wb.step(k, position, R, velocity, omega, q_ref, integral, current, rate)
            q_ref, integral, target, thrust, demand = cmd.reference, cmd.integral, cmd.target, cmd.thrust, cmd.demand
            counts += (bool(cmd.thrust_limited), bool(cmd.joint_limited))
        sim.step(target, thrust=thrust, demand=demand)
        w.record(m, d, target)
        angles.append(angle(k + 1))
    return w.log(), np.array(angles), (int(counts[0]), None if replay else int(counts[1]))


def execute_plan_hovering(robot: Robot, plan: Plan, pose, vehicle: VehicleSettings = VehicleSettings(),
                          controller: ControllerSettings = ControllerSettings(),
                          current: CurrentSettings = CurrentSettings(), *,
                          config: ExecutorSettings = ExecutorSettings(), sim: SimSettings = SimSettings(),
                          tool_tolerance_m: float = 0.01, control: str = "pid",
                          whole_body: WholeBodySettings | None = None, tool_tolerance_deg: float = 2.0,
                          navigation: NavigationSettings | None = None) -> HoverRun:
    """Execute ``plan`` with the BPL executor on the simulated arm mounted on the vehicle
    hovering at the docked ``pose`` ``(4,) = [x, y, z, ψ]`` [m, rad]: the executor, its safety
    checks and its link are the fixed base's (:func:`uvms_jax.hw.run_plan` over the loopback
    link), only the arm's base moves (:class:`HoverWorld` around :class:`uvms_jax.hw.SimArm`).

    The vehicle is ballasted for the arm at the plan's first waypoint (:func:`trimmed`) and
    starts at rest at ``pose``. ``control``:

    - ``"pid"``: the executor streams the plan's profiles, the station keeping holds the docked
      pose, and the gates are on the encoders, which the vehicle's motion does not move. The
      tool error of a row is the tool's distance from where the docked arm holds it at the same
      measured joint angles: the vehicle's motion, seen at the tool, which the executor does not
      see; ``gates_tool_within_tolerance`` counts the gates where the tool was within
      ``tool_tolerance_m`` [m] as well.
    - ``"whole_body"``: the whole-body controller sits between the plan and the arm
      (:class:`~uvms_jax.hover.ExecutorWholeBody`, ``whole_body``; None: the defaults with the
      simulated arm's servo lead, :func:`executor_settings`): every tick it sends the arm's
      demands from the measured joints and the vehicle's ``navigation`` estimate (None: exact)
      and drives the thrusters. The executor's gates wait for the tool to settle on its
      planned pose by that estimate (:data:`~uvms_jax.hover._executed.SETTLED_M`); the run's
      tool error is the tool's distance from its planned pose (the docked arm's along the
      executor's plan rows) from the simulator, ``gates_tool_within_tolerance`` counts the gates
      within ``tool_tolerance_m`` [m] of it, and ``gate_tool_angle`` holds the angles at the
      gates (judged against ``tool_tolerance_deg`` [°]).

    The run's ``world`` draws it (:func:`write_hover_video`).

    Raises:
      PlanError: the plan was made for another arm, or the dry run refused it.
      ValueError: an unknown ``control``; for ``"whole_body"``, an executor rate other than
        the controller's period.
    """
    if control not in ("pid", "whole_body"):
        raise ValueError(f"control must be 'pid' or 'whole_body' over BPL, got {control!r}")
    pose = np.asarray(pose, dtype=float)
    q0 = np.asarray(next(seg.q[0] for seg in plan.segments if len(seg.q)), dtype=float)
    world = HoverWorld(trimmed(vehicle, robot, q0), controller, current, xyz=pose[:3], rpy=(0.0, 0.0, pose[3]))
    driver = None
    if control == "whole_body":
        if not np.isclose(1.0 / config.rate_hz, controller.period, rtol=1e-9, atol=0.0):
            raise ValueError(f"the executor's tick ({1.0 / config.rate_hz:g} s) must be the whole-body controller's "
                             f"period ({controller.period:g} s): set its rate to {1.0 / controller.period:g} Hz")
        settings = executor_settings(WholeBodySettings(), sim.servo_gain) if whole_body is None else whole_body
        driver = ExecutorWholeBody(robot, world, controller, settings, pose, navigation)
    run = run_plan(plan, robot, config=config, sim=sim, world=world, controller=driver)
    log = world.log()
    # A gate passed at the last tick the executor logged for its waypoint (log times count
    # from the run's start on the simulator's clock).
    last_tick = {(row[1], row[2]): row[0] for row in run.log.rows}
    gate_times = np.array([run.result.start_s + last_tick[g.segment, g.waypoint] for g in run.result.gates])
    rows = np.searchsorted(log.time, gate_times - 1e-9).clip(max=len(log.time) - 1)
    angle = None
    if driver is None:
        tool_target = docked_tool(robot, vehicle, pose, log.q)
        tool_error = point_error = np.linalg.norm(log.tool - tool_target, axis=-1)
    else:
        ticks = run.result.start_s + np.array([row[0] for row in run.log.rows])
        tool_target, angle, tool_error = _planned_tool(driver, log, ticks, rows, gate_times)
        point_error = np.linalg.norm(log.tool - tool_target, axis=-1)
    planned = sum(len(seg.q) - (i > 0 and len(seg.q) > 0) + (seg.jaws_mm is not None)
                  for i, seg in enumerate(plan.segments))
    thrust_limited = _saturated_periods(log, world.limits) if driver is None else driver.thrust_limited
    return HoverRun(log=log, gate_times=gate_times, gate_tool_error=point_error[rows],
                    gate_joint_error=np.array([g.error_rad for g in run.result.gates]), tool_error=tool_error,
                    drift=np.linalg.norm(log.position - pose[:3], axis=-1), tool_tolerance_m=float(tool_tolerance_m),
                    joint_tolerance_rad=config.gate_threshold_rad, current=world.current_velocity(0.0),
                    tool_target=tool_target, coordinated=driver is not None, executed=run,
                    planned_gates=int(planned), world=world,
                    gate_tool_angle=None if angle is None else angle[rows],
                    tool_tolerance_rad=float(np.radians(tool_tolerance_deg)), thrust_limited_periods=thrust_limited,
                    joint_limited_periods=None if driver is None else driver.joint_limited)


# How far back along its planned path the tool's error over a run looks [s]: the executor's
# profiles run a joint at up to its speed limit, where the arm trails its demand by what its
# position loop needs (0.07 rad, 0.14 s, for the Bravo 7's joint G at 0.5 rad/s), and the
# controller, with no speed left, cannot take that back until the move slows.
TRAIL_S = 0.3


def _planned_tool(driver: ExecutorWholeBody, log: HoverLog, ticks: np.ndarray, gate_rows: np.ndarray,
                  gate_times: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(tool_target (k, 3) [m, world], angle (k,) [rad], path_error (k,) [m])`` at the rows of
    ``log``: the tool's planned position at the plan row in force (the executor's ticks at
    ``ticks`` [s]; at the log's ``gate_rows``, the row of the gate at ``gate_times`` [s]: a gate
    after the log's last row is judged there); the angle of the simulated tool (the vehicle–arm
    chain at the logged pose and joints) from its planned orientation; and the tool's distance
    from its planned path over the :data:`TRAIL_S` before that row (the polyline through the
    rows)."""
    wb = driver.wb
    k = driver.plan_rows(ticks, log.time)
    k[gate_rows] = driver.plan_rows(ticks, gate_times)
    planned = wb.T_tool[k]  # (k, 4, 4) in V₀
    free = np.concatenate([log.position, log.quat], axis=1)
    zeta = np.array([np.concatenate([vehicle_displacement(wb.T_dock, f), q]) for f, q in zip(free, log.q)])
    T = np.asarray(kin.fk(wb.chain, zeta), dtype=float)
    angle = np.linalg.norm(pose_error(planned, T)[:, 3:], axis=-1)
    path = wb.T_tool[:, :3, 3] @ wb.T_dock[:3, :3].T + wb.T_dock[:3, 3]  # (K, 3) every row, world
    idx = np.clip(k[:, None] + np.arange(-round(TRAIL_S / wb.dt), 1), 0, len(path) - 1)
    a, b, x = path[idx[:, :-1]], path[idx[:, 1:]], log.tool[:, None, :]
    ab = b - a
    s = np.clip(np.sum((x - a) * ab, axis=-1) / np.maximum(np.sum(ab * ab, axis=-1), 1e-300), 0.0, 1.0)
    path_error = np.linalg.norm(x - a - s[..., None] * ab, axis=-1).min(axis=-1)
    return path[k], angle, path_error


def follow_tool_path(robot: Robot, vehicle: VehicleSettings, q_docked, docked_pose, pose, *, key=None,
                     iterations: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles that move the tool along the same world path from another docking pose:
    the task a plan made at ``docked_pose`` does, done from ``pose`` (both ``(4,) = [x, y, z,
    ψ]`` [m, rad], the arm on ``vehicle``'s mount). No collision check: a comparison of poses
    for the same tool motion, not a plan.

    The tool poses of ``q_docked`` ``(P, n)`` [rad] at the docked base are expressed at the
    other base and followed by damped least squares (:func:`uvms_jax.kin.dls_ik`, ``iterations``
    per row, within the joint limits) from the previous row's solution, so the arm stays on one
    branch: from each IK solution of the first row (32 random seeds, ``key``, and the docked
    angles), keeping the path that reaches the most rows, then the one whose joints travel least.

    Returns:
      ``(q (P, n) [rad], reached (P,))``: a row is reached when its forward kinematics meets
      the tool pose within the IK tolerances.
    """
    chain = robot.chain
    base = [_docked_base(vehicle, p) for p in (docked_pose, pose)]
    T_tool = np.linalg.solve(base[1], base[0]) @ np.asarray(kin.fk(chain, np.asarray(q_docked)), dtype=float)
    key = jax.random.key(0) if key is None else key
    # Every IK branch of the first row is followed (one per converged seed, and the docked
    # angles): the path from one may leave the reach or the limits where another's does not.
    first = kin.numeric_ik(key, chain, T_tool[0], n_seeds=_FOLLOW_SEEDS, iterations=100, all_seeds=True)
    seeds = jnp.concatenate([jnp.where(first.valid[:, None], first.q, q_docked[0]), jnp.asarray(q_docked[:1], first.q.dtype)])
    q, reached = _follow(chain, jnp.asarray(T_tool, seeds.dtype), seeds, iterations)
    q, reached = np.asarray(q), np.asarray(reached)
    # The branch that reaches the most rows, of those the one whose joints travel least.
    travel = np.abs(np.diff(q, axis=1)).sum(axis=(1, 2))
    best = np.lexsort((travel, -reached.sum(axis=1)))[0]
    return q[best], reached[best]


_FOLLOW_SEEDS = 32


@functools.partial(jax.jit, static_argnums=3)
def _follow(chain: kin.Chain, T_tool, seeds, iterations: int):
    """From each seed ``(S, n)``: the rows' solutions ``(S, P, n)`` and whether each is reached
    ``(S, P)``."""
    def from_seed(q0):
        def row(q, T):
            q = kin.dls_ik(chain, T, q, iterations)
            return q, q

        _, q = jax.lax.scan(row, q0, T_tool)
        return q, kin.reaches(T_tool, kin.fk(chain, q))

    return jax.vmap(from_seed)(seeds)


def vehicle_arm_chain(robot: Robot, vehicle: VehicleSettings) -> kin.Chain:
    """The arm on its vehicle as one chain (:func:`uvms_jax.kin.uvms`): six vehicle joints (x, y,
    z, then rotations about x, y, z of the docked vehicle frame), then the arm's, at ``vehicle``'s
    mount."""
    return kin.uvms(robot.chain, mount=frames.rpy_pose(vehicle.mount_xyz, vehicle.mount_rpy))


def vehicle_displacement(T_dock: np.ndarray, free_qpos: np.ndarray) -> np.ndarray:
    """``(6,)`` the vehicle joints of :func:`vehicle_arm_chain` for a vehicle whose free joint
    holds ``free_qpos`` ``(7,) = (position [m], quaternion (w, x, y, z))`` in the world, relative
    to the docked pose ``T_dock`` ``(4, 4)``: its displacement [m] and XYZ Euler angles [rad] in
    the docked vehicle frame."""
    T_rel = np.linalg.solve(T_dock, frames.pose(frames.quat_matrix(free_qpos[3:7]), free_qpos[:3]))
    return np.concatenate([T_rel[:3, 3], frames.matrix_euler_xyz(T_rel[:3, :3])])
