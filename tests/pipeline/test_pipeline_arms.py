"""The whole pipeline (tiny preset) with other arms than the Bravo 7: real arms' description files
(example-robot-data, offline), some turned into MJCF by MuJoCo with every geometry stripped
(bare kinematic skeletons), with and without a gripper. Each docks, plans every task-graph edge,
schedules, and runs the winner on its simulated arm with every gate reached; with the default
stages also hovering and the baseline from the thesis's fixed mount.

docs/robots.md's command is run as the page writes it, card included (its ``gripper:`` line
left out), for the Unitree Z1 as a bare MJCF file: the one arm of the fast suite; the other
arms and combinations are slow."""

from __future__ import annotations

import importlib.metadata
import json
import re
import shlex
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
DOC = (ROOT / "docs" / "robots.md").read_text()
N_EDGES = 34  # the thesis task graph (thesis Table 5.1, eq. 4.1)
N_GRIPPER_STEPS = 12  # 4 objects: open and close at each, release at its base (thesis Table 5.1)
# The bare skeletons: the file, its tool frame and the capsule radius (examples/arms.yaml's);
# the joint counts are the oracle of what loads.
BARE = {"z1": ("z1_description/urdf/z1.urdf", "gripperStator", 0.04, 6),
        "xarm7": ("xarm_description/urdf/xarm7.urdf", "link7", 0.04, 7)}
STAGES = ["surrogate", "docking", "plan", "schedule", "hw", "hover", "baseline"]


def _bare_mjcf(urdf: str, out) -> str:
    """The URDF as MJCF, compiled by MuJoCo with every visual and collision element removed: a
    description with no collision geometry at all. Its links stay bodies (MuJoCo would merge
    the fixed ones, tool frames among them, into their parents)."""
    text = re.sub(r"<(visual|collision)>.*?</\1>", "", (ROBOTS / urdf).read_text(), flags=re.S)
    text = re.sub(r"(<robot[^>]*>)", r'\1<mujoco><compiler fusestatic="false"/></mujoco>', text, count=1)
    path = out / "arm.xml"
    mujoco.mj_saveLastXML(str(path), mujoco.MjModel.from_xml_string(text))
    assert "<geom" not in path.read_text()
    return str(path)


def _doc_card() -> dict:
    """docs/robots.md's card (its YAML block), as a mapping."""
    block = re.search(r"```yaml\n(# my_arm\.yaml\n.*?)```", DOC, flags=re.S)
    return yaml.safe_load(block.group(1))


def _doc_command() -> list[str]:
    """docs/robots.md's command that runs an arm card, as words."""
    line = re.search(r"^python experiments/pipeline\.py scenario\.arm\.card=my_arm\.yaml.*$", DOC, flags=re.M)
    return shlex.split(line.group(0))


def _gates(plan: dict) -> int:
    """The reached-gates a plan asks for, counted from plan.json alone: every waypoint (a
    segment's first repeats the previous segment's last, once the arm has started) and every
    gripper step."""
    return sum(len(s.get("q", [])) - (i > 0 and bool(s.get("q"))) + (s["gripper"] is not None)
               for i, s in enumerate(plan["segments"]))


def _run(cmd: list[str], run, card: dict, tmp_path) -> dict:
    """``cmd`` (words of a pipeline command whose card path is ``my_arm.yaml``) with ``card``
    written there, the tiny preset and ``run`` as the run folder; results.json's dict."""
    path = tmp_path / "my_arm.yaml"
    path.write_text(yaml.safe_dump(card))
    cmd = [sys.executable if w == "python" else w.replace("=my_arm.yaml", f"={path}") for w in cmd]
    done = subprocess.run([*cmd, "experiment=tiny", f"hydra.run.dir={run}"], cwd=ROOT, capture_output=True,
                          text=True, timeout=1500)
    assert done.returncode == 0, done.stderr[-3000:]
    assert not (run / "RUNNING").exists()
    return json.loads((run / "results.json").read_text())


def _check_run(res: dict, run, dof: int, gripper: bool, stages=STAGES) -> None:
    """Every stage ran with the card's arm, every edge was planned and every gate reached."""
    assert res["arm"]["dof"] == dof and list(res["stage_seconds"]) == stages
    assert res["docking"]["pose_M_a"] > 0  # a pose from which the arm reaches every target
    assert res["plan"]["RRTConnect_success"] == N_EDGES
    plan = json.loads((run / "schedule" / "plan.json").read_text())
    assert plan["arm"]["joint_names"] == res["arm"]["joint_names"] and plan["arm"]["sha256"] == res["arm"]["sha256"]
    steps = [s for s in plan["segments"] if s["gripper"] is not None]
    dwells = [s for s in plan["segments"] if s["name"].endswith("(dwell: no gripper)")]
    if gripper:
        assert res["arm"]["gripper_steps"] == plan["meta"]["gripper_steps"] == "jaws"
        assert len(steps) == N_GRIPPER_STEPS and not dwells
    else:
        assert res["arm"]["gripper"] is None and plan["arm"]["gripper"] is None
        assert plan["meta"] == {"gripper_steps": "dwell", "dwell_s": 1.0}  # plan.plan_json.dwell_s
        assert res["arm"]["gripper_steps"] == "dwell" and res["arm"]["dwell_s"] == 1.0
        assert len(dwells) == N_GRIPPER_STEPS and not steps
        assert all(s["t"] == [0.0, 1.0] and s["q"][0] == s["q"][1] for s in dwells)
    hw = res["hw"]
    assert hw["ok"] and hw["reason"] == "completed" and hw["gates"] == _gates(plan), hw
    assert hw["sim"]["limit_violations"] == 0 and hw["max_gate_error_rad"] <= 0.01
    assert (hw["max_gate_error_mm"] is None) == (not gripper)
    trajectory = yaml.safe_load((run / "hw" / "joint_trajectory.yaml").read_text())
    assert trajectory["joint_names"] == res["arm"]["joint_names"] + (["jaws"] if gripper else [])
    pairs = json.loads((run / "plan" / "self_collision.json").read_text())
    assert len(pairs["adjacent"]) == dof  # the base and every moving link, each with its parent
    if "hover" in stages:
        # the executor on the vehicle hovering in still water; in the current, the thrusters of a
        # vehicle carrying a heavy arm (the Panda) saturate and its motion can break a gate
        still = res["hover"]["runs"]["still water"]
        assert still["status"] == "completed" and still["gates_reached"] == still["gates"] == hw["gates"], still
    if "baseline" in stages:
        fixed = res["baseline"].get("fixed")
        assert fixed is not None, res["baseline"]
        fixed_plan = json.loads((run / "baseline" / "schedule" / "plan.json").read_text())
        fixed_hw = json.loads((run / "baseline" / "hw" / "results.json").read_text())
        assert fixed["ok"] and fixed_hw["gates"] == _gates(fixed_plan)


def test_robots_md_command_with_a_bare_arm_without_gripper(tmp_path):
    """docs/robots.md's card and command as written, default stages, for the Unitree Z1 as a
    bare MJCF file (no collision geometry) and no gripper: its gripper steps are dwells."""
    urdf, tip, radius, dof = BARE["z1"]
    card = {k: v for k, v in _doc_card().items() if k != "gripper"}
    card.update(description=_bare_mjcf(urdf, tmp_path), tip=tip, link_radius=radius)
    run = tmp_path / "run"
    res = _run(_doc_command(), run, card, tmp_path)
    _check_run(res, run, dof, gripper=False)


@pytest.mark.slow
@pytest.mark.parametrize(("arm", "gripper"), [("z1", True), ("xarm7", False), ("xarm7", True)])
def test_robots_md_command_with_bare_arms(tmp_path, arm, gripper):
    """The same with the card's gripper line, and the 7-joint xArm as a bare skeleton."""
    urdf, tip, radius, dof = BARE[arm]
    card = {k: v for k, v in _doc_card().items() if gripper or k != "gripper"}
    card.update(description=_bare_mjcf(urdf, tmp_path), tip=tip, link_radius=radius)
    run = tmp_path / "run"
    _check_run(_run(_doc_command(), run, card, tmp_path), run, dof, gripper)


# The arms' own description files (examples/arms.yaml: their collision geometry, or capsules),
# each with the jaws the file lacks; the joint counts are the oracle of what loads.
ARMS = {"z1": 6, "ur5": 6}


@pytest.mark.slow
@pytest.mark.parametrize("arm", list(ARMS))
def test_pipeline_with_another_arm(tmp_path, arm):
    settings = dict(EXAMPLE_ARMS["arms"][arm], gripper=EXAMPLE_ARMS["jaws"])
    card = {**settings, "description": str(ROBOTS / settings["description"])}
    run = tmp_path / "run"
    stages = ["docking", "plan", "schedule", "hw"]
    res = _run([*_doc_command(), f"stages=[{','.join(stages)}]"], run, card, tmp_path)
    assert res["arm"]["source"] == card["description"]
    _check_run(res, run, ARMS[arm], gripper=True, stages=stages)


@pytest.mark.slow
def test_pipeline_with_the_panda(tmp_path):
    """The Franka Panda's own description (its collision meshes), default stages."""
    settings = dict(EXAMPLE_ARMS["arms"]["panda"], gripper=EXAMPLE_ARMS["jaws"])
    card = {**settings, "description": str(ROBOTS / settings["description"])}
    run = tmp_path / "run"
    _check_run(_run(_doc_command(), run, card, tmp_path), run, 7, gripper=True)
