"""End-to-end pipeline: what ``make demo`` runs (docs/design.md "Data flow").

One intervention with one Reach Bravo 7 under a vehicle above the thesis's tables. Stages,
each in its own folder of the Hydra run directory (``uvms_jax.pipeline``):

  surrogate/  the arm's dexterity map on its vehicle, learned from analytic scores (docs/docking.md)
  docking/    the vehicle pose by the GA (analytic, and on the map), grid reference (docs/docking.md)
  plan/       IK targets and OMPL plans of every task-graph edge, the arm's base at the docked pose
  schedule/   the planning metrics' cost matrix → greedy, GRASP, A*, exact; the winner's plan.json
  hw/         the winner's plan checked (dry run) and executed on the simulated Bravo 7
  baseline/   plan, schedule and run again with the thesis's fixed cage-top mount; compared

and ``summary.md`` (the chain at a glance, every stage's tables, links to every PNG) and
``results.json`` (key figures, for ``experiments/gather.py``) in the run directory.

    python experiments/pipeline.py                      # the demo (< 10 min on 2 CPU cores)
    python experiments/pipeline.py experiment=tiny      # smoke run
    python experiments/pipeline.py 'stages=[schedule,hw]' hw.plan=examples/thesis_plan.json

The docking and schedule stages take their experiment's own config (``configs/<name>.yaml``)
composed with ``<stage>.overrides``; ``ga``, ``seed`` and ``sched.weights`` of this config are
merged over them.
"""

from __future__ import annotations

import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import _cli  # noqa: E402  # the scripts' folder: one-line config errors, --help
import hydra  # noqa: E402
import jax  # noqa: E402
from hydra.core.hydra_config import HydraConfig  # noqa: E402
from omegaconf import DictConfig, OmegaConf  # noqa: E402

from uvms_jax import evo  # noqa: E402
from uvms_jax.pipeline import PipelineSettings, check_stages, run_pipeline  # noqa: E402
from uvms_jax.settings import SettingsError, check_keys, from_mapping  # noqa: E402

EXAMPLE_PLAN = Path(__file__).resolve().parents[1] / "examples" / "thesis_plan.json"
# The keys of configs/pipeline.yaml (anything else, e.g. a `+foo=1` override, is an error), and
# of its sections that are not settings dataclasses themselves.
KEYS = ("seed", "stages", "reach", "ga", "docking", "docking_fitness", "scenario", "baseline", "plan", "sched", "hw",
        "hover")
SECTION_KEYS = {"docking": ("overrides",), "sched": ("planner", "overrides", "weights")}


def _stage_config(name: str, overrides, **merge) -> dict:
    """``configs/<name>.yaml`` composed with ``overrides``, ``merge`` merged over it, as a dict."""
    cfg = OmegaConf.to_container(hydra.compose(config_name=name, overrides=list(overrides)), resolve=True)
    for key, value in merge.items():
        cfg[key] = {**cfg[key], **value} if isinstance(value, dict) and isinstance(cfg.get(key), dict) else value
    return cfg


def settings_of(cfg: DictConfig) -> PipelineSettings:
    """Typed settings of the composed pipeline config (call inside a Hydra context): every
    stage's settings are checked here, before any stage runs, whichever stages run.

    Raises:
      SettingsError: an unknown key, or values out of range (every one, named by its key path
        as this config writes it, e.g. ``ga.mutation_rate``).
    """
    c = OmegaConf.to_container(cfg, resolve=True)
    check_keys(c, KEYS)
    for section, keys in SECTION_KEYS.items():
        check_keys(c[section], keys, section)
    stages = c["stages"]
    sched_overrides = list(c["sched"]["overrides"])
    if "plan" in stages:  # the planning stage's metrics become the cost matrix (the compat: its scene's)
        sched_overrides = ["sched/source=edges_csv", "sched.source.path=null", *sched_overrides]
    schedule = _stage_config("schedule", sched_overrides, seed=c["seed"])["sched"]
    schedule["weights"] = c["sched"]["weights"]
    hw_stage = dict(c["hw"])
    if hw_stage["plan"] is not None:
        hw_stage["plan"] = hydra.utils.to_absolute_path(hw_stage["plan"])
    elif "plan" not in stages:
        hw_stage["plan"] = str(EXAMPLE_PLAN)
    docking = _stage_config("docking", c["docking"]["overrides"], ga=c["ga"], seed=c["seed"])
    docking.pop("scenario", None)  # the pipeline's own scenario is the task
    errors = []
    try:  # this config's own `ga` section, named as it writes it (not docking.ga)
        docking["ga"] = from_mapping(evo.GASettings, docking["ga"], "ga")
    except SettingsError as e:
        errors.append(str(e))
        docking["ga"] = evo.GASettings()  # the other sections are still checked
    try:
        settings = from_mapping(PipelineSettings, {
            "seed": c["seed"], "stages": stages, "reach": c["reach"], "docking": docking,
            "docking_fitness": c["docking_fitness"], "scenario": c["scenario"], "baseline": c.get("baseline"),
            "plan": c["plan"], "sched": schedule, "sched_planner": c["sched"]["planner"], "hw": hw_stage,
            "hover": c["hover"]})
    except SettingsError as e:
        errors.append(str(e))
    if errors:
        raise SettingsError("; ".join(errors))
    return settings


@hydra.main(version_base="1.3", config_path="../configs", config_name="pipeline")
def main(cfg: DictConfig) -> dict:
    # Decided once, before any JAX work: IK (planning) and the surrogates' training run in
    # float64; the docking GA and all timings ask for float32 explicitly.
    jax.config.update("jax_enable_x64", True)
    with _cli.config_errors():
        settings = settings_of(cfg)
        if "schedule" in settings.stages:
            _cli.reject_unused_weights(settings.sched.source.kind)
        checked = check_stages(settings)  # what each stage needs of the arm, before the first one
    return run_pipeline(settings, Path(HydraConfig.get().runtime.output_dir), OmegaConf.to_yaml(cfg), checked)


if __name__ == "__main__":
    _cli.run(main)
