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
    python experiments/pipeline.py hydra.run.dir=outputs/mine --overwrite   # rerun into a used folder

A folder that holds an earlier run (results.json, summary.md, or the RUNNING marker of a run that
did not end) is refused (exit 2, one line naming the marker's run and when it started) unless
``--overwrite``; SIGTERM stops a run as Ctrl-C does (partial results marked ``interrupted``,
exit 143; Ctrl-C: 130).

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
from uvms_jax import plan as planning  # noqa: E402
from uvms_jax.files import refuse_used_folder  # noqa: E402
from uvms_jax.pipeline import RETRY, RUN_FILES, PipelineSettings, check_stages, run_pipeline  # noqa: E402
from uvms_jax.settings import SettingsError, check_keys, from_mapping  # noqa: E402

EXAMPLE_PLAN = Path(__file__).resolve().parents[1] / "examples" / "thesis_plan.json"
# The keys of configs/pipeline.yaml (anything else, e.g. a `+foo=1` override, is an error), and
# of its sections that are not settings dataclasses themselves.
KEYS = ("overwrite", "seed", "stages", "reach", "ga", "docking", "docking_fitness", "scenario", "baseline", "plan",
        "sched", "hw", "hover")
SECTION_KEYS = {"docking": ("overrides",), "sched": ("planner", "overrides", "weights")}


def _stage_config(name: str, overrides, **merge) -> dict:
    """``configs/<name>.yaml`` composed with ``overrides``, ``merge`` merged over it, as a dict."""
    cfg = OmegaConf.to_container(hydra.compose(config_name=name, overrides=list(overrides)), resolve=True)
    for key, value in merge.items():
        cfg[key] = {**cfg[key], **value} if isinstance(value, dict) and isinstance(cfg.get(key), dict) else value
    return cfg


def check_scenarios(c: dict) -> None:
    """Check the scenario and the baseline's against the scenario schema
    (:func:`uvms_jax.plan.check_scenario`): every bad key in one message that names the file.

    Raises:
      SettingsError: ``<file>: <key path>: <what is allowed>, got <value>``, for every bad key.
    """
    errors = []
    for key, group in (("scenario", "scenario"), ("baseline", "scenario@baseline")):
        if c.get(key):
            try:
                planning.SceneSpec.from_mapping(c[key], key)
            except SettingsError as e:
                errors.append(f"{_cli.config_file(group)}: {e}")
    if errors:
        raise SettingsError("; ".join(errors))


def check_arm(settings: PipelineSettings) -> None:
    """The scenario's arm loads (quietly: the run loads it again and logs what it found; call
    inside a Hydra context). The baseline takes the same arm and start (its start_q is not read:
    :func:`uvms_jax.pipeline.baseline_scenario`).

    Raises:
      SettingsError: ``<file>: <key path>: <what is wrong>``.
    """
    try:
        with _cli.quiet("uvms_jax.robot"):
            planning.scenario_robot(settings.scenario)
    except SettingsError as e:
        raise SettingsError(f"{_cli.config_file('scenario')}: {e}") from None


def settings_of(cfg: DictConfig) -> PipelineSettings:
    """Typed settings of the composed pipeline config (call inside a Hydra context): every
    stage's settings are checked here, before any stage runs, whichever stages run.

    Raises:
      SettingsError: an unknown key, or values out of range (every one, named by its key path
        as this config writes it, e.g. ``ga.mutation_rate``); a scenario's bad keys
        (:func:`check_scenarios`) come alone, the other sections are checked once they pass.
    """
    c = OmegaConf.to_container(cfg, resolve=True)
    check_keys(c, KEYS)
    check_scenarios(c)
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
        if not isinstance(cfg.overwrite, bool):
            raise SettingsError(f"overwrite: expected true/false, got {cfg.overwrite!r}")
        settings = settings_of(cfg)
        if "schedule" in settings.stages:
            _cli.reject_unused_weights(settings.sched.source.kind)
        if settings.scenario:
            check_arm(settings)
        checked = check_stages(settings)  # what each stage needs of the arm, before the first one
        out = Path(HydraConfig.get().runtime.output_dir)
        if not cfg.overwrite:  # a multirun's job folder (a run's: the callback checked it already)
            refuse_used_folder(out, RUN_FILES, RETRY)
    return run_pipeline(settings, out, OmegaConf.to_yaml(cfg), checked, overwrite=cfg.overwrite)


if __name__ == "__main__":
    _cli.run(main)
