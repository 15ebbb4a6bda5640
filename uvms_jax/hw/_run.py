"""The hardware stage: run a plan on a link (simulated or real) and write what happened.

:func:`run_plan` is what ``uvms-hw run`` and the end-to-end pipeline both call;
:func:`write_run` writes its files (``run.csv``, ``run.png``, ``results.json``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from uvms_jax.files import RUNNING, clear_running, mark_running, refuse_used_folder, used_run_folder, write_json
from uvms_jax.planfile import Plan

from ._check import PlanSummary, check_arm, check_plan
from ._client import ReachArm
from ._settings import ExecutorSettings, SimSettings
from ._executor import Executor, JointController, RunInterrupted, RunResult
from ._joints import joint_specs
from ._runlog import RunLog
from ._sim import ArmWorld, SimArm
from ._sim_link import LoopbackTransport, SimLink, SimServer, VirtualClock
from ._transport import UdpTransport

__all__ = ["RUN_FILES", "SIM_LINKS", "HwRun", "SimCounts", "existing_run_files", "prepare_out", "run_plan",
           "run_report", "write_run"]

# What a run writes into its folder (and the marker it carries while it runs).
RUN_FILES = ("results.json", "run.csv", "run.png", RUNNING)

# Simulated links by name: the arm in-process on a virtual clock (a run costs only its
# computation), or behind a UDP socket on 127.0.0.1 in real time (the real arm's code path).
SIM_LINKS = ("loopback", "udp")
RETRY = "choose another --out or pass --overwrite"  # what a refused folder's user does instead


@dataclasses.dataclass(frozen=True)
class SimCounts:
    """What the simulated arm and its link counted during a run.

    Attributes:
      limit_violations: demands outside the limits the device received (and ignored).
      dropped: datagrams lost by fault injection (both directions).
      corrupted: replies with a byte changed by fault injection.
      overflowed: replies dropped because the link's bounded queue was full (the oldest go
        first, as on a flooded device; ``QUEUE_LIMIT``).
    """

    limit_violations: int
    dropped: int
    corrupted: int
    overflowed: int = 0


@dataclasses.dataclass(frozen=True)
class HwRun:
    """Outcome of :func:`run_plan`.

    Attributes:
      result: the executor's result (gates, errors, why it stopped).
      log: commanded vs measured joint states of every tick (rad, jaws mm).
      link: ``"loopback"``, ``"udp"`` (simulated arms) or the real link, e.g.
        ``"udp 192.168.2.3:6789"`` or ``"serial /dev/ttyUSB0"``.
      wall_s: wall-clock time of the run, simulator start-up included [s].
      sim: the simulated arm's counters (None on a real arm).
      status: ``"completed"``, ``"aborted"`` (stopped for safety) or ``"interrupted"``
        (SIGINT); the last two held the arm.
    """

    result: RunResult
    log: RunLog
    link: str
    wall_s: float
    sim: SimCounts | None = None

    @property
    def ok(self) -> bool:
        """Every segment completed."""
        return self.result.ok

    @property
    def status(self) -> str:
        """``"completed"``, ``"aborted"`` or ``"interrupted"``."""
        if self.result.interrupted:
            return "interrupted"
        return "completed" if self.result.ok else "aborted"

    @property
    def check(self) -> PlanSummary:
        """The dry run's summary of the plan."""
        return self.result.summary


def run_plan(
    plan: Plan,
    robot,
    *,
    link: str | ReachArm = "loopback",
    config: ExecutorSettings = ExecutorSettings(),
    sim: SimSettings = SimSettings(),
    progress: Callable[[int, int, str], None] | None = None,
    world: ArmWorld | None = None,
    controller: JointController | None = None,
) -> HwRun:
    """Check that ``plan`` was made for ``robot``, dry-run check it, then execute it on ``link``.

    Args:
      plan: joint waypoints in the robot's joint order [rad] and jaws steps [mm].
      robot: the arm (:class:`uvms_jax.robot.Robot`): the plan's ``arm`` record must name it
        (same name, joint names and description digest); a plan with no record must have its
        joint names.
      link: ``"loopback"``: a simulated arm in this process on a virtual clock;
        ``"udp"``: a simulated arm served on 127.0.0.1 over UDP, in real time; or an open
        :class:`ReachArm` client of the robot's joint table (:func:`joint_specs`; a real arm
        in real time; the caller closes it). A simulated arm starts at the plan's first
        waypoint with the jaws at their lower limit. A robot without a hardware profile runs
        on the simulated links only.
      config: executor, safety and link settings.
      sim: the simulated arm and its faults (ignored for a client).
      world: where the simulated arm is mounted (:class:`ArmWorld`, e.g. a hovering vehicle,
        :class:`uvms_jax.hover.HoverWorld`); None: a fixed base. Simulated links only.
      controller: sets the arm's demands between the plan and the arm (:class:`JointController`,
        e.g. :class:`uvms_jax.hover.ExecutorWholeBody` on ``world``); None: the plan's profiles.
      progress: called ``(segment index, n_segments, segment name)`` as segments start.

    Returns:
      the run; a run stopped for safety (arm told to hold) is ``ok=False`` with the reason,
      not an exception.

    Raises:
      RunInterrupted: SIGINT (Ctrl-C) arrived while the plan ran: the arm was told to hold,
        the simulator (if any) stopped; the exception's ``run`` is the partial
        :class:`HwRun` (``status == "interrupted"``) to write. It is a KeyboardInterrupt.
      PlanError: the plan was made for another arm (one line naming both), or the dry run
        refused it; nothing was started or sent.
      ValueError: ``link`` is neither a simulated link name nor a client, a client of another
        joint table, or a real link for a robot without a hardware profile.
    """
    if not (isinstance(link, ReachArm) or link in SIM_LINKS):
        raise ValueError(f"link must be one of {list(SIM_LINKS)} or an open ReachArm client, got {link!r}")
    if world is not None and isinstance(link, ReachArm):
        raise ValueError("a world (e.g. a hovering vehicle) is simulated: it needs a simulated link, not a client")
    check_arm(plan, robot)
    specs = joint_specs(robot)
    if isinstance(link, ReachArm):
        if robot.hardware is None:
            raise ValueError(f"robot {robot.name!r} has no hardware profile (device ids): it runs on the "
                             f"simulated links {list(SIM_LINKS)} only")
        if tuple(link.joints) != specs:
            raise ValueError(f"the client's joint table is not robot {robot.name!r}'s (hw.joint_specs(robot))")
    check_plan(plan, robot, config)  # before any simulator exists: a refused plan starts nothing
    log = RunLog(tuple(j.name for j in specs))
    t0 = time.perf_counter()
    if isinstance(link, ReachArm):
        try:
            result = Executor(link, config, log=log, progress=progress, controller=controller).run(plan)
        except RunInterrupted as e:
            e.run = HwRun(e.result, log, _link_name(link), time.perf_counter() - t0)
            raise
        return HwRun(result, log, _link_name(link), time.perf_counter() - t0)
    interrupted = None
    with _simulated(link, plan, robot, config, sim, world) as (client, sleep, sim_link):
        try:
            result = Executor(client, config, sleep=sleep, log=log, progress=progress,
                              controller=controller).run(plan)
        except RunInterrupted as e:  # the simulator stops first (leaving the with), then it is raised
            interrupted, result = e, e.result
    counts = SimCounts(sim_link.arm.limit_violations, sim_link.dropped, sim_link.corrupted,
                       sim_link.overflowed)
    run = HwRun(result, log, link, time.perf_counter() - t0, counts)
    if interrupted is not None:
        interrupted.run = run
        raise interrupted
    return run


@contextlib.contextmanager
def _simulated(link: str, plan: Plan, robot, config: ExecutorSettings, sim: SimSettings,
               world: ArmWorld | None) -> Iterator[tuple[ReachArm, Callable[[float], None], SimLink]]:
    """A client of a simulated ``robot`` at the plan's start: ``(client, sleep, link)``."""
    start = next(s.q[0] for s in plan.segments if s.q)  # the dry run ensured there is one
    jaws = [joint_specs(robot)[-1].lower] if robot.gripper is not None else []  # at their lower limit
    arm = SimArm(robot, sim, [*start, *jaws], world)
    if link == "loopback":
        clock = VirtualClock()
        sim_link = SimLink(arm)
        with ReachArm(LoopbackTransport(sim_link, clock), arm.joints, clock=clock.now,
                      request_timeout=config.request_timeout_s) as client:
            yield client, clock.sleep, sim_link
    else:
        with SimServer(arm) as server, ReachArm(UdpTransport(*server.address), arm.joints,
                                                request_timeout=config.request_timeout_s) as client:
            yield client, time.sleep, server.link


def _link_name(client: ReachArm) -> str:
    return getattr(client.transport, "name", type(client.transport).__name__)


def _finite(value: float, digits: int | None = None) -> float | None:
    """JSON has no NaN: None for 'not measured'."""
    if math.isnan(value):
        return None
    return value if digits is None else round(value, digits)


def run_report(run: HwRun, out: Path | str | None = None, plan_path: Path | str | None = None) -> dict[str, Any]:
    """``results.json``'s content: the run's key figures, plain JSON values.

    Keys: ``ok``, ``status`` (``completed``, ``aborted`` or ``interrupted``: :attr:`HwRun.status`),
    ``reason``, ``gates``, ``max_gate_error_rad`` [rad], ``max_gate_error_mm`` [mm]
    (None without gates), ``grips``, ``duration_s`` (on the link's clock, virtual for
    ``loopback``) [s], ``abort_after_s`` [s] (None if ok), ``ticks``, ``link_timeouts``,
    ``rejected_states`` (implausible states skipped), ``wall_s`` [s], ``link``, then ``plan`` and ``out`` (paths, when given) and, on a simulated
    arm, ``sim``: ``{limit_violations, dropped, corrupted, overflowed}``.
    """
    r = run.result
    report: dict[str, Any] = {
        "ok": r.ok,
        "status": run.status,
        "reason": r.reason,
        "gates": len(r.gates),
        "max_gate_error_rad": _finite(r.max_gate_error_rad),
        "max_gate_error_mm": _finite(r.max_gate_error_mm),
        "grips": r.grips,
        "duration_s": round(r.duration_s, 3),
        "abort_after_s": _finite(r.abort_after_s, 3),
        "ticks": r.ticks,
        "link_timeouts": r.link_timeouts,
        "rejected_states": r.rejected_states,
        "wall_s": round(run.wall_s, 3),
        "link": run.link,
    }
    if plan_path is not None:
        report["plan"] = str(plan_path)
    if out is not None:
        report["out"] = str(out)
    if run.sim is not None:
        report["sim"] = dataclasses.asdict(run.sim)
    return report


def existing_run_files(out: Path | str) -> list[str]:
    """The names of :data:`RUN_FILES` that folder ``out`` holds ([] for a fresh or missing folder)."""
    return [name for name in RUN_FILES if (Path(out) / name).exists()]


def refuse_out(out: Path | str) -> str | None:
    """Why ``out`` must not take a run (it holds a run's files: :func:`uvms_jax.files.used_run_folder`,
    one line), or None."""
    return used_run_folder(out, RUN_FILES, RETRY)


def prepare_out(out: Path | str, *, overwrite: bool = False) -> Path:
    """Make ``out`` the folder of a run about to start: created, refused if it already holds a
    run's files (:data:`RUN_FILES`: results, or the marker of a run that did not end) unless
    ``overwrite`` (then those files are removed), and marked :data:`~uvms_jax.files.RUNNING`
    until :func:`write_run` writes the results.

    Raises:
      UsedFolderError: ``out`` holds a run's files and ``overwrite`` is off (one line naming
        them and the marker's run, :func:`refuse_out`).
    """
    out = Path(out)
    if not overwrite:
        refuse_used_folder(out, RUN_FILES, RETRY)
    out.mkdir(parents=True, exist_ok=True)
    for name in existing_run_files(out):
        (out / name).unlink()
    mark_running(out)
    return out


def write_run(run: HwRun, out: Path | str, *, plot: bool = True,
              plan_path: Path | str | None = None, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Write ``run.csv`` (every tick), ``results.json`` (:func:`run_report`, with ``extra``'s
    entries added, e.g. a hovering run's ``hover``) and ``run.png`` (if ``plot`` and anything
    was logged) into ``out`` (created), each atomically (a temporary file renamed over it), then
    remove the folder's :data:`~uvms_jax.files.RUNNING` marker; returns the report. The plot
    comes last: a run interrupted again while plotting has its results written already."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    run.log.write_csv(out / "run.csv")
    report = {**run_report(run, out, plan_path), **(extra or {})}
    write_json(out / "results.json", report)
    clear_running(out)
    if plot and run.log.rows:
        run.log.plot(out / "run.png")
    return report
