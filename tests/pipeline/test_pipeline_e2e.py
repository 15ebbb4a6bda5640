"""End-to-end runs of experiments/pipeline.py (the Hydra entry point, in a subprocess) into a tmp
folder, and the pipeline config composed into typed settings."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from hydra import compose, initialize_config_dir

from _pipeline_helpers import CONFIG_DIR, ROOT
from uvms_jax.pipeline import PipelineSettings
from uvms_jax.planfile import load_plan

STAGE_FILES = {  # each stage's folder must hold these files
    "surrogate": ["reach_map.json"],
    "docking": ["runs.csv", "grid_optimum.json", "best_pose.json", "docked_top_view.png", "results.json"],
    "plan": ["edges.csv", "targets.json", "cost_RRTConnect.csv", "ee_paths_RRTConnect.png"],
    "schedule": ["table.md", "results.json", "plan.json"],
    "hw": ["run.csv", "results.json", "joint_trajectory.yaml"],
    "hover": ["hover.png"],
    "baseline": ["plan/edges.csv", "schedule/plan.json", "hw/results.json"],
}


def _run(tmp_path, overrides: list[str]) -> dict:
    """``experiments/pipeline.py`` with ``overrides`` into ``tmp_path``; results.json's dict."""
    cmd = [sys.executable, "experiments/pipeline.py", f"hydra.run.dir={tmp_path}", *overrides]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=1200)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads((tmp_path / "results.json").read_text())


def _tables_of(summary: str) -> list[str]:
    """Section titles that are followed by a markdown table."""
    sections = re.split(r"^## ", summary, flags=re.M)[1:]
    return [s.splitlines()[0] for s in sections if re.search(r"^\|.*\|$", s, flags=re.M)]


@pytest.mark.parametrize("experiment", ["tiny", "full"])
def test_configs_compose(pipeline, experiment):
    """The demo config and the presets compose into typed settings of every stage."""
    with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
        for overrides in ([], [f"experiment={experiment}"]):
            cfg = compose(config_name="pipeline", overrides=overrides)
            settings = pipeline.settings_of(cfg)
            assert settings.stages == ("surrogate", "docking", "plan", "schedule", "hw", "hover", "baseline")
            assert settings.scenario["cage"] is None and settings.baseline["cage"] is not None  # open water; the cage
            assert settings.plan.seed == cfg.seed and settings.sched.weights.name == "equal"
            assert settings.docking.ga.population_size == cfg.ga.population_size
            assert settings.sched.source.kind == "edges_csv"  # the planning stage's metrics
        launcher = compose(config_name="schedule", overrides=["hydra/launcher=slurm"], return_hydra_config=True)
        assert launcher.hydra.launcher._target_.endswith("SlurmLauncher")


def test_unknown_stage_is_refused():
    with pytest.raises(ValueError, match="unknown stages"):
        PipelineSettings(stages=("docking", "tidy"))


def _gates(plan_file) -> int:
    """The gates of a plan: one per waypoint (a segment's first continues the last one's) and one
    per jaws step."""
    plan = load_plan(plan_file)
    return sum(len(seg.q) - (i > 0 and len(seg.q) > 0) + (seg.jaws_mm is not None) for i, seg in enumerate(plan.segments))


def test_pipeline_smoke_schedule_and_hw(tmp_path):
    """Scheduling on the thesis matrix, then the shipped thesis plan executed in simulated time."""
    res = _run(tmp_path, ["experiment=tiny", "stages=[schedule,hw]"])
    summary = (tmp_path / "summary.md").read_text()
    assert "## Stage times" in summary and len(_tables_of(summary)) >= 2
    assert res["schedule"]["thesis_greedy_cost"] == pytest.approx(3.2059)  # thesis eq. 4.1 greedy schedule
    assert res["schedule"]["winner_cost"] == pytest.approx(2.791)
    assert res["hw"]["ok"] and res["hw"]["sim"]["limit_violations"] == 0 and res["hw"]["max_gate_error_rad"] <= 0.01
    assert res["hw"]["gates"] == _gates(ROOT / "examples" / "thesis_plan.json")
    assert res["stage_seconds"].keys() == {"schedule", "hw"}
    for stage in ("schedule", "hw"):
        for f in STAGE_FILES[stage]:
            if f != "plan.json":  # no planning stage: the thesis example plan is executed
                assert (tmp_path / stage / f).exists(), f


@pytest.mark.slow
def test_pipeline_tiny_end_to_end(tmp_path):
    """Every stage, shrunk (experiment=tiny): summary.md with every stage's table, every file."""
    res = _run(tmp_path, ["experiment=tiny"])
    summary = (tmp_path / "summary.md").read_text()
    titled = _tables_of(summary)
    for words in ("Stage times", "Docking", "Surrogate", "Planning", "Schedules", "Execution", "Hovering", "Baseline"):
        assert any(words in t for t in titled), (words, titled)
    for stage, files in STAGE_FILES.items():
        for f in files:
            assert (tmp_path / stage / f).exists(), f"{stage}/{f}"
    for png in tmp_path.rglob("*.png"):  # every PNG is linked
        assert str(png.relative_to(tmp_path)) in summary
    assert "## The intervention at a glance" in summary
    assert res["plan"]["RRTConnect_success"] == 34
    assert res["hw"]["ok"], res["hw"]["reason"]
    assert res["hw"]["gates"] == _gates(tmp_path / "schedule" / "plan.json")  # every gate reached
    assert res["hw"]["sim"]["limit_violations"] == 0
    assert res["hw"]["plan"].endswith("schedule/plan.json")
    # The planning scene's arm base is the docked vehicle's mount, computed here from the pose:
    # T_world_vehicle = (x, y, z, Rz(ψ)), then the scene file's mount (0.35 m ahead, 0.2 m down, hanging).
    x, y, z, psi = res["docking"]["pose"]
    T_world_vehicle = np.eye(4)
    T_world_vehicle[:3, :3] = Rotation.from_euler("z", psi).as_matrix()
    T_world_vehicle[:3, 3] = x, y, z
    mount = np.array([[1.0, 0, 0, 0.35], [0, -1.0, 0, 0], [0, 0, -1.0, -0.2], [0, 0, 0, 1.0]])
    np.testing.assert_allclose(res["plan"]["T_world_base"], T_world_vehicle @ mount, atol=1e-6)
    assert res["docking"]["pose_M_a"] > 0 and res["baseline"]["fixed"]["ok"]
    # Hovering: the hw stage's executor and gates, the vehicle afloat; a current drifts further.
    runs = res["hover"]["runs"]
    still, flowing = runs["still water"], runs["current [0.3, 0.0, 0.0] m/s"]
    for m in (still, flowing):
        assert m["driver"] == "BPL executor" and m["status"] == "completed", m["reason"]
        assert m["gates"] == m["gates_reached"] == res["hw"]["gates"]
    assert flowing["max_drift_m"] > still["max_drift_m"] > 0
    # The whole-body controller between the executor's plan and the arm, over BPL: every gate on
    # the tool within 10 mm; it is the hover entry's main run.
    coordinated = runs["current [0.3, 0.0, 0.0] m/s, whole-body controller"]
    assert coordinated["driver"] == "BPL executor, whole-body controller"
    assert coordinated["status"] == "completed", coordinated["reason"]
    assert coordinated["gates"] == coordinated["gates_tool_within_tolerance"] == res["hw"]["gates"]
    assert max(coordinated["gate_tool_error_m"]) <= 0.01 and res["hover"]["driver"] == coordinated["driver"]
    assert res["hover"]["coordination_removes"]["max_gate_tool_error_m"] > 0.5
