"""The whole pipeline (tiny preset) with other arms than the Bravo 7: real arms' description files
(example-robot-data, offline), one of them turned into MJCF by MuJoCo with every geometry
stripped. Each docks, plans every task-graph edge, schedules, and runs the winner on its
simulated arm with every gate reached."""

from __future__ import annotations

import importlib.metadata
import json
import re
import subprocess
import sys

import mujoco
import pytest
import yaml

from _pipeline_helpers import ROOT

ROBOTS = importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots"
)
EXAMPLE_ARMS = yaml.safe_load((ROOT / "examples" / "arms.yaml").read_text())
# The xArm 7 also as MJCF with no geometry; the joint counts are the oracle of what loads.
ARMS = {"xarm7_mjcf": 7, "z1": 6, "ur5": 6, "panda": 7}
N_EDGES = 34  # the thesis task graph (thesis Table 5.1, eq. 4.1)


def _bare_mjcf(urdf: str, out) -> str:
    """The URDF as MJCF, compiled by MuJoCo with every visual and collision element removed: a
    description with no collision geometry at all."""
    text = re.sub(r"<(visual|collision)>.*?</\1>", "", (ROBOTS / urdf).read_text(), flags=re.S)
    path = out / "arm.xml"
    mujoco.mj_saveLastXML(str(path), mujoco.MjModel.from_xml_string(text))
    assert "<geom" not in path.read_text()
    return str(path)


@pytest.mark.parametrize("arm", list(ARMS))
def test_pipeline_with_another_arm(tmp_path, arm):
    dof = ARMS[arm]
    settings = dict(EXAMPLE_ARMS["arms"][arm.removesuffix("_mjcf")], gripper=EXAMPLE_ARMS["jaws"])
    urdf = settings["description"]
    description = _bare_mjcf(urdf, tmp_path) if arm.endswith("_mjcf") else str(ROBOTS / urdf)
    card = tmp_path / "arm.yaml"
    card.write_text(yaml.safe_dump({**settings, "description": description}))
    run = tmp_path / "run"
    cmd = [sys.executable, "experiments/pipeline.py", f"hydra.run.dir={run}", "experiment=tiny",
           "stages=[docking,plan,schedule,hw]", f"scenario.arm.card={card}", "scenario.start_q=null",
           "plan.ik.select=nearest_start"]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=1200)
    assert done.returncode == 0, done.stderr[-3000:]
    res = json.loads((run / "results.json").read_text())
    assert res["arm"]["dof"] == dof and res["arm"]["source"] == description
    assert res["docking"]["pose_M_a"] > 0  # a pose from which the arm reaches every target
    assert res["plan"]["RRTConnect_success"] == N_EDGES
    plan = json.loads((run / "schedule" / "plan.json").read_text())
    assert plan["arm"]["joint_names"] == res["arm"]["joint_names"] and plan["arm"]["sha256"] == res["arm"]["sha256"]
    hw = res["hw"]
    assert hw["ok"] and hw["reason"] == "completed", hw
    assert hw["sim"]["limit_violations"] == 0 and hw["max_gate_error_rad"] <= 0.01
    trajectory = yaml.safe_load((run / "hw" / "joint_trajectory.yaml").read_text())
    assert trajectory["joint_names"] == [*res["arm"]["joint_names"], "jaws"]
    pairs = json.loads((run / "plan" / "self_collision.json").read_text())
    assert len(pairs["adjacent"]) == dof  # the base and every moving link, each with its parent
