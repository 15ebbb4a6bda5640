"""The five stages of the end-to-end run, each a call of its package's stage function and
writer, and the part of ``summary.md`` it contributes (tables of ours beside the papers')."""

from __future__ import annotations

import dataclasses
import logging
import math
from pathlib import Path

import jax
import numpy as np

from uvms_jax import bravo7, evo, hw, kin, planfile, progress, sched, surrogate
from uvms_jax import plan as planning
from uvms_jax.pipeline._report import StageReport, md_table
from uvms_jax.pipeline._settings import PipelineSettings

log = logging.getLogger(__name__)

# Thesis Table 5.5: solver times on the eq. 4.1 matrix [ms] (docs/theory.md §5).
THESIS_SOLVER_MS = {"greedy": 0.0121, "grasp": 110.2, "astar": 0.9435, "exact": None}
# Docking paper Table 3 (docs/theory.md §3): best pose and the M_a range of its seven GA runs.
PAPER_DOCKING = {"pose": (-0.32, -0.36, 0.24, 0.79), "Ma": (0.134, 0.181)}
# hw/run.mp4: the ~92 s demo run → ~730 frames, 22–25 s of software (Mesa) rendering on 2 cores.
VIDEO_FPS = 8.0
VIDEO_SIZE = (480, 360)  # width, height [pixels]


@dataclasses.dataclass
class Flow:
    """What a stage hands to the later ones, in memory."""

    task_plan: planning.TaskGraphPlan | None = None
    plan: planfile.Plan | None = None
    plan_source: str = ""


def _pose(p) -> list[float]:
    return [round(float(v), 3) + 0.0 for v in p]


def docking(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Docking GA (+ grid reference) and the w_max maps of the best and the ill-placed pose."""
    run = evo.run_docking(s.docking)
    evo.write_docking(run, out)
    rows = [[i + 1, *_pose(p), float(f), float(m), int(g)]
            for i, (p, f, m, g) in enumerate(zip(run.poses, run.fitness, run.M_a, run.generations))]
    pp = PAPER_DOCKING
    rows.append(["paper Table 3", *pp["pose"], None, f"{pp['Ma'][0]}–{pp['Ma'][1]}", "≤ 500"])
    rows.append(["grid optimum", *_pose(run.grid.pose), run.grid.fitness, run.grid.M_a,
                 f"{run.grid.candidates} candidates"])
    t1 = md_table(["GA run", "x [m]", "y [m]", "z [m]", "ψ [rad]", "fitness (eq. 15)", "M_a (eq. 1)", "generations"], rows)
    t2 = md_table(["pose", "x, y, z, ψ", "zero-w area of the task area", "mean w_max", "paper"],
                  [[name, ", ".join(f"{v:.3f}" for v in m.pose), f"{100 * m.map.zero_fraction:.1f} %", m.w_max_mean, paper]
                   for name, m, paper in (("best GA pose", run.wmax_best, "Fig. 9: w_max stays high"),
                                          ("ill-placed (paper)", run.wmax_ill_placed, "Fig. 10: large zero-w region"))])
    ratio = run.ga_ratio_to_grid
    res = {"ga_best_fitness": float(run.fitness.max()), "ga_ratio_to_grid_min": float(ratio.min()),
           "ga_batch_seconds": run.ga_batch_seconds, "grid_fitness": run.grid.fitness,
           "zero_w_best": run.wmax_best.map.zero_fraction, "zero_w_ill_placed": run.wmax_ill_placed.map.zero_fraction,
           "all_face_task_area": run.all_face_task_area}
    notes = [f"{len(run.fitness)} GA runs in one jitted batch: {run.ga_batch_seconds:.2f} s after compilation "
             f"(compile + first batch {run.ga_compile_seconds:.1f} s); GA / grid optimum {ratio.min():.3f}–{ratio.max():.3f}.",
             "Absolute M_a differs from the paper's (its frames are not fully given; docs/theory.md §1.1): compare the "
             "placement (near quarter, facing the task area) and the w_max maps."]
    return StageReport("docking", "Docking GA and w_max maps (docs/theory.md §3, docking paper Table 3, Figs 9–10)",
                       [t1, t2], res, notes)


def surrogates(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """FFBN/RBFN surrogates of the 12-DOF UVMS's indices, timed against the analytic index."""
    run = surrogate.run_surrogates(jax.random.key(s.surrogate.seed), kin.uvms12(), s.surrogate)
    surrogate.write_surrogates(run, out)
    rows, res = [], {}
    for name, n in run.networks.items():
        p, timing = n["paper"], n.get("timing", {})
        t, t5 = timing.get("1000", {}), timing.get("100000", {})
        units = n["hidden_units"] if n["kind"] == "ffbn" else f"{n['hidden_units']} (spread {n['spread']:.3g})"
        rows.append([name, units, p.get("hidden_units", f"spread {p.get('spread')}"),
                     f"{100 * n['max_rel_test_error']:.2f} %", n["operation_count"], p["operation_count"],
                     t.get("network_s", math.nan) * 1e3, p["seconds_1000"] * 1e3, t.get("speedup"), t5.get("speedup")])
        res[f"{name}_max_rel_error"] = n["max_rel_test_error"]
        res[f"{name}_units"] = n["hidden_units"]
        if t5:
            res[f"{name}_speedup_1e5"] = t5["speedup"]
    for index, a in run.analytic.items():
        t = a["timing"].get("1000", {})
        rows.append([f"analytic {index}", "—", "—", "—", a["xla_flops_per_sample"], a["paper"]["operation_count"],
                     t.get("seconds", math.nan) * 1e3, a["paper"]["seconds_1000"] * 1e3, None, None])
    table = md_table(["network", "units (ours)", "units (paper)", "max rel. test error (eq. 21)", "ops (ours)",
                      "ops (paper Table 4)", "1000 inputs [ms] (ours)", "1000 inputs [ms] (paper Table 5)",
                      "speed-up at 1e3", "speed-up at 1e5"], rows)
    notes = ["Ours: float32, jitted, compilation excluded, this machine; paper: Matlab on an i7-3930K. "
             "Analytic ops (ours) are XLA flops per sample.",
             "Acceptance figures: " + ", ".join(f"{k} = {v:.3g}" if isinstance(v, float) else f"{k} = {v}"
                                                for k, v in run.acceptance.items())]
    return StageReport("surrogate", "Surrogates of w and KCI (docs/theory.md §4, dexterity paper Tables 4–5)",
                       [table], res, notes)


def plan(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """IK targets and OMPL plans of every task-graph edge; kept in memory for the schedule."""
    scene = planning.build_scene(s.scenario)
    task_plan = planning.plan_task_graph(jax.random.key(s.plan.seed), scene, s.plan)
    planning.write_task_graph(task_plan, out)
    flow.task_plan = task_plan
    rows, res = [], {"ik_seconds": task_plan.ik_seconds}
    for planner, p in task_plan.summary.items():
        rows.append([planner, f"{p.success}/{p.edges}", f"{p.revalidated}/{p.edges}", 1e3 * p.median_planning_time_s,
                     1e3 * p.mean_planning_time_s, 1e3 * p.max_planning_time_s])
        res[f"{planner}_success"] = p.success
        res[f"{planner}_median_ms"] = 1e3 * p.median_planning_time_s
    table = md_table(["planner", "planned", "re-checked OK", "median [ms]", "mean [ms]", "max [ms]"], rows)
    n_edges = len(next(iter(task_plan.by_planner.values()), ()))
    pc = s.plan
    notes = [f"{n_edges} task-graph edges (thesis Table 5.1 / eq. 4.1 structure), budget {pc.budget_s} s per edge; "
             f"IK targets {task_plan.ik_seconds:.1f} s (mostly XLA compilation). Every path re-checked at "
             f"{pc.recheck_resolution} rad with margin 0 and time-parameterised ({pc.max_velocity} rad/s). "
             "The thesis publishes no per-edge planning times; BENCHMARKS.md has a 5 s-budget run of all three planners."]
    return StageReport("plan", "Bravo 7 planning of the thesis cage (docs/theory.md §5, thesis ch. 5.1)", [table], res, notes)


def schedule(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Cost matrix (the planning stage's metrics, else the configured source) → every solver;
    the thesis's eq. 4.1 instance beside its published times; the winner's plan."""
    key = jax.random.key(s.seed)
    task_plan = flow.task_plan
    planner = s.sched_planner or s.plan.planners[0]
    raw = task_plan.metrics[planner] if task_plan is not None else None
    run = sched.run_schedule(key, s.sched, raw, note=f"planning stage metrics ({planner})")
    results = sched.write_schedule(run, out, plots=s.sched.plots)
    winner = run.best
    t1 = md_table(["solver", "schedule", "cost", "time [ms] (ours)", "thesis Table 5.5 [ms] (eq. 4.1 matrix)"],
                  [[r.solver, r.path_str(), r.cost, r.wall_time_s * 1e3, THESIS_SOLVER_MS.get(r.solver)]
                   for r in run.solved.values()])
    thesis = sched.solve_all(key, sched.thesis_problem(), s.sched)
    thesis_path = "-".join(map(str, sched.THESIS_EQ41_GREEDY_PATH))
    t2 = md_table(["solver", "schedule (ours)", "cost", "thesis schedule", "time [ms] (ours)", "thesis [ms]"],
                  [[n, r.path_str(), r.cost, thesis_path if n == "greedy" else None, r.wall_time_s * 1e3,
                    THESIS_SOLVER_MS.get(n)] for n, r in thesis.items()])
    res = {"source": run.note, "weights": run.weights.name, "winner": winner.solver, "winner_path": winner.path_str(),
           "winner_cost": winner.cost, "optimal_cost": run.optimal_cost,
           **{f"{n}_cost": r.cost for n, r in run.solved.items()},
           **{f"{n}_ms": r.wall_time_s * 1e3 for n, r in run.solved.items()},
           **{f"thesis_{n}_cost": r.cost for n, r in thesis.items()},
           **{f"thesis_{n}_ms": r.wall_time_s * 1e3 for n, r in thesis.items()}}
    weights_note = "" if run.weights_used else " (not used by a ready matrix)"
    notes = [f"Cost matrix: {run.note}, weights `{run.weights.name}`{weights_note} {results['weights']}. "
             f"Winner: **{winner.solver}** `{winner.path_str()}` (cost {winner.cost:.4f})."]
    if run.weights_used:
        sums = md_table(["solver", *(f"Σ N {m}" for m in sched.METRICS)],
                        [[r["solver"], *(r[f"N_{m}"] for m in sched.METRICS)] for r in run.rows])
        notes.append("Normalised metric sums along each schedule (thesis Table 5.2 layout; lower is better, "
                     "security already inverted):\n\n" + sums)
    notes.append("Thesis instance (eq. 4.1 matrix, Table 5.1 nodes), same solvers:\n\n" + t2)
    if task_plan is not None:
        flow.plan = planning.plan_for_schedule(task_plan, planner, list(winner.path), s.plan)
        flow.plan_source = "schedule/plan.json"
        planning.write_plan(flow.plan, out)
        notes.append(f"`schedule/plan.json`: the winner's moves ({planner} trajectories) with the grasp/release "
                     "steps, in the `uvms_jax.planfile` format.")
    return StageReport("schedule", "Schedules: cost matrix → greedy / GRASP / A* / exact (docs/theory.md §5, "
                       "thesis Tables 5.2, 5.5)", [t1], res, notes)


def execute(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Dry-run check, then execution of the scheduled plan (or ``hw.plan``) on the simulated Bravo 7."""
    hs = s.hw
    if hs.plan is not None:
        the_plan, source = planfile.load_plan(hs.plan), hs.plan
    elif flow.plan is not None:
        the_plan, source = flow.plan, flow.plan_source
    else:
        raise ValueError("the hw stage needs a plan: run the plan and schedule stages, or set hw.plan")
    with progress.bar(total=len(the_plan.segments), desc="hw", unit="seg") as bar:
        run = hw.run_plan(the_plan, link=hs.link, config=hs.executor, sim=hs.sim,
                          progress=lambda i, n, name: bar.update(i - bar.n))  # i: segments finished
        if run.ok:
            bar.update(bar.total - bar.n)
    res = hw.write_run(run, out, plot=hs.plot, plan_path=source)
    if not run.ok:
        log.warning("simulated run aborted (arm told to hold): %s", run.result.reason)
    clock = "virtual clock" if hs.link == "loopback" else "real time"
    r, c = run.result, run.check
    table = md_table(
        ["plan", "segments", "waypoints", "estimated motion [s]", "result", "gates", "max gate error [rad]",
         "max gate error [mm]", f"run time ({clock}) [s]", "wall [s]", "demands outside limits"],
        [[f"`{Path(source).name}`", c.n_segments, c.n_waypoints, c.estimated_s, r.reason, len(r.gates),
          res["max_gate_error_rad"], res["max_gate_error_mm"], r.duration_s, run.wall_s, run.sim.limit_violations]])
    notes = [f"Link: {hs.link} ({clock}); reached-gate threshold {hs.executor.gate_threshold_rad} rad "
             "(thesis 4.6: every encoder within the threshold before the next motion). The thesis validated its "
             "real-arm runs with motion capture (~2 mm); `run.csv` logs commanded vs measured states for the same "
             "comparison. Same plan on a real arm: `uvms-hw run PLAN --dry-run`, then `--udp 192.168.2.3:6789`."]
    if hs.plot and run.log.rows:
        notes.append(_run_video(s, flow, run.log, out, res))
    return StageReport("hw", "Execution on the simulated Bravo 7 (docs/theory.md §6, thesis 4.6)", [table], res, notes)


def _measured_arm(run_log: hw.RunLog) -> tuple[np.ndarray, np.ndarray]:
    """Times ``(n,)`` [s] and measured arm angles ``(n, 6)`` G…B [rad] of the log rows whose
    measured arm state is complete (a state that did not arrive is NaN in the log)."""
    names = run_log.joint_names
    n = len(names)
    cols = [4 + n + names.index(j.name) for j in bravo7.ARM_JOINTS]
    rows = np.asarray([[r[0], *(r[c] for c in cols)] for r in run_log.rows], dtype=float)
    rows = rows[np.all(np.isfinite(rows), axis=1)]
    return rows[:, 0], rows[:, 1:]


def _run_video(s: PipelineSettings, flow: Flow, run_log: hw.RunLog, out: Path, res: dict) -> str:
    """``out/run.mp4``: the measured run in the planning stage's scene, else the scenario's
    (the example plan was planned in the thesis cage of ``configs/scenario/thesis_cage.yaml``);
    returns the summary note."""
    if flow.task_plan is not None:
        scene = flow.task_plan.scene
    elif s.scenario:
        scene = planning.build_scene(s.scenario)
    else:
        return "No video of the run: no scene (run the plan stage or give a scenario)."
    t, q = _measured_arm(run_log)
    if len(t) == 0:
        return "No video of the run: no complete measured state was logged."
    try:
        video = planning.render_run_video(scene, t, q, out / "run.mp4", fps=VIDEO_FPS, size=VIDEO_SIZE)
    except RuntimeError as e:  # no offscreen GL context on this machine
        log.warning("no video of the run: %s", e)
        return f"No video of the run: {e}."
    res["video_frames"] = video.frames
    res["video_render_s"] = video.seconds
    link = f"{out.name}/{video.path.name}"
    return (f"Video of the run: [{link}]({link}) — measured joint angles in the MuJoCo scene, {video.fps:g} fps, "
            f"{VIDEO_SIZE[0]}×{VIDEO_SIZE[1]}, {video.frames} frames, rendered offscreen in {video.seconds:.1f} s "
            "(arm only: the jaws' opening and the carried objects are not drawn).")


STAGE_FNS = {"docking": docking, "surrogate": surrogates, "plan": plan, "schedule": schedule, "hw": execute}
