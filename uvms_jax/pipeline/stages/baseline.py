"""The baseline stage: the same task with the thesis's fixed cage-top mount, planned, scheduled
and run again by the plan, schedule and hw stages, beside the docked arm."""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path

import numpy as np

from uvms_jax import evo, sched
from uvms_jax import plan as planning
from uvms_jax.pipeline._precheck import baseline_scenario
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.pipeline.stages import execute, plan, schedule
from uvms_jax.pipeline.stages._flow import Flow
from uvms_jax.text import md_table

__all__ = ["TITLE", "run"]

log = logging.getLogger(__name__)

TITLE = "Baseline: the thesis's fixed mount against the docked arm"


def _skipped(why: str) -> StageReport:
    return StageReport("baseline", TITLE, [], {"skipped": why}, [f"Skipped: {why}."])


def run(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """The same task with the thesis's fixed cage-top mount (``baseline``), the run's arm and
    start (:func:`~uvms_jax.pipeline.baseline_scenario`): plan, schedule and run again, and
    compare with the docked arm. Skipped, with the reason in ``results["skipped"]``, where the
    arm cannot do the task from there (found before the first stage, or no valid IK target)."""
    if s.baseline is None:
        raise ValueError("the baseline stage needs a baseline scenario (`baseline.scenario`)")
    if flow.baseline_skipped is not None:
        return _skipped(flow.baseline_skipped)
    fixed = Flow(robot=flow.robot, scene_spec=planning.SceneSpec.from_mapping(baseline_scenario(s)),
                 scene=flow.baseline_scene)
    quiet = dataclasses.replace(s, hw=dataclasses.replace(s.hw, plot=False))
    stages = {}
    for name, fn in (("plan", plan.run), ("schedule", schedule.run), ("hw", execute.run)):
        (out / name).mkdir(parents=True, exist_ok=True)
        try:
            stages[name] = fn(quiet, out / name, fixed).results
        except ValueError as e:  # a node without a valid IK target from the fixed mount
            if name != "plan":
                raise
            why = f"arm {flow.robot.name!r} cannot do the task from the fixed mount: {e}"
            log.warning("baseline stage skipped: %s", why)
            return _skipped(why)
    planner = s.sched_planner or s.plan.planners[0]
    rows, res = [], {}
    for label, f, r in (("docked under the vehicle", flow, {k: v.results for k, v in flow.reports.items()}),
                        ("fixed cage-top mount (thesis)", fixed, stages)):
        if "schedule" not in r or f.task_plan is None:
            continue
        path = [int(v) for v in r["schedule"]["winner_path"].split("-")]
        fig = sched.path_totals(f.task_plan.metrics[planner], path)
        if f is flow:
            M_a = r["docking"]["pose_M_a"] if "docking" in r else None
        elif flow.problem is not None:  # the docking problem's M_a with the base at the fixed mount
            M_a = evo.fixed_base_M_a(flow.problem, f.task_plan.scene.T_world_base)
        else:
            M_a = None
        hw_r = r.get("hw", {})
        rows.append([label, ", ".join(f"{v:.3f}" for v in f.task_plan.scene.T_world_base[:3, 3]), M_a,
                     r["plan"].get(f"{planner}_success"), r["schedule"]["winner_path"], r["schedule"]["winner_cost"],
                     fig["joint_movement_rad"],
                     fig["ee_distance_m"], fig["min_clearance_m"], fig["max_torque_Nm"], hw_r.get("duration_s"),
                     hw_r.get("gates"), hw_r.get("reason")])
        res[label.split()[0]] = {"M_a": M_a, "winner_path": r["schedule"]["winner_path"], **fig,
                                 "executed_s": hw_r.get("duration_s"), "ok": hw_r.get("ok")}
    table = md_table(["arm base", "base xyz [m]", "M_a of the task", "edges planned", "schedule",
                      "cost (own scene's normalisation)", "joint movement [rad]",
                      "tool path [m]", "min clearance [m]", "max torque [N·m]", "executed [s]", "gates", "result"], rows)
    notes = []
    if len(rows) == 2:
        d, b = res["docked"], res["fixed"]
        faster = "docked" if (d["executed_s"] or np.inf) < (b["executed_s"] or np.inf) else "fixed"
        dexterous = "docked" if (d["M_a"] or 0) > (b["M_a"] or 0) else "fixed"
        notes.append(f"The **{faster}** arm finishes the task sooner ({d['executed_s']:.1f} s docked, "
                     f"{b['executed_s']:.1f} s fixed); the **{dexterous}** arm is the more dexterous over the targets "
                     f"(M_a {d['M_a']:.4f} docked, {b['M_a']:.4f} fixed; the fixed mount's M_a is the docking problem's "
                     "with the base there and no hull).")
    notes.append("Sums along each schedule of the raw metrics; the costs are normalised within each scene's own edges "
                 "(thesis eq. 4.16), so they rank schedules of one scene, not the two scenes. The baseline plans in "
                 "the thesis's cage (`configs/scenario/thesis_cage.yaml`) with the run's arm and start "
                 "(`scenario.start_q`; null: one found there).")
    return StageReport("baseline", TITLE, [table], res, notes)
