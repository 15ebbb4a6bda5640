"""The pipeline's runs with other arms than the Bravo 7 (tests/pipeline/test_pipeline_arms*.py):
docs/robots.md's card and command, the arms' description files (example-robot-data, offline),
bare MJCF skeletons made from them, and the checks every such run must pass."""

from __future__ import annotations

import importlib.metadata
import json
import os
import re
import shlex
import subprocess
import sys

import mujoco
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
DOCK_TO_RUN = ["docking", "plan", "schedule", "hw"]  # the stages that place, plan and run the arm


def bare_mjcf(urdf: str, out) -> str:
    """The URDF as MJCF, compiled by MuJoCo with every visual and collision element removed: a
    description with no collision geometry at all. Its links stay bodies (MuJoCo would merge
    the fixed ones, tool frames among them, into their parents)."""
    text = re.sub(r"<(visual|collision)>.*?</\1>", "", (ROBOTS / urdf).read_text(), flags=re.S)
    text = re.sub(r"(<robot[^>]*>)", r'\1<mujoco><compiler fusestatic="false"/></mujoco>', text, count=1)
    path = out / "arm.xml"
    mujoco.mj_saveLastXML(str(path), mujoco.MjModel.from_xml_string(text))
    assert "<geom" not in path.read_text()
    return str(path)


def doc_card() -> dict:
    """docs/robots.md's card (its YAML block), as a mapping."""
    block = re.search(r"```yaml\n(# my_arm\.yaml\n.*?)```", DOC, flags=re.S)
    return yaml.safe_load(block.group(1))


def doc_command(stages: list[str] = STAGES) -> list[str]:
    """docs/robots.md's command that runs an arm card, as words; ``stages`` other than the
    default ones are added to it."""
    line = re.search(r"^python experiments/pipeline\.py scenario\.arm\.card=my_arm\.yaml.*$", DOC, flags=re.M)
    extra = [] if stages == STAGES else [f"stages=[{','.join(stages)}]"]
    return shlex.split(line.group(0)) + extra


def plan_gates(plan: dict) -> int:
    """The reached-gates a plan asks for, counted from plan.json alone: every waypoint (a
    segment's first repeats the previous segment's last, once the arm has started) and every
    gripper step."""
    return sum(len(s.get("q", [])) - (i > 0 and bool(s.get("q"))) + (s["gripper"] is not None)
               for i, s in enumerate(plan["segments"]))


def run_pipeline(cmd: list[str], run, card: dict, tmp_path, optimised: bool = False) -> dict:
    """``cmd`` (words of a pipeline command whose card path is ``my_arm.yaml``) with ``card``
    written there, the tiny preset and ``run`` as the run folder; results.json's dict.

    ``optimised``: XLA's own optimisation instead of the tests' quick compiles (tests/conftest.py),
    for a run that spends its time running programs, not compiling them: the Panda's docking stage
    (its collision meshes) took 87 s with the tests' flags and 47 s without, on 2 cores; the Z1's
    (its own meshes) took as long either way."""
    path = tmp_path / "my_arm.yaml"
    path.write_text(yaml.safe_dump(card))
    cmd = [sys.executable if w == "python" else w.replace("=my_arm.yaml", f"={path}") for w in cmd]
    env = dict(os.environ, XLA_FLAGS=os.environ["XLA_FLAGS_OUTSIDE_TESTS"]) if optimised else None
    done = subprocess.run([*cmd, "experiment=tiny", f"hydra.run.dir={run}"], cwd=ROOT, capture_output=True,
                          text=True, timeout=1500, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    assert not (run / "RUNNING").exists()
    return json.loads((run / "results.json").read_text())


def check_run(res: dict, run, dof: int, gripper: bool, stages=STAGES) -> None:
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
    assert hw["ok"] and hw["reason"] == "completed" and hw["gates"] == plan_gates(plan), hw
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
        assert fixed["ok"] and fixed_hw["gates"] == plan_gates(fixed_plan)


def own_card(arm: str) -> dict:
    """examples/arms.yaml's settings of ``arm`` with its own description file and the jaws."""
    settings = dict(EXAMPLE_ARMS["arms"][arm], gripper=EXAMPLE_ARMS["jaws"])
    return {**settings, "description": str(ROBOTS / settings["description"])}
