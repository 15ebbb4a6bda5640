"""End-to-end pipeline: what ``make demo`` runs (issue 8; DESIGN.md "Data flow").

Stages, each in its own folder of the Hydra run directory:

  docking/    docking GA (fast preset), grid and CMA-ES references, w_max maps (SPEC §3)
              — experiments/docking.py, driven with its own config (configs/docking.yaml)
  surrogate/  small FFBN/RBFN surrogates of w and KCI, timed against the analytic index (§4)
              — experiments/surrogate.py (configs/surrogate.yaml, ``surrogate=small``)
  plan/       IK targets and OMPL plans of every task-graph edge of the thesis cage, edges.csv,
              metric and cost matrices, end-effector path plots (§5; uvms_jax.plan)
  schedule/   cost matrix from plan/edges.csv → greedy, GRASP, A*, exact (experiments/schedule.py)
              and the thesis eq. 4.1 instance beside the thesis timings; the winner's plan.json
  hw/         the winner's plan.json checked (dry run) and executed on the simulated Bravo 7
              (in-process loopback on a virtual clock, or a UDP simulator in real time)

and ``summary.md`` (every stage's table, the papers' figures next to ours, links to every PNG)
and ``results.json`` (key figures, for ``experiments/gather.py``) in the run directory.

    python experiments/pipeline.py                      # the demo (< 10 min on 2 CPU cores)
    python experiments/pipeline.py experiment=tiny      # smoke run
    python experiments/pipeline.py 'stages=[schedule,hw]' hw.plan=examples/thesis_plan.json

Call :func:`run_pipeline` with a composed config and an output folder to drive it from Python
(tests do). The docking and surrogate experiments are run through their ``main`` with a config
composed from their own YAML plus ``<stage>.overrides``; planning and scheduling through their
``run`` functions (the planning result stays in memory so that the schedule's winner becomes a
plan.json without planning twice).
"""

from __future__ import annotations

import contextlib
import csv
import importlib.util
import json
import logging
import math
import os
import platform
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

import hydra  # noqa: E402
import jax  # noqa: E402
import numpy as np  # noqa: E402
from hydra.core.global_hydra import GlobalHydra  # noqa: E402
from hydra.core.hydra_config import HydraConfig  # noqa: E402
from omegaconf import DictConfig, OmegaConf, open_dict  # noqa: E402
from tqdm import tqdm  # noqa: E402

from uvms_jax import hw, sched  # noqa: E402

log = logging.getLogger("pipeline")

ROOT = Path(__file__).resolve().parents[1]
CONFIG_DIR = ROOT / "configs"
EXAMPLE_PLAN = ROOT / "examples" / "thesis_plan.json"
STAGES = ("docking", "surrogate", "plan", "schedule", "hw")

# Thesis Table 5.5 solver times on the eq. 4.1 matrix [ms] (SPEC §5).
THESIS_MS = {"greedy": 0.0121, "grasp": 110.2, "astar": 0.9435, "exact": None}
# Docking paper Table 3 (SPEC §3): best pose and the M_a range of its seven GA runs.
PAPER_DOCKING = {"pose": (-0.32, -0.36, 0.24, 0.79), "Ma": (0.134, 0.181)}


# -- plumbing ------------------------------------------------------------------------------
@dataclass
class StageReport:
    """What a stage contributes to summary.md and results.json."""

    name: str
    title: str
    tables: list[str] = field(default_factory=list)  # markdown blocks
    results: dict[str, Any] = field(default_factory=dict)  # key figures (flat-ish, JSON)
    notes: list[str] = field(default_factory=list)
    seconds: float = math.nan
    cpu_seconds: float = math.nan  # process CPU time (all threads): a load-independent size of the work


def _experiment(name: str) -> ModuleType:
    """``experiments/<name>.py`` as a module (without putting experiments/ on sys.path)."""
    key = f"uvms_experiments.{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, ROOT / "experiments" / f"{name}.py")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[key] = mod
        spec.loader.exec_module(mod)
    return sys.modules[key]


def compose_stage(config_name: str, overrides: list[str]) -> DictConfig:
    """A stage experiment's config (``configs/<config_name>.yaml`` + overrides), composed with
    the running Hydra (inside ``@hydra.main`` or a ``hydra.initialize*`` block) or on its own."""
    if GlobalHydra.instance().is_initialized():
        return hydra.compose(config_name=config_name, overrides=list(overrides))
    with hydra.initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
        return hydra.compose(config_name=config_name, overrides=list(overrides))


@contextlib.contextmanager
def hydra_output_dir(path: Path) -> Iterator[None]:
    """Point ``HydraConfig.get().runtime.output_dir`` at ``path`` while a stage experiment's
    ``main`` runs, so that it writes into the stage folder; restored afterwards."""
    inst = HydraConfig.instance()
    saved = inst.cfg
    inst.cfg = OmegaConf.create({"hydra": {"runtime": {"output_dir": str(path), "cwd": os.getcwd()},
                                           "job": {"name": path.name}}})
    try:
        yield
    finally:
        inst.cfg = saved


def _merge_into(stage_cfg: DictConfig, key: str, values: Any) -> None:
    with open_dict(stage_cfg):
        if key in stage_cfg and isinstance(values, DictConfig):
            stage_cfg[key] = OmegaConf.merge(stage_cfg[key], values)
        else:
            stage_cfg[key] = values


def md_table(header: list[str], rows: list[list[Any]]) -> str:
    def fmt(v: Any) -> str:
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return "—"
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(fmt(v) for v in r) + " |" for r in rows]
    return "\n".join(lines)


# -- stages ----------------------------------------------------------------------------------
def stage_docking(cfg: DictConfig, out: Path, ctx: dict) -> StageReport:
    """Docking GA (+ grid/CMA-ES references) and w_max maps via experiments/docking.py."""
    dcfg = compose_stage("docking", cfg.docking.overrides)
    _merge_into(dcfg, "ga", cfg.ga)
    _merge_into(dcfg, "seed", int(cfg.seed))
    with hydra_output_dir(out):
        summary = _experiment("docking").main(dcfg)
    with (out / "runs.csv").open() as f:
        runs = list(csv.DictReader(f))
    grid = json.loads((out / "grid_optimum.json").read_text())
    wmax = json.loads((out / "wmax.json").read_text())
    rows = [[i + 1, *(round(float(r[k]), 3) + 0.0 for k in ("x", "y", "z", "psi")), float(r["fitness"]), float(r["Ma"]),
             int(r["generations"])] for i, r in enumerate(runs)]
    pp = PAPER_DOCKING
    rows.append(["paper Table 3", *pp["pose"], None, f"{pp['Ma'][0]}–{pp['Ma'][1]}", "≤ 500"])
    rows.append(["grid optimum", *(round(v, 3) + 0.0 for v in grid["pose"].values()), grid["fitness"], grid["Ma"],
                 f"{grid['candidates']} candidates"])
    t1 = md_table(["GA run", "x [m]", "y [m]", "z [m]", "ψ [rad]", "fitness (eq. 15)", "M_a (eq. 1)", "generations"], rows)
    t2 = md_table(
        ["pose", "x, y, z, ψ", "zero-w area of the task area", "mean w_max", "paper"],
        [["best GA pose", ", ".join(f"{v:.3f}" for v in wmax["best"]["pose"].values()),
          f"{100 * wmax['best']['zero_w_fraction']:.1f} %", wmax["best"]["w_max_mean"], "Fig. 9: w_max stays high"],
         ["ill-placed (paper)", ", ".join(f"{v:.3f}" for v in wmax["ill_placed"]["pose"].values()),
          f"{100 * wmax['ill_placed']['zero_w_fraction']:.1f} %", wmax["ill_placed"]["w_max_mean"],
          "Fig. 10: large zero-w region"]])
    f_ga = np.asarray(summary["ga_fitness"])
    res = {"ga_best_fitness": float(f_ga.max()), "ga_ratio_to_grid_min": float(min(summary["ga_ratio_to_grid"])),
           "ga_batch_seconds": summary["ga_batch_seconds"], "grid_fitness": grid["fitness"],
           "zero_w_best": wmax["best"]["zero_w_fraction"], "zero_w_ill_placed": wmax["ill_placed"]["zero_w_fraction"],
           "all_face_task_area": summary["all_face_task_area"]}
    notes = [f"{len(runs)} GA runs in one jitted batch: {summary['ga_batch_seconds']:.2f} s after compilation "
             f"(compile + first batch {summary['ga_compile_and_first_batch_seconds']:.1f} s); "
             f"GA / grid optimum {min(summary['ga_ratio_to_grid']):.3f}–{max(summary['ga_ratio_to_grid']):.3f}.",
             "Absolute M_a differs from the paper's (its frames are not fully given; SPEC §1.1): compare the "
             "placement (near quarter, facing the task area) and the w_max maps."]
    ctx["docking_pose"] = [float(runs[int(np.argmax(f_ga))][k]) for k in ("x", "y", "z", "psi")]
    return StageReport("docking", "Docking GA and w_max maps (SPEC §3, docking paper Table 3, Figs 9–10)",
                       [t1, t2], res, notes)


def stage_surrogate(cfg: DictConfig, out: Path, ctx: dict) -> StageReport:
    """Small FFBN/RBFN surrogates via experiments/surrogate.py."""
    scfg = compose_stage("surrogate", cfg.surrogate.overrides)
    _merge_into(scfg, "seed", int(cfg.seed))
    with hydra_output_dir(out):
        _experiment("surrogate").main(scfg)
    report = json.loads((out / "report.json").read_text())
    rows, res = [], {}
    for name, n in report["networks"].items():
        p = n["paper"]
        t = n.get("timing", {}).get("1000", {})
        t5 = n.get("timing", {}).get("100000", {})
        units = n["hidden_units"] if n["kind"] == "ffbn" else f"{n['hidden_units']} (spread {n['spread']:.3g})"
        paper_units = p.get("hidden_units", f"spread {p.get('spread')}")
        rows.append([name, units, paper_units, f"{100 * n['max_rel_test_error']:.2f} %", n["operation_count"],
                     p["operation_count"], t.get("network_s", math.nan) * 1e3, p["seconds_1000"] * 1e3,
                     t.get("speedup"), t5.get("speedup")])
        res[f"{name}_max_rel_error"] = n["max_rel_test_error"]
        res[f"{name}_units"] = n["hidden_units"]
        if t5:
            res[f"{name}_speedup_1e5"] = t5["speedup"]
    for index, a in report["analytic"].items():
        t = a["timing"].get("1000", {})
        rows.append([f"analytic {index}", "—", "—", "—", a["xla_flops_per_sample"], a["paper"]["operation_count"],
                     t.get("seconds", math.nan) * 1e3, a["paper"]["seconds_1000"] * 1e3, None, None])
    table = md_table(["network", "units (ours)", "units (paper)", "max rel. test error (eq. 21)", "ops (ours)",
                      "ops (paper Table 4)", "1000 inputs [ms] (ours)", "1000 inputs [ms] (paper Table 5)",
                      "speed-up at 1e3", "speed-up at 1e5"], rows)
    notes = ["Ours: float32, jitted, compilation excluded, this machine; paper: Matlab on an i7-3930K. "
             "Analytic ops (ours) are XLA flops per sample.",
             "Acceptance figures: " + ", ".join(f"{k} = {v:.3g}" if isinstance(v, float) else f"{k} = {v}"
                                                for k, v in report["acceptance"].items())]
    return StageReport("surrogate", "Surrogates of w and KCI (SPEC §4, dexterity paper Tables 4–5)", [table], res, notes)


def stage_plan(cfg: DictConfig, out: Path, ctx: dict) -> StageReport:
    """IK targets and OMPL plans of every task-graph edge via experiments/plan.py's ``run``,
    kept in memory so the schedule's winner becomes a plan.json without planning twice."""
    jax.config.update("jax_enable_x64", True)  # as experiments/plan.py: IK in float64
    pc = cfg.plan
    t0 = time.perf_counter()
    planned = _experiment("plan").run(cfg, out)
    log.info("%d planners over the task graph in %.1f s", len(planned.by_planner), time.perf_counter() - t0)
    ctx["plan"] = planned
    rows, res = [], {"ik_seconds": planned.ik_seconds}
    for planner, s in planned.summary.items():
        rows.append([planner, f"{s['success']}/{s['edges']}", f"{s['revalidated']}/{s['edges']}",
                     1e3 * s["median_planning_time_s"], 1e3 * s["mean_planning_time_s"],
                     1e3 * s["max_planning_time_s"]])
        res[f"{planner}_success"] = s["success"]
        res[f"{planner}_median_ms"] = 1e3 * s["median_planning_time_s"]
    table = md_table(["planner", "planned", "re-checked OK", "median [ms]", "mean [ms]", "max [ms]"], rows)
    n_edges = len(next(iter(planned.by_planner.values()), []))
    notes = [f"{n_edges} task-graph edges (thesis Table 5.1 / eq. 4.1 structure), budget {pc.budget_s} s per edge; "
             f"IK targets {planned.ik_seconds:.1f} s (mostly XLA compilation). Every path re-checked at "
             f"{pc.recheck_resolution} rad with margin 0 and time-parameterised ({pc.max_velocity} rad/s). "
             "The thesis publishes no per-edge planning times; BENCHMARKS.md has a 5 s-budget run of all three planners."]
    return StageReport("plan", "Bravo 7 planning of the thesis cage (SPEC §5, thesis ch. 5.1)", [table], res, notes)


def stage_schedule(cfg: DictConfig, out: Path, ctx: dict) -> StageReport:
    """Cost matrix from plan/edges.csv → all solvers (experiments/schedule.py); the thesis
    eq. 4.1 instance beside the thesis timings; the winner's plan.json."""
    ex = _experiment("schedule")
    planned = ctx.get("plan")
    overrides = list(cfg.sched.overrides)
    planner = cfg.sched.planner or (cfg.plan.planners[0] if planned else None)
    if planned:
        overrides = ["sched/source=edges_csv", f"sched.source.path={planned.edges_csv}",
                     f"sched.source.planner={planner}", *overrides]
    scfg = compose_stage("schedule", overrides)
    _merge_into(scfg, "seed", int(cfg.seed))
    with open_dict(scfg):
        scfg.sched.weights = cfg.sched.weights
    results = ex.run(scfg, out)
    solvers = results["solvers"]
    winner = min(solvers.values(), key=lambda r: (r["cost"], r["solver"] != "exact"))
    rows = [[r["solver"], r["path"], r["cost"], r["time_ms"], THESIS_MS.get(r["solver"])] for r in solvers.values()]
    t1 = md_table(["solver", "schedule", "cost", "time [ms] (ours)", "thesis Table 5.5 [ms] (eq. 4.1 matrix)"], rows)
    metric_rows = [[r["solver"], *(r[f"N_{m}"] for m in sched.METRICS)] for r in solvers.values()]
    t_metrics = md_table(["solver", *(f"Σ N {m}" for m in sched.METRICS)], metric_rows)

    # The thesis's own instance (eq. 4.1): same solvers, next to its published schedule and times.
    problem = sched.thesis_problem()
    key = jax.random.key(int(cfg.seed))
    g = ex.grasp_kwargs(scfg)
    fns = {"greedy": lambda: sched.greedy(problem), "grasp": lambda: sched.grasp(problem, key, **g),
           "astar": lambda: sched.astar(problem), "exact": lambda: sched.exact(problem)}
    thesis_rows, thesis_res = [], {}
    for name in scfg.sched.solvers:
        fns[name]()  # warm-up / compile
        runs = [fns[name]() for _ in range(max(1, int(scfg.sched.timing_repeats)))]
        s = runs[0]
        t_ms = float(np.median([r.wall_time_s for r in runs])) * 1e3
        thesis_path = "-".join(map(str, sched.THESIS_EQ41_GREEDY_PATH)) if name == "greedy" else None
        thesis_rows.append([name, s.path_str(), s.cost, thesis_path, t_ms, THESIS_MS.get(name)])
        thesis_res[f"thesis_{name}_cost"] = s.cost
        thesis_res[f"thesis_{name}_ms"] = t_ms
    t2 = md_table(["solver", "schedule (ours)", "cost", "thesis schedule", "time [ms] (ours)", "thesis [ms]"],
                  thesis_rows)

    res = {"source": results["source"], "weights": results["weights_name"], "winner": winner["solver"],
           "winner_path": winner["path"], "winner_cost": winner["cost"], "optimal_cost": results["optimal_cost"],
           **{f"{k}_cost": v["cost"] for k, v in solvers.items()},
           **{f"{k}_ms": v["time_ms"] for k, v in solvers.items()}, **thesis_res}
    weights_note = "" if results["weights_used"] else " (not used by a ready matrix)"
    notes = [f"Cost matrix: {results['source']}, weights `{results['weights_name']}`{weights_note} "
             f"{results['weights']}. Winner: **{winner['solver']}** `{winner['path']}` (cost {winner['cost']:.4f})."]
    if results["weights_used"]:
        notes.append("Normalised metric sums along each schedule (thesis Table 5.2 layout; lower is better, "
                     "security already inverted):\n\n" + t_metrics)
    notes.append("Thesis instance (eq. 4.1 matrix, Table 5.1 nodes), same solvers:\n\n" + t2)
    sequence = [int(v) for v in winner["path"].split("-")]
    ctx["schedule_sequence"] = sequence
    if planned:
        _experiment("plan").write_plan_json(planned, cfg.plan, planner, sequence, out)
        ctx["plan_json"] = out / "plan.json"
        notes.append(f"`schedule/plan.json`: the winner's moves ({planner} trajectories) with the grasp/release "
                     "steps, in the `uvms_jax.hw.plan` format.")
    return StageReport("schedule", "Schedules: cost matrix → greedy / GRASP / A* / exact (SPEC §5, thesis Tables 5.2, 5.5)",
                       [t1], res, notes)


def stage_hw(cfg: DictConfig, out: Path, ctx: dict) -> StageReport:
    """Dry-run check, then execution of the plan.json on the simulated Bravo 7."""
    hc = cfg.hw
    if hc.plan:
        plan_path = Path(hydra.utils.to_absolute_path(hc.plan))
    else:
        plan_path = ctx.get("plan_json", EXAMPLE_PLAN)
    hw_cfg, sim_cfg = hw.config_from_mapping({"executor": OmegaConf.to_container(hc.executor),
                                              "sim": OmegaConf.to_container(hc.sim)})
    plan = hw.load_plan(plan_path)
    check = hw.check_plan(plan, hw_cfg)  # the dry run: raises PlanError listing every problem
    start = next(s.q[0] for s in plan.segments if s.q)
    runlog = hw.RunLog(tuple(j.name for j in hw.BRAVO7))
    bar = tqdm(total=len(plan.segments), unit="seg", desc="hw", leave=False, disable=None)

    def progress(i: int, n: int, name: str) -> None:
        bar.n = i
        bar.set_description(f"hw {name[:24]}")
        bar.refresh()

    arm = hw.SimArm(sim_cfg, list(start) + [0.0])
    server = None
    t0 = time.perf_counter()
    try:
        if hc.link == "loopback":
            clock = hw.VirtualClock()
            link = hw.SimLink(arm)
            client = hw.Bravo7(hw.LoopbackTransport(link, clock), clock=clock.now,
                               request_timeout=hw_cfg.request_timeout_s)
            sleep = clock.sleep
        elif hc.link == "udp":
            server = hw.SimServer(arm).start()
            link = server.link
            client = hw.Bravo7(hw.UdpTransport(*server.address), request_timeout=hw_cfg.request_timeout_s)
            sleep = time.sleep
        else:
            raise ValueError(f"hw.link must be 'loopback' or 'udp', got {hc.link!r}")
        with client:
            result = hw.Executor(client, hw_cfg, sleep=sleep, log=runlog, progress=progress).run(plan)
    finally:
        bar.close()
        if server is not None:
            server.stop()
    wall = time.perf_counter() - t0
    runlog.write_csv(out / "run.csv")
    if hc.plot and runlog.rows:
        runlog.plot(out / "run.png")
    res = {"ok": result.ok, "reason": result.reason, "gates": len(result.gates),
           "max_gate_error_rad": None if math.isnan(result.max_gate_error_rad) else result.max_gate_error_rad,
           "max_gate_error_mm": None if math.isnan(result.max_gate_error_mm) else result.max_gate_error_mm,
           "grips": result.grips,
           "simulated_s" if hc.link == "loopback" else "duration_s": result.duration_s, "wall_s": wall,
           "ticks": result.ticks, "link_timeouts": result.link_timeouts,
           "limit_violations": arm.limit_violations, "dropped": link.dropped, "corrupted": link.corrupted,
           "plan": str(plan_path), "link": hc.link}
    (out / "result.json").write_text(json.dumps(res, indent=2))
    if not result.ok:
        log.warning("simulated run aborted (arm told to hold): %s", result.reason)
    clock_note = "virtual clock" if hc.link == "loopback" else "real time"
    table = md_table(
        ["plan", "segments", "waypoints", "estimated motion [s]", "result", "gates", "max gate error [rad]",
         "max gate error [mm]", f"run time ({clock_note}) [s]", "wall [s]", "demands outside limits"],
        [[f"`{plan_path.name}`", check.n_segments, check.n_waypoints, check.estimated_s, result.reason,
          len(result.gates), res["max_gate_error_rad"], res["max_gate_error_mm"], result.duration_s, wall,
          arm.limit_violations]])
    notes = [f"Link: {hc.link} ({clock_note}); reached-gate threshold {hw_cfg.gate_threshold_rad} rad "
             "(thesis 4.6: every encoder within the threshold before the next motion). The thesis validated its "
             "real-arm runs with motion capture (~2 mm); `run.csv` logs commanded vs measured states for the same "
             "comparison. Same plan on a real arm: `uvms-hw run PLAN --dry-run`, then `--udp 192.168.2.3:6789`."]
    return StageReport("hw", "Execution on the simulated Bravo 7 (SPEC §6, thesis 4.6)", [table], res, notes)


STAGE_FNS: dict[str, Callable[[DictConfig, Path, dict], StageReport]] = {
    "docking": stage_docking, "surrogate": stage_surrogate, "plan": stage_plan, "schedule": stage_schedule,
    "hw": stage_hw,
}


# -- summary ---------------------------------------------------------------------------------
def write_summary(out: Path, reports: list[StageReport], total_s: float, cfg: DictConfig) -> Path:
    dev = jax.devices()[0]
    lines = ["# uvms_jax pipeline run", "",
             f"{time.strftime('%Y-%m-%d %H:%M:%S')} · {platform.machine()}, {os.cpu_count()} CPUs, "
             f"device {dev.platform} ({dev.device_kind}) · Python {platform.python_version()}, jax {jax.__version__} · "
             f"load average {', '.join(f'{v:.1f}' for v in os.getloadavg())} · total wall time **{total_s:.1f} s**", "",
             "## Stage times", "",
             md_table(["stage", "folder", "wall [s]", "CPU [s]"],
                      [[r.title.split(" (")[0], f"[{r.name}/]({r.name}/)", r.seconds, r.cpu_seconds] for r in reports]
                      + [["total", "", total_s, sum(r.cpu_seconds for r in reports)]]), "",
             "Wall times include JAX/XLA compilation. CPU = process CPU time over all threads; on a busy "
             "machine wall time exceeds it by the share other jobs take.", ""]
    for r in reports:
        lines += [f"## {r.title}", ""]
        for t in r.tables:
            lines += [t, ""]
        for n in r.notes:
            lines += [n, ""]
        pngs = sorted((out / r.name).rglob("*.png"))
        if pngs:
            lines += ["Figures: " + " · ".join(f"[{p.relative_to(out)}]({p.relative_to(out)})" for p in pngs), ""]
            lines += [f"![{p.stem}]({p.relative_to(out)})" for p in pngs[:4]] + [""]
    lines += ["## Config", "", "```yaml", OmegaConf.to_yaml(cfg).rstrip(), "```", ""]
    path = out / "summary.md"
    path.write_text("\n".join(lines))
    return path


def run_pipeline(cfg: DictConfig, out: Path) -> dict:
    """Run the configured stages into ``out``; returns results.json's dict."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    unknown = [s for s in cfg.stages if s not in STAGE_FNS]
    if unknown:
        raise ValueError(f"unknown stages {unknown}; choose from {list(STAGE_FNS)}")
    order = [s for s in STAGES if s in cfg.stages]  # data flow order, whatever the list order
    log.info("pipeline stages %s into %s; devices %s", order, out, jax.devices())
    ctx: dict = {}
    reports = []
    t_start = time.perf_counter()
    for name in tqdm(order, desc="pipeline", unit="stage", disable=None):
        stage_out = out / name
        stage_out.mkdir(parents=True, exist_ok=True)
        log.info("== stage %s", name)
        t0, c0 = time.perf_counter(), time.process_time()
        rep = STAGE_FNS[name](cfg, stage_out, ctx)
        rep.seconds, rep.cpu_seconds = time.perf_counter() - t0, time.process_time() - c0
        reports.append(rep)
        log.info("== stage %s done in %.1f s: %s", name, rep.seconds, rep.results)
    total = time.perf_counter() - t_start
    results = {"total_seconds": total, "stage_seconds": {r.name: r.seconds for r in reports},
               "stage_cpu_seconds": {r.name: r.cpu_seconds for r in reports},
               **{r.name: r.results for r in reports}}
    (out / "results.json").write_text(json.dumps(results, indent=1, default=str))
    summary = write_summary(out, reports, total, cfg)
    log.info("pipeline done in %.1f s; summary: %s", total, summary)
    return results


@hydra.main(version_base="1.3", config_path="../configs", config_name="pipeline")
def main(cfg: DictConfig) -> dict:
    return run_pipeline(cfg, Path(HydraConfig.get().runtime.output_dir))


if __name__ == "__main__":
    main()
