"""Plan every edge of the thesis task graph with RRTConnect, BKPIECE1 and PRM (thesis ch. 5).

Writes into the Hydra run directory: ``targets.json`` (IK targets), ``edges.csv`` (one row per
planner and edge), ``metrics_<planner>.json`` (the five metric matrices), ``cost_<planner>.csv``
(thesis eq. 4.16 cost matrix, NaN = forbidden), ``plan.json`` (the configured schedule, format
of ``uvms_jax.planfile``), ``results.json`` and PNGs (end-effector paths in the scene, joint
curves, rendered frames where offscreen rendering works).

    .venv/bin/python experiments/plan.py plan.planners=[RRTConnect] plan.budget_s=2
    .venv/bin/python experiments/plan.py scenario=cage_obstacles             # another scene preset
    .venv/bin/python experiments/plan.py 'scenario.arm.mount_rpy=[3.1416,0,0.3]'   # the arm's base pose
    .venv/bin/python experiments/plan.py 'plan.planners=[RRTstar]' +plan.planner_params.RRTstar.range=1.0
    .venv/bin/python experiments/plan.py plan.checker=mujoco                  # OMPL's state-by-state checks
"""

from __future__ import annotations

import dataclasses
import logging
import os
from pathlib import Path

import _cli  # the scripts' folder: one-line config errors, --help
import hydra
import jax
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

os.environ.setdefault("MUJOCO_GL", "egl")  # headless offscreen rendering where EGL exists

from uvms_jax import hw  # noqa: E402
from uvms_jax import plan as P  # noqa: E402
from uvms_jax.files import write_json  # noqa: E402
from uvms_jax.settings import from_mapping  # noqa: E402

log = logging.getLogger(__name__)


@hydra.main(version_base="1.3", config_path="../configs", config_name="plan")
def main(cfg: DictConfig) -> dict:
    jax.config.update("jax_enable_x64", True)  # IK in float64
    out = Path(HydraConfig.get().runtime.output_dir)
    with _cli.config_errors():
        settings = from_mapping(P.PlanSettings, OmegaConf.to_container(cfg.plan, resolve=True), "plan")
    scenario = OmegaConf.to_container(cfg.scenario, resolve=True)
    with _cli.config_errors():
        robot = P.scenario_robot(scenario)
    scene = P.build_scene(robot, scenario)
    task_plan = P.plan_task_graph(jax.random.PRNGKey(settings.seed), scene, settings)
    P.write_task_graph(task_plan, out)
    summary = {planner: dataclasses.asdict(s) for planner, s in task_plan.summary.items()}
    jp = settings.plan_json
    if jp.planner in task_plan.by_planner:
        plan = P.plan_for_schedule(task_plan, jp.planner, jp.sequence, settings)
        P.write_plan(plan, out)
        check = hw.check_plan(plan, robot)  # the hardware's dry run: limits, continuity, timing
        summary["plan_json"] = {"segments": check.n_segments, "estimated_s": check.estimated_s}
    summary["frames"] = P.render_frames(scene, task_plan.targets, out) if settings.render else 0
    write_json(out / "results.json", summary)
    log.info("outputs in %s", out)
    return summary


if __name__ == "__main__":
    _cli.run(main)
