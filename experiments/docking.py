"""Docking-pose optimisation experiment (docs/theory.md §3; docking paper Tables 2–3, Figs 9–10).

A thin entry point: config → :class:`uvms_jax.evo.DockingSettings` → :func:`uvms_jax.evo.run_docking`
→ :func:`uvms_jax.evo.write_docking`. Writes into the Hydra run directory:
  runs.csv            one row per GA run: x, y, z, psi, fitness, Ma, generations, seconds
  grid_optimum.json   grid-search reference: pose, fitness, Ma, candidates, seconds (+ zoom stages)
  cmaes.json          CMA-ES (evosax) runs
  wmax.json           zero-w area fraction of the task area for the best pose
  wmax_best.png       its w_max heat map (eq. 16); the paper's ill-placed pose (Fig. 10) beside
                      it is drawn by `make papers` (uvms_jax.papers.docking)
  convergence.png     best fitness per generation of every GA and CMA-ES run
  results.json        acceptance figures (GA vs grid, batch time, evaluations/s, quarter/facing checks)
                      and the certificate: the chosen pose, and the GA's best against the dense
                      grid + zoom reference (ga_certified; a multistart search certifies nothing)
For an arm scene (docking/preset=bravo7, bravo7_tables) best_pose.json (IK solution and w per
target) and docked_top_view.png replace the w_max files.

  python experiments/docking.py                              # full (the paper's arm)
  python experiments/docking.py docking/preset=fast          # ~1 minute demo
  python experiments/docking.py docking/preset=bravo7        # Bravo 7 beside a panel (GPU)
  python experiments/docking.py docking/preset=bravo7_fast   # the same at test size
  python experiments/docking.py docking/preset=bravo7_tables # above the thesis's tables (GPU)
"""

from __future__ import annotations

import logging
from pathlib import Path

import _cli  # the scripts' folder: one-line config errors, --help
import hydra
import jax
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from uvms_jax import evo, plan
from uvms_jax.settings import from_mapping

log = logging.getLogger(__name__)


@hydra.main(version_base="1.3", config_path="../configs", config_name="docking")
def main(cfg: DictConfig) -> dict:
    out = Path(HydraConfig.get().runtime.output_dir)
    c = OmegaConf.to_container(cfg, resolve=True)
    scenario = c.pop("scenario", None)  # a pick-and-place scenario: its grasp and place poses are the task
    with _cli.config_errors():
        settings = from_mapping(evo.DockingSettings, c)
        # The arm of the docking scene, in the scenario's scene (its mount replaced by the vehicle's).
        robot = evo.scene_robot(settings.scene) if scenario else None
        task = plan.docking_task(plan.build_scene(robot, scenario), vehicle=settings.scene) if scenario else None
    if settings.dtype == "float64":
        jax.config.update("jax_enable_x64", True)
    run = evo.run_docking(settings, task, robot)
    summary = evo.write_docking(run, out)
    log.info("GA/grid ratios %s (refined grid: %s); %.0f GA evaluations/s; outputs in %s",
             summary["ga_ratio_to_grid"], summary["ga_ratio_to_refined_grid"], summary["ga_evaluations_per_s"], out)
    if run.wmax_best is not None:
        log.info("zero-w best %.3f", run.wmax_best.map.zero_fraction)
    return summary


if __name__ == "__main__":
    _cli.run(main)
