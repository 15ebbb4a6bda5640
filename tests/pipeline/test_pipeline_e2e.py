"""End-to-end runs of experiments/pipeline.py through Hydra's compose API, in a tmp folder."""

from __future__ import annotations

import json
import re

import pytest
from hydra import compose, initialize_config_dir
from hydra.core.hydra_config import HydraConfig

from _pipeline_helpers import CONFIG_DIR

STAGE_FILES = {  # each stage's folder must hold these files
    "docking": ["runs.csv", "grid_optimum.json", "wmax.json", "wmax_best.png", "summary.json"],
    "surrogate": ["report.json"],
    "plan": ["edges.csv", "targets.json", "cost_RRTConnect.csv", "ee_paths_RRTConnect.png"],
    "schedule": ["table.md", "results.json", "plan.json"],
    "hw": ["run.csv", "result.json"],
}


def _run(pipeline, tmp_path, overrides):
    with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
        cfg = compose(config_name="pipeline", overrides=overrides)
        return cfg, pipeline.run_pipeline(cfg, tmp_path)


def _tables_of(summary: str) -> list[str]:
    """Section titles that are followed by a markdown table."""
    sections = re.split(r"^## ", summary, flags=re.M)[1:]
    return [s.splitlines()[0] for s in sections if re.search(r"^\|.*\|$", s, flags=re.M)]


@pytest.mark.parametrize("experiment", ["tiny", "full"])
def test_configs_compose(experiment):
    """The demo config and the presets compose, and the stage configs compose with their overrides."""
    with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
        for overrides in ([], [f"experiment={experiment}"]):
            cfg = compose(config_name="pipeline", overrides=overrides)
            assert list(cfg.stages) == ["docking", "surrogate", "plan", "schedule", "hw"]
            assert cfg.plan.seed == cfg.seed and cfg.sched.weights.name == "equal"
            for name, key in (("docking", "docking"), ("surrogate", "surrogate"), ("schedule", "sched")):
                compose(config_name=name, overrides=list(cfg[key].overrides))
        launcher = compose(config_name="schedule", overrides=["hydra/launcher=slurm"], return_hydra_config=True)
        assert launcher.hydra.launcher._target_.endswith("SlurmLauncher")


def test_stage_output_dir_is_restored(pipeline, tmp_path):
    saved = HydraConfig.instance().cfg
    with pipeline.hydra_output_dir(tmp_path):
        assert HydraConfig.get().runtime.output_dir == str(tmp_path)
    assert HydraConfig.instance().cfg is saved


def test_unknown_stage_is_refused(pipeline, tmp_path):
    with pytest.raises(ValueError, match="unknown stages"):
        _run(pipeline, tmp_path, ["stages=[docking,tidy]"])


def test_pipeline_smoke_schedule_and_hw(pipeline, tmp_path):
    """Scheduling on the thesis matrix, then the shipped thesis plan executed in simulated time."""
    _, res = _run(pipeline, tmp_path, ["experiment=tiny", "stages=[schedule,hw]"])
    summary = (tmp_path / "summary.md").read_text()
    assert "## Stage times" in summary and len(_tables_of(summary)) >= 2
    assert res["schedule"]["thesis_greedy_cost"] == pytest.approx(3.2059)  # thesis eq. 4.1 greedy schedule
    assert res["schedule"]["winner_cost"] == pytest.approx(2.791)
    assert res["hw"]["ok"] and res["hw"]["limit_violations"] == 0 and res["hw"]["max_gate_error_rad"] <= 0.01
    assert json.loads((tmp_path / "results.json").read_text())["stage_seconds"].keys() == {"schedule", "hw"}
    for stage in ("schedule", "hw"):
        for f in STAGE_FILES[stage]:
            if f != "plan.json":  # no planning stage: the thesis example plan is executed
                assert (tmp_path / stage / f).exists(), f


@pytest.mark.slow
def test_pipeline_tiny_end_to_end(pipeline, tmp_path):
    """Every stage, shrunk (experiment=tiny): summary.md with every stage's table, every file."""
    _, res = _run(pipeline, tmp_path, ["experiment=tiny"])
    summary = (tmp_path / "summary.md").read_text()
    titled = _tables_of(summary)
    for words in ("Stage times", "Docking", "Surrogates", "planning", "Schedules", "Execution"):
        assert any(words in t for t in titled), (words, titled)
    for stage, files in STAGE_FILES.items():
        for f in files:
            assert (tmp_path / stage / f).exists(), f"{stage}/{f}"
    for png in tmp_path.rglob("*.png"):  # every PNG is linked
        assert str(png.relative_to(tmp_path)) in summary
    assert res["plan"]["RRTConnect_success"] > 0
    assert res["hw"]["ok"], res["hw"]["reason"]
    assert res["hw"]["plan"].endswith("schedule/plan.json")
