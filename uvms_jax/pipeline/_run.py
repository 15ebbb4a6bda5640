"""The end-to-end run: every configured stage in data-flow order, in one process."""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

import jax

from uvms_jax import plan as planning_kernels
from uvms_jax import progress
from uvms_jax.files import RUNNING, clear_running, mark_running, refuse_used_folder, write_json
from uvms_jax.pipeline._precheck import Checked, check_stages
from uvms_jax.pipeline._report import write_summary
from uvms_jax.pipeline._settings import STAGES, PipelineSettings
from uvms_jax.pipeline.stages import STAGE_FNS, Flow, chain

log = logging.getLogger(__name__)

# What a pipeline run writes into its folder (its results, and the marker it carries while it
# runs): a folder holding any of them holds a run.
RUN_FILES = ("results.json", "summary.md", RUNNING)
# What a refused rerun is told to do instead (experiments/pipeline.py's options).
RETRY = "choose another hydra.run.dir or pass --overwrite"



def run_pipeline(settings: PipelineSettings, out: Path, config_text: str = "", checked: Checked | None = None, *,
                 overwrite: bool = False) -> dict:
    """Run the configured stages into ``out`` (one folder per stage) and write ``summary.md``
    and ``results.json``; returns results.json's dict.

    Each stage calls its package's stage function and writer; results pass from stage to stage
    in memory (planning metrics → cost matrix, the winning schedule → its plan → execution).

    The folder carries a ``RUNNING`` marker (:data:`uvms_jax.files.RUNNING`) from the start
    until results.json and summary.md are written (each atomically), so a killed run is
    recognisable: it has the marker and no results.json. A folder that holds an earlier run
    (:data:`RUN_FILES`: its results or its marker) is refused, unless ``overwrite`` (then they
    are removed at the start). A run stopped by an exception, Ctrl-C or SIGTERM keeps the
    marker too, rewritten to say so: ``status`` (``interrupted`` or
    ``failed``), the stage it stopped in, the error, and the finished stages' results (their
    folders keep what they wrote); results.json is never written for it, so nothing reads a
    partial run as a finished one.

    What the stages need of the arm is checked first (:func:`check_stages`): a run that cannot
    finish is refused before anything is written.

    Args:
      settings: every stage's settings.
      out: the run directory.
      config_text: the config as YAML, copied into summary.md.
      checked: :func:`check_stages` of ``settings``, where the caller has it already.
      overwrite: run in a folder that holds an earlier run.

    Raises:
      UsedFolderError: ``out`` holds an earlier run and ``overwrite`` is off (one line naming
        the files and the marker's run, :func:`uvms_jax.files.used_run_folder`); nothing written.
      SettingsError: what a stage cannot do for the arm (one line), before any stage runs.
    """
    out = Path(out)
    if not overwrite:
        refuse_used_folder(out, RUN_FILES, RETRY)
    checked = check_stages(settings) if checked is None else checked
    mark_running(out)
    # A folder used before (overwrite): its results are not this run's, and must not stand for
    # it if this run stops early (it writes them anew at the end).
    for name in ("results.json", "summary.md"):
        (out / name).unlink(missing_ok=True)
    done: dict = {}
    try:
        results = _run_stages(settings, out, config_text, done, checked)
    except BaseException as e:
        status = "interrupted" if isinstance(e, KeyboardInterrupt) else "failed"
        stage = next((s for s in STAGES if s in settings.stages and s not in done), None)
        mark_running(out, status=status, stage=stage, error=f"{type(e).__name__}: {e}", finished=done)
        log.error("pipeline %s in stage %s; partial run in %s (marker %s)", status, stage, out, RUNNING)
        raise
    clear_running(out)
    return results


def _warm_planner(settings: PipelineSettings, order: list[str], robot) -> None:
    """Compile the planner's Numba kernels in a background thread while the stages before the
    planning run (:func:`uvms_jax.plan.warm_kernels`): on a machine's first run their
    compilation then overlaps with those stages' XLA work instead of lengthening the planning
    stage. Nothing to do when planning comes first or uses no compiled checker; a failure is
    logged, and the planning stage compiles (and reports) for itself."""
    planning = [s for s in ("plan", "baseline") if s in order]
    if not planning or order.index(planning[0]) == 0 or settings.plan.checker != "query":
        return

    def warm() -> None:
        try:
            planning_kernels.warm_kernels(robot)
        except Exception as e:  # noqa: BLE001  (the planning stage meets and reports it)
            log.warning("compiling the planner's kernels ahead failed: %s: %s", type(e).__name__, e)

    threading.Thread(target=warm, name="planner-kernels", daemon=True).start()


def _run_stages(settings: PipelineSettings, out: Path, config_text: str, done: dict, checked: Checked) -> dict:
    """:func:`run_pipeline`'s work; ``done`` collects each finished stage's results."""
    order = [s for s in STAGES if s in settings.stages]
    log.info("pipeline stages %s into %s; devices %s", order, out, jax.devices())
    checked.log_findings(order)
    # One arm for every stage: the scenario's (planning.scenario_robot).
    flow = Flow(robot=checked.robot, baseline_scene=checked.baseline_scene, baseline_skipped=checked.baseline_skipped)
    _warm_planner(settings, order, checked.robot)
    reports = []
    t_start = time.perf_counter()
    for name in progress.bar(order, desc="pipeline", unit="stage"):
        stage_out = out / name
        stage_out.mkdir(parents=True, exist_ok=True)
        log.info("== stage %s", name)
        t0, c0 = time.perf_counter(), time.process_time()
        report = STAGE_FNS[name](settings, stage_out, flow)
        report.seconds, report.cpu_seconds = time.perf_counter() - t0, time.process_time() - c0
        reports.append(report)
        flow.reports[name] = report
        done[name] = report.results
        log.info("== stage %s done in %.1f s: %s", name, report.seconds, report.results)
    total = time.perf_counter() - t_start
    results = {"total_seconds": total, "stage_seconds": {r.name: r.seconds for r in reports},
               "stage_cpu_seconds": {r.name: r.cpu_seconds for r in reports},
               "arm": checked.arm_record(), **{r.name: r.results for r in reports}}
    write_json(out / "results.json", results, default=str)
    summary = write_summary(out, reports, total, config_text, chain(flow, out))
    log.info("pipeline done in %.1f s; summary: %s", total, summary)
    return results
