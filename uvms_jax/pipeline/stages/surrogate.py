"""The surrogate stage: the arm's dexterity map on its vehicle (``surrogate.run_reach_map``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from uvms_jax import surrogate
from uvms_jax.files import write_json
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.pipeline.stages._flow import Flow, docking_problem
from uvms_jax.text import md_table

__all__ = ["run"]


def run(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Learn the arm's best manipulability at a tool pose seen from its base on this vehicle
    (the inner part of the docking fitness) from analytic scores of tool poses sampled in the
    base frame (the task and the scene are not used: one map per arm and vehicle)."""
    problem = docking_problem(s, flow)
    reach = surrogate.run_reach_map(problem, s.reach)
    flow.reach = reach
    t, r = reach.test, reach.settings
    k = int(problem.group.shape[0])
    n = reach.n_train + reach.n_test
    res = {"n_train_samples": reach.n_train, "n_test_samples": reach.n_test,
           "analytic_seconds": reach.analytic_seconds, "train_seconds": reach.train_seconds,
           "vehicle_pose_equivalents": n / k, **t}
    write_json(out / "reach_map.json", {**res, "settings": dataclasses.asdict(r)})
    table = md_table(["tool poses (train / test)", "reached", "analytic scoring [s]", "FFBN units", "training [s]",
                      "test RMSE of w", "max error of w", "largest w"],
                     [[f"{reach.n_train} / {reach.n_test}", f"{100 * t['reached_fraction']:.0f} %",
                       reach.analytic_seconds, r.hidden, reach.train_seconds, t["rmse_w"], t["max_abs_error_w"],
                       t["w_range"]]])
    notes = ["The docking fitness spends its time in multi-seed numerical IK; what it keeps per tool pose is the best "
             "w over the valid solutions (reached, within the limits, clear of the vehicle and of the arm itself), a "
             "function of the tool "
             "pose seen from the arm's base alone. An FFBN learns it here from tool poses sampled in the base frame "
             f"(reached positions, approaches within {r.approach_cone_deg:g}° of the downward vertical), each scored by "
             "the docking fitness's own IK: the arm, its mount, the vehicle and the IK settings, not the task or the "
             f"scene, so one map serves every task of this arm on this vehicle (its {n} tool "
             f"poses cost what {res['vehicle_pose_equivalents']:.0f} docking evaluations of this task's {k} tool poses "
             "do). The scene's obstacles are not in the map: the docking stage scores its proposals analytically. "
             "The dexterity paper's surrogates of the 12-DOF UVMS are reproduced apart: `python "
             "experiments/surrogate.py` (docs/reproduction.md)."]
    return StageReport("surrogate", f"Surrogate: the {flow.robot.name}'s dexterity map on its vehicle (docs/docking.md)",
                       [table], res, notes)
