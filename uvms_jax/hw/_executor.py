"""Trajectory executor: runs a checked plan on a Reach arm with the thesis 4.6 controller.

Per move (waypoint to waypoint, or a jaws step) the executor streams POSITION demands of a
synchronised, velocity- and acceleration-limited profile at ``rate_hz``, reads the measured
state every tick, and after the profile ends holds the goal until the reached-gate passes:
every encoder within ``gate_threshold_rad`` (jaws ``gate_threshold_mm``). Only then does the
next move start. A closing jaws step that stalls on an object (still for ``grip_settle_s``,
short of its goal) has gripped it: its gate passes, and later gates expect the jaws at the
opening where they stopped, so a dropped object stops the run. An arm without a gripper has no
jaws in its joint table (its plans hold still where a gripper would move: dwells, which are
moves to where the arm stands) and takes no gripper step.

The state comes from a request every tick, or from the joints' heartbeat stream
(``ExecutorSettings.stream_hz``); answers lost on the way are made up from ones under
``max_state_age_s`` old. A state that implies a joint moved faster than it can
(``plausible_speed_factor``) is a corrupted frame that passed the CRC: it is skipped and counted.

Safety: the plan is dry-run checked before anything is sent (:class:`PlanError`); every demand
passes the client's send guard. A lost link (no trusted state for ``link_timeout_s``), a non-zero
hardware status, a measured angle outside the limits, a tracking error above
``tracking_error_rad``, a gate not reached within ``gate_timeout_s``, or a refused demand aborts
the run: zero velocity is sent to every joint (hold) and the result says why (``ok=False``).

A :class:`JointController` may sit between the plan and the arm (e.g. the whole-body controller of
a hovering vehicle, :mod:`uvms_jax.hover`): at every tick it turns the plan's demand and the
measured joints into the arm's demands, and it judges the arm's part of each gate. The plan's
demands it follows are the executor's moves back to back (a gate's wait holds its move's last
row). Its demands pass the same send guard (never outside the limits: a refused one aborts the
run), the same tracking check against the demands sent, and the same faults stop the run.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import NamedTuple, Protocol

import numpy as np

from uvms_jax.motion import Move, synchronised_move
from uvms_jax.planfile import Plan

from ._check import PlanSummary, check_plan
from ._client import JointState, ReachArm
from ._settings import ExecutorSettings
from ._ids import HardwareStatus, Mode
from ._joints import LimitError
from ._runlog import RunLog
from ._transport import LinkError

__all__ = ["AbortRun", "Executor", "GateRecord", "JointController", "RunInterrupted", "RunResult"]

INTERRUPTED = "interrupted (SIGINT): the arm was told to hold"  # RunResult.reason of an interrupted run


class AbortRun(RuntimeError):
    """The run was stopped for safety; the arm was told to hold."""


class RunInterrupted(KeyboardInterrupt):
    """The run was interrupted (Ctrl-C, SIGINT); the arm was told to hold.

    A :class:`KeyboardInterrupt`, so a caller that does not look for it still stops, with the
    partial outcome attached: ``result`` (:class:`RunResult`, ``interrupted=True``) and, from
    :func:`~uvms_jax.hw.run_plan`, ``run`` (the :class:`~uvms_jax.hw.HwRun` to write).
    """

    def __init__(self, result: RunResult) -> None:
        super().__init__(result.reason)
        self.result = result
        self.run = None


@dataclasses.dataclass(frozen=True)
class GateRecord:
    """One passed reached-gate.

    Attributes:
      segment, waypoint: where (waypoint -1 = the segment's gripper step).
      error_rad: max |measured - goal| over the arm joints when the gate passed [rad].
      error_mm: |measured - goal| of the jaws [mm] (NaN for an arm without a gripper).
      wait_s: time from the end of the profile to the gate [s].
      gripped: a closing jaws step stopped on an object; ``error_mm`` is then how far short of
        the goal the jaws stopped.
    """

    segment: int
    waypoint: int
    error_rad: float
    error_mm: float
    wait_s: float
    gripped: bool = False


@dataclasses.dataclass(frozen=True)
class RunResult:
    """Outcome of :meth:`Executor.run`.

    Attributes:
      ok: every segment completed.
      reason: "completed" or why the run was aborted.
      gates: passed gates, in order.
      max_gate_error_rad: max arm gate error over all gates [rad] (NaN if none).
      duration_s: time from connect to the end [s].
      ticks: streaming ticks.
      link_timeouts: state requests that went unanswered.
      abort_after_s: time from the start of the failing move to the abort [s] (NaN if ok).
      summary: the dry-run summary.
      rejected_states: received states skipped as implausible (a jump no joint can make:
        a corrupted frame that passed the CRC).
      interrupted: the run was stopped by SIGINT (Ctrl-C), not by a fault; ``ok`` is False.
      start_s: the executor's clock when the run started [s]: the log's times count from it
        (on a simulated link, the simulator's time).
    """

    ok: bool
    reason: str
    gates: tuple[GateRecord, ...]
    max_gate_error_rad: float
    duration_s: float
    ticks: int
    link_timeouts: int
    abort_after_s: float
    summary: PlanSummary
    rejected_states: int = 0
    interrupted: bool = False
    start_s: float = 0.0

    @property
    def max_gate_error_mm(self) -> float:
        """Max jaws error over the gates the jaws reached (grips excluded) [mm]; NaN if none
        (or no jaws)."""
        errs = [g.error_mm for g in self.gates if not g.gripped and not math.isnan(g.error_mm)]
        return max(errs) if errs else math.nan

    @property
    def grips(self) -> int:
        """Jaws steps that stopped on an object."""
        return sum(g.gripped for g in self.gates)


class JointController(Protocol):
    """Sets the arm's joint demands between the plan and the arm, tick by tick.

    The executor calls :meth:`prepare` once at connect, then every tick :meth:`demand` and, once
    a move's profile has ended, :meth:`gate`; :meth:`stop` when the run ends, however it ends.
    """

    def prepare(self, q_plan: np.ndarray, period: float) -> None:
        """``q_plan (K, n)``: the plan's arm demands [rad] at every tick of ``period`` [s], the
        executor's moves back to back; raise ValueError to refuse the run (nothing moved)."""

    def demand(self, k: int, q: np.ndarray) -> np.ndarray:
        """``(n,)`` the arm's joint demands [rad] for row ``k`` of ``q_plan``, from the measured
        angles ``q (n,)`` [rad] (the last trusted state); raise ValueError to stop the run."""

    def gate(self, k: int, q: np.ndarray) -> str | None:
        """None when the arm's part of the gate at row ``k`` is reached with the arm at ``q``
        ``(n,)`` [rad], else why not (one line)."""

    def stop(self) -> None:
        """The run ended (completed, aborted or interrupted): hand back what it drove."""


class _Step(NamedTuple):
    """One move of a run: its goal (every joint), profile, where it is in the plan, and its
    rows of the controller's plan (``first`` to ``last``, inclusive)."""

    goal: np.ndarray
    move: Move
    seg: int
    wp: int
    first: int
    last: int


class Executor:
    """Runs plans through a :class:`ReachArm` client, on the client's joint table.

    Args:
      client: connected client; its clock is the executor's clock, its ``joints`` (the arm's
        joints, then the jaws if it has a gripper; ``joint_specs(robot)``) the limits the
        executor runs within.
      config: rates, thresholds and timeouts.
      sleep: how to wait [s] (``time.sleep``, or a virtual clock's ``sleep``).
      log: where commanded/measured states go (a fresh :class:`RunLog` by default).
      progress: optional callback ``(segment index, n_segments, name)`` for progress display.
      controller: sets the arm's demands from the plan and the measured joints, and judges
        the arm's part of the gates (:class:`JointController`); None: the plan's profiles are
        streamed as they are and the gates read the encoders.
    """

    def __init__(
        self,
        client: ReachArm,
        config: ExecutorSettings = ExecutorSettings(),
        *,
        sleep: Callable[[float], None] = time.sleep,
        log: RunLog | None = None,
        progress: Callable[[int, int, str], None] | None = None,
        controller: JointController | None = None,
    ) -> None:
        self.client = client
        self.controller = controller
        self.config = config
        self.clock = client.clock
        self.sleep = sleep
        self.joints = tuple(client.joints)
        # The jaws (mm), if any, come last; an arm without a gripper has none.
        self.jaws = self.joints[-1] if self.joints[-1].unit == "mm" else None
        self.arm_joints = self.joints[:-1] if self.jaws is not None else self.joints
        misplaced = [j.name for j in self.arm_joints if j.unit == "mm"]
        if misplaced:
            raise ValueError(f"the client's jaws (mm) must be its last joint, got {misplaced} before it")
        self.devices = tuple(j.device_id for j in self.joints)
        self.log = log if log is not None else RunLog(tuple(j.name for j in self.joints))
        self.progress = progress
        n = len(self.joints)
        self._lower = np.array([j.lower for j in self.joints])
        self._upper = np.array([j.upper for j in self.joints])
        self._margin = np.array([config.limit_margin_mm if j.unit == "mm" else config.limit_margin_rad
                                 for j in self.joints])
        self._vmax = np.array([j.max_velocity for j in self.joints]) * config.speed_scale
        self._amax = np.array([j.max_acceleration for j in self.joints]) * config.speed_scale
        self._gate = np.array([config.gate_threshold_mm if j.unit == "mm" else config.gate_threshold_rad
                               for j in self.joints])
        self._arm = np.arange(len(self.arm_joints))
        self._cmd = np.full(n, math.nan)
        self._goal = np.full(n, math.nan)
        self._expected = np.full(n, math.nan)  # what the encoders read at a gate (jaws: on the object)
        self._ticks = self._timeouts = self._rejected = 0
        # Plausibility reference: the last trusted positions and when they arrived.
        self._vlimit = np.array([j.max_velocity for j in self.joints]) * config.plausible_speed_factor
        self._trusted = np.full(n, math.nan)
        self._trusted_t = -math.inf
        self._last_state_t = -math.inf
        self._next_status_t = -math.inf
        self._move_start = math.nan
        self._t0 = 0.0

    # -- public ----------------------------------------------------------------------------
    def run(self, plan: Plan) -> RunResult:
        """Check and execute ``plan``; never raises for run-time faults (see ``RunResult``).

        Raises:
          PlanError: the dry-run check refused the plan (nothing was sent).
        """
        summary = check_plan(plan, self.joints, self.config)
        t0 = self._t0 = self.clock()
        gates: list[GateRecord] = []
        self._move_start = t0
        try:
            steps = self._connect(plan)
            for i, seg in enumerate(plan.segments):
                if self.progress is not None:
                    self.progress(i, len(plan.segments), seg.name)
                gates.extend(self._execute(step) for step in steps if step.seg == i)
            ok, reason, after = True, "completed", math.nan
        except (AbortRun, LinkError, LimitError, ValueError) as e:
            self.client.hold()
            ok, reason = False, f"{type(e).__name__}: {e}"
            after = self.clock() - self._move_start
        except KeyboardInterrupt:  # Ctrl-C: hold, then stop with what was done so far
            self.client.hold()  # the stream is stopped below, as for every end
            raise RunInterrupted(self._result(False, INTERRUPTED, gates, t0, self.clock() - self._move_start,
                                              summary, interrupted=True)) from None
        except BaseException:
            self.client.hold()
            raise
        finally:
            if self.config.stream_hz:
                self.client.stop_stream()
            if self.controller is not None:
                self.controller.stop()
        return self._result(ok, reason, gates, t0, after, summary)

    def _result(self, ok: bool, reason: str, gates: list[GateRecord], t0: float, after: float,
                summary: PlanSummary, interrupted: bool = False) -> RunResult:
        errs = [g.error_rad for g in gates]
        return RunResult(ok, reason, tuple(gates), max(errs) if errs else math.nan, self.clock() - t0,
                         self._ticks, self._timeouts, after, summary, self._rejected, interrupted, t0)

    # -- steps -----------------------------------------------------------------------------
    def _connect(self, plan: Plan) -> list[_Step]:
        """Check the arm's start, set position mode; the run's moves (the controller prepared
        for them)."""
        cfg = self.config
        meas = self._start_state()
        self._check_status(force=True)
        self._check_measured(meas)
        q_start = np.asarray(plan.segments[0].q[0]) if plan.segments[0].q else None
        if q_start is None:  # first segment is gripper-only: start at the first waypoint found
            q_start = np.asarray(next(s.q[0] for s in plan.segments if s.q))
        err = np.abs(meas[self._arm] - q_start)
        j = int(np.argmax(err))
        if err[j] > cfg.start_tolerance_rad and not cfg.approach:
            raise AbortRun(f"arm is {err[j]:.3f} rad from the plan start on joint {self.joints[j].name} "
                           f"(tolerance {cfg.start_tolerance_rad} rad); move it there first or allow the approach move")
        self._goal = meas.copy()
        self._expected = meas.copy()
        self._cmd = meas.copy()
        steps = self._steps(plan, meas)
        if self.controller is not None:
            dt = 1.0 / cfg.rate_hz
            rows = [s.move.sample(min(j * dt, s.move.duration))[0][self._arm] for s in steps
                    for j in range(s.last - s.first + 1)]
            self.controller.prepare(np.array(rows), dt)
        self.client.set_mode(Mode.POSITION)
        if cfg.stream_hz:
            self.client.start_stream(cfg.stream_hz)
        return steps

    def _steps(self, plan: Plan, start: np.ndarray) -> list[_Step]:
        """Every move of ``plan`` from the arm at ``start`` (a waypoint, or a jaws step), with
        its profile and its rows: one per tick until the tick at or after the profile's end."""
        steps, goal, row, dt = [], start.copy(), 0, 1.0 / self.config.rate_hz
        for i, seg in enumerate(plan.segments):
            moves = [(k, seg.q[k], seg.t[k] - seg.t[k - 1] if k > 0 else 0.0) for k in range(len(seg.q))
                     if not (k == 0 and i > 0)]  # continuity: the previous gate already holds a segment's start
            moves += [(-1, seg.jaws_mm, 0.0)] if seg.jaws_mm is not None else []
            for k, value, min_dt in moves:
                new = goal.copy()
                if k >= 0:
                    new[self._arm] = value
                else:
                    new[-1] = value
                move = synchronised_move(goal, new, self._vmax, self._amax, min_dt)
                n = math.ceil(move.duration / dt - 1e-9) + 1
                steps.append(_Step(new, move, i, k, row, row + n - 1))
                goal, row = new, row + n
        return steps

    def _start_state(self) -> np.ndarray:
        """The arm's positions at connect: two consecutive states that agree, so that a
        corrupted frame cannot become the reference the later states are judged against."""
        cfg = self.config
        prev = None
        for _ in range(cfg.connect_retries):
            state = self.client.read_state(self.devices, timeout=cfg.request_timeout_s * 5,
                                           retries=cfg.connect_retries)
            now = self.clock()
            pos, vel = np.asarray(state.positions), np.asarray(state.velocities)
            if prev is not None and self._plausible(pos, vel, *prev):
                self._trusted, self._trusted_t = pos, now
                self._last_state_t = now
                return pos
            prev = (pos, now)
        raise AbortRun(f"no two consecutive start states agree within {cfg.connect_retries} reads: "
                       "the link corrupts what it carries")

    def _execute(self, step: _Step) -> GateRecord:
        """Stream one synchronised move from the current goal to the step's goal, then gate."""
        cfg, goal, move, seg, wp = self.config, step.goal, step.move, step.seg, step.wp
        moving = np.flatnonzero(np.abs(goal - self._goal) > 0) if np.all(np.isfinite(self._goal)) \
            else np.arange(len(goal))
        if self.controller is not None:  # it sets every arm joint every tick
            moving = np.union1d(self._arm, moving)
        jaws = self.jaws is not None
        closing = jaws and goal[-1] < self._goal[-1]
        expected = np.where(goal != self._goal, goal, self._expected)
        start = self.clock()
        self._move_start = start
        self._goal = goal.copy()
        still_since, still_at = math.inf, math.nan  # jaws stall detection after the profile
        phase = "gripper" if wp < 0 else "move"
        dt = 1.0 / cfg.rate_hz
        k = 0
        while True:
            t = self.clock() - start
            q_cmd, _ = move.sample(t)
            row = step.first + min(round(t / dt), step.last - step.first)
            if self.controller is not None:
                q_cmd[self._arm] = self.controller.demand(row, self._trusted[self._arm].copy())
            self._cmd = q_cmd
            if len(moving):
                self.client.set_positions((self.devices[i], float(q_cmd[i])) for i in moving)
            meas = self._measure()
            self.log.add(self.clock() - self._t0, seg, wp, phase if t < move.duration else "gate", q_cmd, meas)
            self._ticks += 1
            if meas is not None:
                self._check_measured(meas)
                lag = np.abs(meas[self._arm] - q_cmd[self._arm])
                if np.max(lag) > cfg.tracking_error_rad:
                    j = int(np.argmax(lag))
                    raise AbortRun(f"segment {seg} waypoint {wp}: joint {self.joints[j].name} lags its demand by "
                                   f"{lag[j]:.3f} rad > {cfg.tracking_error_rad} rad")
                if t >= move.duration:
                    err = np.abs(meas - expected)
                    arm_off = self._arm_gate(row, meas, err)
                    if arm_off is None and (not jaws or err[-1] <= self._gate[-1]):
                        self._expected = expected
                        return GateRecord(seg, wp, float(np.max(err[self._arm])),
                                          float(err[-1]) if jaws else math.nan, t - move.duration)
                    if jaws and not abs(meas[-1] - still_at) <= self._gate[-1]:  # jaws moved (or first reading)
                        still_since, still_at = t, meas[-1]
                    gripped = (closing and meas[-1] > goal[-1] and t - still_since >= cfg.grip_settle_s
                               and arm_off is None)
                    if gripped:
                        self._expected = np.append(expected[:-1], meas[-1])
                        return GateRecord(seg, wp, float(np.max(err[self._arm])), float(err[-1]),
                                          t - move.duration, gripped=True)
            if t >= move.duration + cfg.gate_timeout_s:
                detail = ""
                if meas is not None:
                    ratio = np.abs(meas - expected) / self._gate
                    if self.controller is not None:
                        ratio[self._arm] = 0.0  # the controller judges the arm
                    j = int(np.argmax(ratio))
                    unit = self.joints[j].unit
                    if self.controller is None or ratio[j] > 1.0:
                        detail = (f"; joint {self.joints[j].name} error {abs(meas[j] - expected[j]):.4f} {unit}"
                                  f" > {self._gate[j]} {unit}")
                    if self.controller is not None and (off := self._arm_gate(row, meas, ratio)) is not None:
                        detail += f"; {off}"
                raise AbortRun(f"segment {seg} waypoint {wp}: gate not reached within "
                               f"{cfg.gate_timeout_s} s after the move{detail}")
            k += 1
            delay = start + k * dt - self.clock()
            if delay > 0:
                self.sleep(delay)
            else:
                k = int((self.clock() - start) / dt)  # behind schedule: do not try to catch up

    def _arm_gate(self, row: int, meas: np.ndarray, err: np.ndarray) -> str | None:
        """None when the arm's part of the gate is reached: the controller's judgement at plan
        row ``row``, else every arm encoder within the threshold of its goal (``err``)."""
        if self.controller is not None:
            return self.controller.gate(row, meas[self._arm].copy())
        off = err[self._arm] > self._gate[self._arm]
        return None if not off.any() else f"{int(off.sum())} arm joint(s) outside the gate threshold"

    def _measure(self) -> np.ndarray | None:
        """Measured positions (n,) or None if this tick's state did not arrive or is implausible."""
        try:
            self._check_status()
            state = self._read_state()
        except LinkError as e:
            self._timeouts += 1
            self._check_silence(f"last error: {e}")
            return None
        now = self.clock()
        self._last_state_t = now
        pos, vel = np.asarray(state.positions), np.asarray(state.velocities)
        if not self._plausible(pos, vel, self._trusted, self._trusted_t):
            self._rejected += 1
            self._check_silence(f"{self._rejected} implausible states skipped")
            return None
        self._trusted, self._trusted_t = pos, now
        return pos

    def _read_state(self) -> JointState:
        """This tick's state: requested, or the streamed packets that arrived since the last
        state. When some were lost (each device answers in its own datagram, so the 2 (n + 1) answers
        rarely all arrive on a lossy link), it is completed from those under
        ``max_state_age_s`` old."""
        cfg = self.config
        try:
            if cfg.stream_hz:
                return self.client.stream_state(self.devices, since=self._last_state_t,
                                                timeout=max(cfg.request_timeout_s, 1.5 / cfg.stream_hz))
            return self.client.read_state(self.devices, timeout=cfg.request_timeout_s)
        except LinkError as e:
            try:
                return self.client.stream_state(self.devices, since=self.clock() - cfg.max_state_age_s, timeout=0.0)
            except LinkError:
                raise e from None

    def _check_silence(self, detail: str) -> None:
        """Abort when no trusted state has arrived for ``link_timeout_s``."""
        silent = self.clock() - self._trusted_t
        if silent > self.config.link_timeout_s:
            raise LinkError(f"lost link: no state for {silent:.2f} s (limit {self.config.link_timeout_s} s); {detail}")

    def _plausible(self, pos: np.ndarray, vel: np.ndarray, ref: np.ndarray, ref_t: float) -> bool:
        """Whether a state could follow ``ref`` (positions at time ``ref_t``): no joint moved or
        moves faster than ``plausible_speed_factor`` × its limit (see :class:`ExecutorSettings`)."""
        if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(vel))):
            return False
        if np.any(np.abs(vel) > self._vlimit):
            return False
        dt = max(self.clock() - ref_t, 1.0 / self.config.rate_hz)
        return bool(np.all(np.abs(pos - ref) <= self._vlimit * dt + self._gate))

    def _check_status(self, force: bool = False) -> None:
        """Abort on any non-zero hardware status. Answers lost on the way are asked again at the
        next tick; a device whose status has not arrived for ``link_timeout_s`` is a lost link."""
        cfg = self.config
        now = self.clock()
        if not force and now < self._next_status_t:
            return
        try:
            status = self.client.read_hardware_status(
                self.devices, timeout=cfg.request_timeout_s * (5 if force else 1),
                retries=cfg.connect_retries if force else 1)
            self._next_status_t = now + cfg.status_period_s
        except LinkError:
            if force:
                raise
            status = self.client.recent_hardware_status(self.devices, since=now - cfg.link_timeout_s)
            missing = [d for d in self.devices if d not in status]
            if missing:
                names = {j.device_id: j.name for j in self.joints}
                raise LinkError(f"lost link: no hardware status from joint(s) "
                                f"{', '.join(names[d] for d in missing)} for {cfg.link_timeout_s} s") from None
        bad = {d: s for d, s in status.items() if s != HardwareStatus.OK}
        if bad:
            names = {j.device_id: j.name for j in self.joints}
            text = "; ".join(f"joint {names[d]} (0x{d:02X}): {s!r}" for d, s in bad.items())
            raise AbortRun(f"hardware status fault: {text}")

    def _check_measured(self, meas: np.ndarray) -> None:
        low = meas < self._lower - self._margin
        high = meas > self._upper + self._margin
        bad = np.flatnonzero(low | high | ~np.isfinite(meas))
        if len(bad):
            j = int(bad[0])
            s = self.joints[j]
            raise AbortRun(f"limit breach: joint {s.name} measured {meas[j]:.4f} {s.unit} outside "
                           f"[{s.lower}, {s.upper}] ± {self._margin[j]}")
