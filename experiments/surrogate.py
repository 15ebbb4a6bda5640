"""Surrogate networks for the dexterity indices w and KCI (docs/theory.md §4; dexterity paper §3–4).

Thin Hydra entry point: configs/surrogate.yaml → ``surrogate.SurrogateSettings`` →
``surrogate.run_surrogates`` → ``surrogate.write_surrogates``. The run builds datasets D1
(θ1…θ11 → KCI) and D2 (θ5…θ11 → w) with the paper's sampling (Fig. 7), runs the FFBN and RBFN
design loops until the maximum relative test error (eq. 21) is below E, and times every network
against the analytic index. Writes into the Hydra run directory:

  results.json                 per network: hidden units, spread, max relative test error,
                              operation counts, design time, time for 1e3 / 1e5 / 1e6 inputs
                              vs the analytic index; acceptance figures
  ffbn_w_design.png, ffbn_kci_design.png   test error vs hidden neurons (Fig. 10/14)
  rbfn_w_design.png, rbfn_kci_design.png   test error and units vs spread (Fig. 8/12)
  training.png                training mse of each selected network (Figs. 9/11/13/15)
  data/  networks/            datasets (npz + json) and networks (npz + json)

  python experiments/surrogate.py                    # paper-sized
  python experiments/surrogate.py surrogate=small    # ~1-2 minute demo
"""

from __future__ import annotations

import logging
from pathlib import Path

import _cli  # the scripts' folder: one-line config errors, --help
import hydra
import jax
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from uvms_jax import kin, surrogate
from uvms_jax.settings import from_mapping

log = logging.getLogger(__name__)


def settings_from_cfg(cfg: DictConfig) -> surrogate.SurrogateSettings:
    """Typed settings of a composed surrogate config (the config's keys are the settings' fields)."""
    return from_mapping(surrogate.SurrogateSettings, OmegaConf.to_container(cfg, resolve=True))


@hydra.main(version_base="1.3", config_path="../configs", config_name="surrogate")
def main(cfg: DictConfig) -> None:
    with _cli.config_errors():
        settings = settings_from_cfg(cfg)
    # Decided once, before any JAX work: float64 datasets and training need x64.
    if settings.train_dtype == "float64":
        jax.config.update("jax_enable_x64", True)
    out = Path(HydraConfig.get().runtime.output_dir)
    run = surrogate.run_surrogates(jax.random.key(settings.seed), kin.uvms12(), settings)
    log.info("report: %s", surrogate.write_surrogates(run, out))


if __name__ == "__main__":
    _cli.run(main)
