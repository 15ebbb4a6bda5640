"""Pick-and-place scheduling experiment (docs/theory.md §5; thesis Tables 5.2–5.9, A.1–A.5, Figs 5.9–5.12).

Writes into the Hydra run directory:
  table.md, table.csv     Table-5.2-like: solver, path, cost, per-metric normalised sums, time
  results.json            source, weights, per-solver path/cost/time, GRASP sweep (for gathering)
  grasp_sweep.csv         GRASP cost and time versus iterations
  grasp_iterations.png    cost and time versus iterations, with greedy / A* / exact lines
  route.png               the best schedule drawn over the nodes
  schedule_edges.json     the moves of the best schedule (src, dst, action, object)

  python experiments/schedule.py
  python experiments/schedule.py sched/source=synthetic sched/weights=security
  python experiments/schedule.py --multirun sched/source=synthetic sched/weights=equal,speed,security
"""

from __future__ import annotations

import logging
from pathlib import Path

import _cli  # the scripts' folder: one-line config errors, --help
import hydra
import jax
from hydra.core.hydra_config import HydraConfig
from hydra.utils import get_original_cwd
from omegaconf import DictConfig, OmegaConf

from uvms_jax import sched
from uvms_jax.settings import from_mapping

log = logging.getLogger(__name__)


def settings(cfg: DictConfig) -> sched.SchedSettings:
    """The typed settings of the config's ``sched`` section (a missing ``???`` raises)."""
    return from_mapping(sched.SchedSettings, OmegaConf.to_container(cfg.sched, resolve=True, throw_on_missing=True),
                        "sched")


@hydra.main(version_base="1.3", config_path="../configs", config_name="schedule")
def main(cfg: DictConfig) -> None:
    with _cli.config_errors():
        s = settings(cfg)
        _cli.reject_unused_weights(s.source.kind)
    out = Path(HydraConfig.get().runtime.output_dir)
    run = sched.run_schedule(jax.random.key(cfg.seed), s, root=Path(get_original_cwd()))
    sched.write_schedule(run, out, plots=s.plots)
    log.info("results in %s", out)


if __name__ == "__main__":
    _cli.run(main)
