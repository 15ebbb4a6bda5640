"""Files of the planning stage: what :func:`write_task_graph` and :func:`write_plan` put in a folder.

``targets.json``: node → ``q_pre``, ``q_at`` [rad], ``yaw`` [rad], ``manipulability``,
``candidates``, plus ``start`` (the start configuration). ``edges.csv``: one row per planner and
edge (``planner, src, dst, success``, the five metrics, ``revalidated``; the metrics of a failed
edge are empty except its planning time). ``metrics_<planner>.json``: metric → ``(N, N)`` matrix
(null = no edge). ``cost_<planner>.csv``: the ``(N, N)`` cost matrix (NaN = forbidden).
``ee_paths_<planner>.png``; ``plan.json`` (:mod:`uvms_jax.planfile`) and ``joints.png``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from uvms_jax import planfile, sched
from uvms_jax.files import atomic_path, write_csv, write_json
from uvms_jax.plan._plots import plot_ee_paths, plot_plan_joints
from uvms_jax.plan._taskgraph import TaskGraphPlan
from uvms_jax.plan._tasks import EdgeResult

__all__ = ["write_plan", "write_task_graph"]

# The metrics' names in edges.csv and metrics_<planner>.json (sched reads them back).
_FILE_METRICS = sched.EDGE_CSV_COLUMNS


def _edge_row(r: EdgeResult) -> dict:
    values = tuple(r.metrics) if r.metrics is not None else (np.nan,) * len(_FILE_METRICS)
    m = dict(zip(_FILE_METRICS, values))
    m[_FILE_METRICS[0]] = r.plan.planning_time_s  # measured even when planning fails
    return {"planner": r.planner, "src": r.src, "dst": r.dst, "success": r.success, **m, "revalidated": r.revalidated}


def write_task_graph(task_plan: TaskGraphPlan, out: Path) -> None:
    """Write ``targets.json``, ``edges.csv`` and per planner ``metrics_<planner>.json``,
    ``cost_<planner>.csv`` and ``ee_paths_<planner>.png`` into the folder ``out``."""
    out = Path(out)
    scene = task_plan.scene
    write_json(out / "targets.json", {
        str(n): {"q_pre": t.q_pre.tolist(), "q_at": t.q_at.tolist(), "yaw": t.yaw,
                 "manipulability": t.manipulability, "candidates": t.n_candidates}
        for n, t in task_plan.targets.items()} | {"start": scene.start_q.tolist()})
    # The self-collision pairs the checker skips, as computed for this arm (docs/robots.md).
    write_json(out / "self_collision.json", scene.self_collision)
    rows = []
    for planner, results in task_plan.by_planner.items():
        rows += [_edge_row(r) for r in results]
        mats = task_plan.metrics[planner]
        write_json(out / f"metrics_{planner}.json",
                   {k: np.where(np.isnan(v), None, v).tolist() for k, v in zip(_FILE_METRICS, mats)})
        with atomic_path(out / f"cost_{planner}.csv") as tmp:
            np.savetxt(tmp, task_plan.costs[planner], delimiter=",", fmt="%.6g")
        plot_ee_paths(scene, results, out / f"ee_paths_{planner}.png")
    write_csv(out / "edges.csv", rows)


def write_plan(plan: planfile.Plan, out: Path) -> None:
    """Write ``plan.json`` (:func:`uvms_jax.planfile.save_plan`) and its joint plot ``joints.png`` into ``out``."""
    out = Path(out)
    planfile.save_plan(plan, out / "plan.json")
    plot_plan_joints(plan, out / "joints.png")
