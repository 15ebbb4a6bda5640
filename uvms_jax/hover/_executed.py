"""The whole-body controller in the BPL executor's loop (:class:`ExecutorWholeBody`).

At every tick of :class:`uvms_jax.hw.Executor` it turns the arm's measured joints (BPL position
feedback) and the vehicle's navigation estimate into the arm's joint demands and the thrusts,
with :class:`~uvms_jax.hover.WholeBody` (the formulas of :mod:`uvms_jax.hover._wbc`, the same
step as on :class:`~uvms_jax.hover.HoverSim`), and it judges the arm's part of
each gate by the tool's pose. The arm is the simulated BPL arm; the vehicle is its
:class:`~uvms_jax.hover.HoverWorld`, whose thrusters the controller drives while the run lasts.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import numpy as np

from uvms_jax import kin
from uvms_jax.hw import joint_specs
from uvms_jax.robot import Robot

from ._model import VEHICLE_BODY
from ._settings import ControllerSettings, NavigationSettings, WholeBodySettings
from ._sim import HoverWorld
from ._wbc import pose_error
from ._wholebody import NavigationEstimate, WholeBody

_fk = jax.jit(kin.fk_of)  # the tool's pose every tick, without kin.fk's input checks (ζ built here)

__all__ = ["EXECUTOR_TOOL_GAIN", "SETTLED_DEG", "SETTLED_M", "ExecutorWholeBody", "executor_settings"]

# The executor's gate with the controller in the loop: the tool, by the navigation estimate,
# within this of the gate's planned pose [m, °]: settled (the controller drives the estimate onto
# the plan). A fifth of the 10 mm and 2° the runs are judged on, so the navigation's own error
# (5 mm at worst on the CPU simulator) fits beside it.
SETTLED_M = 0.002
SETTLED_DEG = 0.4


class ExecutorWholeBody:
    """The whole-body controller as the executor's :class:`uvms_jax.hw.JointController`.

    Each tick (:meth:`demand`) reads the vehicle's state from ``world`` (its pose through
    ``navigation``: fixes at a rate, late and noisy, :class:`NavigationEstimate`; None: exactly)
    and the current there, takes the arm's measured angles as the reference, and runs
    :meth:`WholeBody.step`: the thrusts go to the vehicle at once, the joint targets go back to
    the executor as the tick's demands. The measured angles are held within the joint limits
    first (an encoder may read a joint the firmware stopped on its limit a float32 rounding past
    it; the executor stops the run beyond its limit margin): from a reference inside them the
    controller's targets lie inside them too. A gate is reached when the tool, by the navigation
    estimate and the measured joints, has settled on its planned pose: within ``gate_m`` [m]
    and ``gate_deg`` [°] of it (:data:`SETTLED_M`, :data:`SETTLED_DEG`). The controller drives
    that estimate onto the plan, so the gate waits out the arm's lag; the tool's true error
    there is the estimate's plus the navigation's, which the run is judged on.

    Args:
      robot: the arm; world: the hovering vehicle the simulated arm is mounted on (prepared:
        the simulated arm built its model); controller: the thrusters' PID, levelling and
        period (the executor's tick must equal the period); settings: the whole-body controller
        (``servo_lead_s``: the arm's position loop, ``1 / servo_gain`` for the simulated arm,
        :func:`executor_settings`).
      pose: ``(4,)`` the docked pose ``[x, y, z, ψ]`` [m, rad].

    Attributes (after a run):
      rows: the plan row of every demand, tick by tick; thrust_limited, joint_limited:
        the ticks in which the allocation scaled the thrust demand down, and in which a joint
        rate bound was active.
    """

    def __init__(self, robot: Robot, world: HoverWorld, controller: ControllerSettings, settings: WholeBodySettings,
                 pose, navigation: NavigationSettings | None = None, *, gate_m: float = SETTLED_M,
                 gate_deg: float = SETTLED_DEG) -> None:
        self.robot, self.world, self.controller, self.settings = robot, world, controller, settings
        self.pose, self.navigation = np.asarray(pose, dtype=float), navigation
        self.gate_m, self.gate_rad = float(gate_m), math.radians(gate_deg)
        # The limits the executor's client holds the demands to (the joint table's), within the arm's.
        table = joint_specs(robot)[:robot.n_joints]
        self.lower = np.maximum(np.asarray(robot.lower, float), [j.lower for j in table])
        self.upper = np.minimum(np.asarray(robot.upper, float), [j.upper for j in table])
        self.rows: list[int] = []
        self.thrust_limited = self.joint_limited = 0
        self.wb: WholeBody | None = None

    def prepare(self, q_plan: np.ndarray, period: float) -> None:
        """Build the controller for the executor's plan rows ``q_plan (K, n)``, one per tick of
        ``period`` [s]; ValueError when the tick is not the controller's period."""
        if not math.isclose(period, self.controller.period, rel_tol=1e-9):
            raise ValueError(f"the executor's tick ({period:g} s) must be the whole-body controller's period "
                             f"({self.controller.period:g} s): set its rate to {1.0 / self.controller.period:g} Hz")
        w = self.world
        self.wb = WholeBody(self.robot, w.vehicle, self.controller, self.settings, self.pose, q_plan, w.model)
        self.wb.lower, self.wb.upper = self.lower, self.upper  # its targets within the client's limits
        self._hull = w.model.body(VEHICLE_BODY).id
        position, R = self._truth()[:2]
        self.nav = None if self.navigation is None else NavigationEstimate(self.navigation, position, R)
        self.estimate, self.integral = (position, R), np.zeros(4)

    def _truth(self) -> tuple[np.ndarray, ...]:
        """The vehicle's position [m], orientation, velocity [m/s, world] and angular velocity
        [rad/s, in V] now."""
        d = self.world.data
        return d.qpos[:3].copy(), d.xmat[self._hull].reshape(3, 3).copy(), d.qvel[:3].copy(), d.qvel[3:6].copy()

    def demand(self, k: int, q: np.ndarray) -> np.ndarray:
        """``(n,)`` the arm's joint targets [rad] for plan row ``k`` from the measured angles
        ``q (n,)`` [rad]; the thrusts are commanded on the vehicle."""
        w, period = self.world, self.controller.period
        t = float(w.data.time)
        position, R, velocity, omega = self._truth()
        if self.nav is not None:
            position, R = self.nav.estimate(t, position, R)
        self.estimate = (position, R)
        current = w.current_velocity(t)
        rate = (w.current_velocity(t + period) - current) / period
        q_ref = np.minimum(np.maximum(np.asarray(q, dtype=float), self.lower), self.upper)
        cmd = self.wb.step(k, position, R, velocity, omega, q_ref, self.integral, current, rate)
        w.command_thrust(cmd.thrust, cmd.demand)
        self.integral = cmd.integral
        self.thrust_limited += bool(cmd.thrust_limited)
        self.joint_limited += bool(cmd.joint_limited)
        self.rows.append(int(k))
        return np.asarray(cmd.target, dtype=float)

    def tool_error(self, k: int, q: np.ndarray) -> tuple[float, float]:
        """``(distance [m], angle [rad])`` of the tool from its planned pose at row ``k``, by the
        last navigation estimate and the joint angles ``q (n,)``."""
        eta = self.wb.displacement(*self.estimate)
        T = np.asarray(_fk(self.wb.chain, np.concatenate([eta, np.asarray(q, dtype=float)])), dtype=float)
        e = pose_error(self.wb.T_tool[min(k, len(self.wb.T_tool) - 1)], T)
        return float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))

    def gate(self, k: int, q: np.ndarray) -> str | None:
        """None when the tool has settled on its planned pose at row ``k`` (by the estimate),
        else why not."""
        distance, angle = self.tool_error(k, q)
        if distance <= self.gate_m and angle <= self.gate_rad:
            return None
        return (f"the tool is {1e3 * distance:.1f} mm and {math.degrees(angle):.2f}° from its planned pose by the "
                f"navigation estimate (gate {1e3 * self.gate_m:g} mm, {math.degrees(self.gate_rad):g}°)")

    def stop(self) -> None:
        """The run ended: the station keeping takes the thrusters back (it holds the docked pose)."""
        self.world.release_thrust()

    def plan_rows(self, tick_times: np.ndarray, times: np.ndarray) -> np.ndarray:
        """``(k,)`` int: the plan row in force at each of ``times`` [s]: the row of the last
        demand sent at or before it, the demands sent at ``tick_times`` [s] (the executor's log);
        row 0 before the first."""
        n = min(len(tick_times), len(self.rows))
        if not n:
            return np.zeros(len(times), dtype=int)
        rows = np.asarray(self.rows[:n], dtype=int)
        return rows[np.maximum(np.searchsorted(np.asarray(tick_times)[:n], np.asarray(times) + 1e-9, side="right") - 1, 0)]


# The share of the tool's pose error the arm's demands remove per tick over BPL. The measured
# joints the demands start from are a tick old, so the error follows e' = e − g e₋₁: g = 1 (the
# CPU simulator's, whose reference is its own) rings undamped (z² − z + 1 = 0, |z| = 1), g = 0.5
# settles (|z| = 0.71).
EXECUTOR_TOOL_GAIN = 0.5


def executor_settings(settings: WholeBodySettings, servo_gain: float) -> WholeBodySettings:
    """``settings`` for the simulated BPL arm: its position loop ``v = gain (q* − q)`` needs a
    lead of ``1 / gain`` [s] to follow a ramp (:class:`uvms_jax.hw.SimSettings` ``servo_gain``
    [1/s]; ``servo_lead_s``), and its measured joints come a tick late (``tool_gain``
    :data:`EXECUTOR_TOOL_GAIN`)."""
    if not (math.isfinite(servo_gain) and servo_gain > 0):
        raise ValueError(f"servo_gain must be > 0 [1/s], got {servo_gain}")
    return dataclasses.replace(settings, servo_lead_s=1.0 / servo_gain, tool_gain=EXECUTOR_TOOL_GAIN)
