"""The scheduling stage: the planning stage's metrics as a cost matrix, every configured solver
(``sched.run_schedule``), the thesis's eq. 4.1 instance beside its published times, the
winner's plan (``plan.plan_for_schedule``)."""

from __future__ import annotations

from pathlib import Path

import jax

from uvms_jax import plan as planning
from uvms_jax import sched
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.pipeline.stages._flow import Flow
from uvms_jax.text import md_table

__all__ = ["run"]


def run(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Cost matrix (the planning stage's metrics, else the configured source) → every solver;
    the thesis's eq. 4.1 instance beside its published times; the winner's plan."""
    key = jax.random.key(s.seed)
    task_plan = flow.task_plan
    planner = s.sched_planner or s.plan.planners[0]
    raw = task_plan.metrics[planner] if task_plan is not None else None
    compat = planning.compatibility(task_plan.scene) if task_plan is not None else None  # the scene's fits
    sr = sched.run_schedule(key, s.sched, raw, note=f"planning stage metrics ({planner})", compat=compat)
    results = sched.write_schedule(sr, out, plots=s.sched.plots)
    winner = sr.best
    thesis_ms = sched.THESIS_SOLVER_MS
    t1 = md_table(["solver", "schedule", "cost", "time [ms] (ours)", "thesis Table 5.5 [ms] (eq. 4.1 matrix)"],
                  [[sched.SOLVERS[r.solver].label, r.path_str(), r.cost, r.wall_time_s * 1e3, thesis_ms.get(r.solver)]
                   for r in sr.solved.values()])
    thesis = sched.solve_all(key, sched.thesis_problem(), s.sched)
    thesis_path = "-".join(map(str, sched.THESIS_EQ41_GREEDY_PATH))
    t2 = md_table(["solver", "schedule (ours)", "cost", "thesis schedule", "time [ms] (ours)", "thesis [ms]"],
                  [[sched.SOLVERS[n].label, r.path_str(), r.cost, thesis_path if n == "greedy" else None,
                    r.wall_time_s * 1e3, thesis_ms.get(n)] for n, r in thesis.items()])
    res = {"source": sr.note, "weights": sr.weights.name, "winner": winner.solver, "winner_path": winner.path_str(),
           "winner_cost": winner.cost, "optimal_cost": sr.optimal_cost,
           **{f"{n}_cost": r.cost for n, r in sr.solved.items()},
           **{f"{n}_ms": r.wall_time_s * 1e3 for n, r in sr.solved.items()},
           **{f"thesis_{n}_cost": r.cost for n, r in thesis.items()},
           **{f"thesis_{n}_ms": r.wall_time_s * 1e3 for n, r in thesis.items()}}
    weights_note = "" if sr.weights_used else " (not used by a ready matrix)"
    notes = [f"Cost matrix: {sr.note}, weights `{sr.weights.name}`{weights_note} {results['weights']}. "
             f"Winner: **{winner.solver}** `{winner.path_str()}` (cost {winner.cost:.4f})."]
    if sr.weights_used:
        sums = md_table(["solver", *(f"Σ N {m}" for m in sched.METRICS)],
                        [[r["solver"], *(r[f"N_{m}"] for m in sched.METRICS)] for r in sr.rows])
        notes.append("Normalised metric sums along each schedule (thesis Table 5.2 layout; lower is better, "
                     "security already inverted):\n\n" + sums)
    notes.append("Thesis instance (eq. 4.1 matrix, Table 5.1 nodes), same solvers:\n\n" + t2)
    if task_plan is not None:
        flow.plan = planning.plan_for_schedule(task_plan, planner, list(winner.path), s.plan)
        flow.plan_source = "schedule/plan.json"
        planning.write_plan(flow.plan, out)
        notes.append(f"`schedule/plan.json`: the winner's moves ({planner} trajectories) with the grasp/release "
                     "steps, in the `uvms_jax.planfile` format.")
    solvers = " / ".join(sched.SOLVERS[n].label for n in s.sched.solvers)
    return StageReport("schedule", f"Schedules: cost matrix → {solvers} (docs/theory.md §5, thesis Tables 5.2, 5.5)",
                       [t1], res, notes)
