"""What the stages need of the run's arm is checked before the first stage
(``uvms_jax.pipeline.check_stages``): a run that cannot finish is refused in one line with exit
status 2 and nothing run; a baseline the arm cannot do from the thesis's fixed mount is skipped
with the reason; the baseline takes the run's arm and start."""

from __future__ import annotations

import pytest
import yaml
from hydra import compose, initialize_config_dir

from _pipeline_helpers import CONFIG_DIR, ROOT
from _script_runs import run_script_cases
from uvms_jax.pipeline import check_stages

USAGE_EXIT = 2  # experiments/_cli.py: a configuration error, nothing ran
DESCRIPTIONS = ROOT / "uvms_jax" / "robot" / "descriptions"
EXAMPLE_PLAN = ROOT / "examples" / "thesis_plan.json"  # the Bravo 7's, with gripper steps


def _settings(pipeline, *overrides: str):
    with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
        return pipeline.settings_of(compose(config_name="pipeline", overrides=["experiment=tiny", *overrides]))


def _bravo_without_gripper(tmp_path) -> str:
    """A card of the Bravo 7's own description file without its `gripper:` line."""
    card = yaml.safe_load((DESCRIPTIONS / "bravo7.yaml").read_text())
    card = {k: v for k, v in card.items() if k not in ("gripper", "finger_size", "hardware")}
    path = tmp_path / "card.yaml"
    path.write_text(yaml.safe_dump({**card, "description": str(DESCRIPTIONS / card["description"])}))
    return str(path)


REFUSED = [
    (["scenario.start_q=[0.1,0.2,0.3]"],  # the scenario schema's check, the first to see it
     ["scenario.start_q: expected 6 joint angles ['G', 'F', 'E', 'D', 'C', 'B'] [rad], got [0.1, 0.2, 0.3]"]),
    (["plan.plan_json.jaws_open_mm=50", "plan.plan_json.jaws_closed_mm=-1"],
     ["plan.plan_json.jaws_open_mm: 50.0 mm is outside the travel [0, 35] mm of arm 'bravo7''s gripper 'A'",
      "plan.plan_json.jaws_closed_mm: -1.0 mm is outside"]),
    (["scenario.arm.card=alpha5", "scenario.start_q=null", "stages=[hw]"],  # the example plan is the Bravo 7's
     ["error: hw.plan: plan joint_names ['G', 'F', 'E', 'D', 'C', 'B'] must be those of arm 'alpha_5'"]),
    (["scenario.arm.card=GRIPPERLESS", "stages=[hw]"],
     [f"hw.plan: {EXAMPLE_PLAN} has gripper steps and arm 'bravo7' has no gripper: add "
      "`gripper: {joint: jaws, lower: 0.0, upper: 0.1, velocity: 0.1}` (its jaws) to the arm's card"]),
]


@pytest.fixture(scope="module")
def refused(tmp_path_factory):
    """Each case of :data:`REFUSED`, its own run of the pipeline's command line, the runs in one
    child process (the imports once): ``[(result, run folder)]``."""
    tmp = tmp_path_factory.mktemp("arm_checks")
    runs = [tmp / f"run{i}" for i in range(len(REFUSED))]
    cases = [["experiment=tiny", f"hydra.run.dir={run}", *(o.replace("GRIPPERLESS", _bravo_without_gripper(tmp))
                                                           for o in overrides)]
             for run, (overrides, _) in zip(runs, REFUSED)]
    return list(zip(run_script_cases("pipeline.py", cases, timeout=300 * len(cases))["cases"], runs))


@pytest.mark.parametrize("case", range(len(REFUSED)), ids=["start_q", "jaws", "another_arms_plan", "no_gripper"])
def test_what_a_stage_cannot_do_for_the_arm_is_refused_before_the_first_stage(refused, case):
    done, run = refused[case]
    lines = [line for line in done["stderr"].splitlines() if line.strip()]  # stdout: the log (the arm loaded)
    assert done["code"] == USAGE_EXIT and len(lines) == 1, done["output"]
    assert lines[0].startswith("error: ")
    for part in REFUSED[case][1]:
        assert part in lines[0], lines[0]
    assert not any((run / name).exists() for name in ("surrogate", "docking", "hw", "RUNNING", "results.json"))


def test_baseline_takes_the_runs_start(pipeline):
    """The Bravo 7 keeps the thesis's start at the fixed mount (the demo's scenario has the
    cage's start_q); null finds one there, clear of the cage."""
    thesis = yaml.safe_load((CONFIG_DIR / "scenario" / "thesis_cage.yaml").read_text())["start_q"]
    checked = check_stages(_settings(pipeline))
    assert checked.baseline_skipped is None
    assert checked.baseline_scene.start_q.tolist() == thesis
    found = check_stages(_settings(pipeline, "scenario.start_q=null")).baseline_scene
    assert found.start_q.tolist() != thesis
    assert checked.gripper_steps == {"gripper_steps": "jaws"}


def test_baseline_out_of_the_arms_reach_is_skipped(pipeline):
    """The Alpha 5 (0.34 m of reach) cannot reach the tables from the cage top: the run goes on
    without the baseline, and says why."""
    checked = check_stages(_settings(pipeline, "scenario.arm.card=alpha5", "scenario.start_q=null",
                                     "plan.plan_json.jaws_open_mm=15"))  # its jaws open 15 mm
    assert checked.baseline_scene is None
    assert checked.baseline_skipped.startswith("arm 'alpha_5' cannot reach node 1 (cube1) from the fixed mount")
    assert "beyond the arm's longest reach (0.342 m)" in checked.baseline_skipped
