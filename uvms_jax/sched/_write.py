"""Files of a scheduling run: table.md, table.csv, grasp_sweep.csv, schedule_edges.json,
results.json, and the figures grasp_iterations.png and route.png."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import jax

from uvms_jax.files import write_atomic, write_csv, write_json
from uvms_jax.sched._costs import METRICS
from uvms_jax.sched._edges import schedule_edges
from uvms_jax.sched._plots import plot_route, plot_sweep
from uvms_jax.sched._stage import ScheduleRun


def schedule_results(run: ScheduleRun) -> dict:
    """The contents of ``results.json``: source, weights, per-solver table rows, GRASP sweep."""
    return {
        "source": run.note,
        "weights_name": run.weights.name,
        "weights": dict(zip(METRICS, run.weights.values())),
        "weights_used": run.weights_used,
        "optimal_cost": run.optimal_cost,
        "solvers": {r["solver"]: r for r in run.rows},
        "grasp_sweep": [dataclasses.asdict(p) for p in run.sweep],
        "jax": jax.__version__,
    }


def write_schedule(run: ScheduleRun, out: Path, plots: bool = True) -> dict:
    """Writes the run's files into ``out`` (created if missing); returns ``schedule_results``.

    ``grasp_sweep.csv`` and ``grasp_iterations.png`` only when the run has a sweep; the
    figures only with ``plots``.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _write_table(out, run.rows, run.note)
    sweep = [dataclasses.asdict(p) for p in run.sweep]
    if sweep:
        write_csv(out / "grasp_sweep.csv", sweep)
    edges = [e._asdict() for e in schedule_edges(run.problem, run.best.path)]
    write_json(out / "schedule_edges.json", edges)
    results = schedule_results(run)
    write_json(out / "results.json", results)
    if plots:
        if run.sweep:
            plot_sweep(out, run.sweep, run.solved)
        plot_route(out, run.problem, run.best, run.solved.get("greedy"))
    return results


def _write_table(out: Path, rows, note: str) -> None:
    """table.csv (one row per solver) and table.md (thesis Table 5.2 layout)."""
    write_csv(out / "table.csv", rows)
    lines = [f"Source: {note}", "", "| solver | path | metric | K | N_metric | C_final | time [ms] |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        for i, m in enumerate(METRICS):
            n = r[f"N_{m}"]
            head = (r["solver"], r["path"]) if i == 0 else ("", "")
            tail = (f"{r['cost']:.4f}", f"{r['time_ms']:.4f}") if i == 0 else ("", "")
            n_txt = "—" if math.isnan(n) else f"{n:.3f}"
            lines.append(f"| {head[0]} | {head[1]} | {m} | {r[f'K_{m}']:.3g} | {n_txt} | {tail[0]} | {tail[1]} |")
    write_atomic(out / "table.md", "\n".join(lines) + "\n")
