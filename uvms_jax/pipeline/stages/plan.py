"""The planning stage: IK targets and a motion plan of every task-graph edge
(``plan.plan_task_graph``), in the docked scene."""

from __future__ import annotations

from pathlib import Path

import jax

from uvms_jax import plan as planning
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.pipeline.stages._flow import Flow, rounded
from uvms_jax.text import md_table

__all__ = ["run"]


def run(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """IK targets and OMPL plans of every task-graph edge, the arm's base where the docking
    stage put it (else the scenario's mount); kept in memory for the schedule."""
    scene = flow.scene
    if scene is None:
        scene = planning.build_scene(flow.robot, flow.scene_spec if flow.scene_spec is not None else s.scenario)
    task_plan = planning.plan_task_graph(jax.random.key(s.plan.seed), scene, s.plan)
    planning.write_task_graph(task_plan, out)
    flow.task_plan = task_plan
    rows, res = [], {"ik_seconds": task_plan.ik_seconds}
    for planner, p in task_plan.summary.items():
        rows.append([planner, f"{p.success}/{p.edges}", f"{p.revalidated}/{p.edges}", f"{p.shortcuts}/{p.edges}",
                     1e3 * p.median_planning_time_s, 1e3 * p.mean_planning_time_s, 1e3 * p.max_planning_time_s])
        res[f"{planner}_success"] = p.success
        res[f"{planner}_shortcuts"] = p.shortcuts
        res[f"{planner}_median_ms"] = 1e3 * p.median_planning_time_s
    table = md_table(["planner", "planned", "re-checked OK", "straight-segment shortcut", "median [ms]", "mean [ms]",
                      "max [ms]"], rows)
    n_edges = len(next(iter(task_plan.by_planner.values()), ()))
    pc = s.plan
    notes = [f"{n_edges} task-graph edges (thesis Table 5.1 / eq. 4.1 structure), budget {pc.budget_s} s per edge; "
             f"IK targets {task_plan.ik_seconds:.1f} s (mostly XLA compilation). Every path re-checked at "
             f"{pc.recheck_resolution} rad with margin 0 and time-parameterised ({pc.max_velocity} rad/s). "
             + ("The straight joint-space segment replaces the planner's path wherever it is free (`plan.straight_shortcut`"
                ", column \"straight-segment shortcut\"): fast, and the moves the planners need are the others. "
                if pc.straight_shortcut else "Each path is the planner's own, simplified. ")
             + 
             "The thesis publishes no per-edge planning times; BENCHMARKS.md has a 5 s-budget run of all three planners."]
    res["base_xyz"] = rounded(scene.T_world_base[:3, 3])
    res["T_world_base"] = scene.T_world_base.tolist()
    first = min(scene.objects)  # the arm at its first grasp: the picture of the intervention
    if first in task_plan.targets and planning.render_frame(scene, task_plan.targets[first].q_at, out / "scene.png"):
        notes.append("`plan/scene.png`: the arm at its grasp of the first object, in the planning scene.")
    return StageReport("plan", "Planning every pick-and-place move (docs/theory.md §5, thesis ch. 5.1)", [table], res, notes)
