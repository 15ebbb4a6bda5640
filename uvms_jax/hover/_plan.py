"""A scheduled plan's motion on the hovering vehicle: how good is a docking pose if the vehicle
only hovers there?

:func:`run_plan_hovering` replays a ``plan.json`` (:class:`uvms_jax.planfile.Plan`) on
:class:`~uvms_jax.hover.HoverSim`: the arm's servos follow the plan's timed waypoints, dwelling
at the end of every segment (where the executor waits for its gate) and during every gripper
step, while the vehicle holds the docked pose on its thrusters in the given current. At each
gate it compares the tool with where the docked arm puts it at the same joint angles: the
vehicle's motion, seen at the tool.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from uvms_jax import frames, kin
from uvms_jax.planfile import Plan
from uvms_jax.robot import TOOL_SITE, Robot

from ._model import trimmed
from ._settings import ControllerSettings, CurrentSettings, VehicleSettings
from ._sim import HoverLog, HoverSim

__all__ = ["HoverRun", "docked_tool", "plan_targets", "run_plan_hovering"]


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
    pose = np.asarray(pose, dtype=float)
    T = frames.pose(frames.rot_z(pose[3]), pose[:3]) @ frames.rpy_pose(vehicle.mount_xyz, vehicle.mount_rpy)
    return np.asarray(kin.fk(robot.chain, np.asarray(q)))[..., :3, 3] @ T[:3, :3].T + T[:3, 3]


@dataclasses.dataclass(frozen=True)
class HoverRun:
    """A plan's motion on the hovering vehicle (:func:`run_plan_hovering`).

    Attributes:
      log: the simulator's record (world frame, SI).
      gate_times: ``(g,)`` [s]; gate_tool_error: ``(g,)`` the tool's distance from its docked
        position at each gate [m]; gate_joint_error: ``(g,)`` the largest joint error from the
        gate's waypoint [rad].
      tool_error: ``(k,)`` the tool's distance from where the docked arm holds it on the plan
        (the arm's forward kinematics at the docked base), per logged row [m].
      drift: ``(k,)`` the vehicle's distance from the docked pose [m].
      tool_tolerance_m, joint_tolerance_rad: a gate is reached within both.
      current: ``(3,)`` the water's velocity at the start [m/s].
      coordinated: the arm corrected for the vehicle's motion (gates judged by the tool alone).
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
    coordinated: bool = False

    @property
    def _joints_checked(self) -> np.ndarray:
        return self.coordinated | (self.gate_joint_error <= self.joint_tolerance_rad)

    @property
    def gates_reached(self) -> int:
        return int(np.sum((self.gate_tool_error <= self.tool_tolerance_m) & self._joints_checked))

    @property
    def status(self) -> tuple[str, str]:
        """``("completed", "")`` when every gate is reached, else ``("held", reason)``: an
        executor waiting at that gate holds the arm there."""
        for i, (e_tool, e_joint) in enumerate(zip(self.gate_tool_error, self.gate_joint_error)):
            if e_tool > self.tool_tolerance_m:
                return "held", (f"gate {i + 1} of {len(self.gate_times)}: the tool is {1e3 * e_tool:.1f} mm from its "
                                f"docked position (tolerance {1e3 * self.tool_tolerance_m:.0f} mm)")
            if e_joint > self.joint_tolerance_rad and not self.coordinated:
                return "held", (f"gate {i + 1} of {len(self.gate_times)}: a joint is {e_joint:.4f} rad from its "
                                f"waypoint (tolerance {self.joint_tolerance_rad} rad)")
        return "completed", ""

    def summary(self) -> dict:
        """The figures of ``results.json``'s ``hover`` entry (SI units)."""
        status, reason = self.status
        rpy = self.log.rpy
        return {"current_m_s": self.current.tolist(), "coordinated": self.coordinated, "status": status, "reason": reason,
                "gates": len(self.gate_times), "gates_reached": self.gates_reached,
                "max_drift_m": float(self.drift.max()), "max_tool_error_m": float(self.tool_error.max()),
                "max_gate_tool_error_m": float(self.gate_tool_error.max(initial=0.0)),
                "max_tilt_deg": float(np.degrees(np.abs(rpy[:, :2]).max())),
                "peak_thrust_N": float(np.abs(self.log.thrust).max()),
                "simulated_s": float(self.log.time[-1])}


def run_plan_hovering(robot: Robot, plan: Plan, pose, vehicle: VehicleSettings = VehicleSettings(),
                      controller: ControllerSettings = ControllerSettings(),
                      current: CurrentSettings = CurrentSettings(), *, dwell_s: float = 0.5,
                      gripper_s: float = 1.0, tool_tolerance_m: float = 0.01,
                      joint_tolerance_rad: float = 0.01, coordinate: bool = False) -> HoverRun:
    """Replay ``plan`` with the vehicle hovering at the docked ``pose`` ``(4,) = [x, y, z, ψ]``
    [m, rad] instead of fixed there.

    The vehicle is ballasted for the arm at the plan's first waypoint (:func:`trimmed`: neutral
    and level), starts at rest at ``pose`` and holds it by station keeping. ``vehicle``'s mount
    must be the docking problem's, so that the docked base is where the plan was made for.
    With ``coordinate`` the arm corrects for the vehicle's motion (:func:`_coordinated`): it then
    leaves the plan's joint angles on purpose, and a gate is judged by the tool alone.

    Raises:
      ValueError: a plan for other joints than the robot's, or a waypoint outside its limits.
    """
    if tuple(plan.joint_names) != tuple(robot.joint_names):
        raise ValueError(f"the plan moves {plan.joint_names}, the arm has {robot.joint_names}")
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
    arm = _coordinated(sim, robot, q_plan, p_docked, period) if coordinate else (lambda t: q_plan[round(t / period)])
    log = sim.run(times[-1], arm_trajectory=arm)
    tool_error = np.linalg.norm(log.tool - p_docked[: len(log.time)], axis=-1)
    rows = np.searchsorted(log.time, gate_times - 1e-9).clip(max=len(log.time) - 1)
    joint_error = np.abs(log.q[rows] - np.array([targets(t) for t in gate_times])).max(axis=-1) \
        if len(rows) else np.zeros(0)
    return HoverRun(log=log, gate_times=gate_times, gate_tool_error=tool_error[rows], gate_joint_error=joint_error,
                    tool_error=tool_error, drift=np.linalg.norm(log.position - pose[:3], axis=-1),
                    tool_tolerance_m=float(tool_tolerance_m), joint_tolerance_rad=float(joint_tolerance_rad),
                    current=sim.current_velocity(0.0), coordinated=coordinate)


def _coordinated(sim: HoverSim, robot: Robot, q_plan: np.ndarray, p_docked: np.ndarray, period: float,
                 gain: float = 0.5, damping: float = 0.02):
    """Arm targets that correct for the vehicle's motion: each tick, the tool's offset from
    where the docked arm holds it on the plan, mapped to joint corrections through the arm's
    part of the tool Jacobian (MuJoCo's, of the whole vehicle–arm system: damped least
    squares, damping [m]), accumulated with ``gain`` and kept within the joint limits."""
    m, d = sim.model, sim.data
    site = m.site(TOOL_SITE).id
    dofs = np.array([m.jnt_dofadr[m.joint(j).id] for j in robot.joint_names])
    jacp = np.zeros((3, m.nv))
    correction = np.zeros(robot.n_joints)

    def targets(t: float) -> np.ndarray:
        nonlocal correction
        k = round(t / period)
        mujoco.mj_jacSite(m, d, jacp, None, site)
        J = jacp[:, dofs]
        error = p_docked[k] - d.site_xpos[site]
        step = J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(3), error)
        correction = np.clip(q_plan[k] + correction + gain * step, robot.lower, robot.upper) - q_plan[k]
        return q_plan[k] + correction

    return targets
