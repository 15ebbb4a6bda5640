"""The pipeline (tiny preset) with real arms' own description files (examples/arms.yaml: their
collision geometry, or capsules), each with the jaws the file lacks, through docs/robots.md's
command: each docks, plans every task-graph edge, schedules and runs the winner on its
simulated arm with every gate reached; the Panda also hovers and runs the baseline (default
stages). All slow; a file of its own so that pytest's workers share these runs with
test_pipeline_arms.py's."""

from __future__ import annotations

import pytest

from _arm_runs import check_run, doc_command, own_card, run_pipeline

pytestmark = pytest.mark.slow

# The joint counts are the oracle of what loads.
ARMS = {"z1": 6, "ur5": 6}


@pytest.mark.parametrize("arm", list(ARMS))
def test_pipeline_with_another_arm(tmp_path, arm):
    card = own_card(arm)
    run = tmp_path / "run"
    stages = ["docking", "plan", "schedule", "hw"]
    res = run_pipeline([*doc_command(), f"stages=[{','.join(stages)}]"], run, card, tmp_path)
    assert res["arm"]["source"] == card["description"]
    check_run(res, run, ARMS[arm], gripper=True, stages=stages)


def test_pipeline_with_the_panda(tmp_path):
    """The Franka Panda's own description (its collision meshes), default stages."""
    run = tmp_path / "run"
    check_run(run_pipeline(doc_command(), run, own_card("panda"), tmp_path, optimised=True), run, 7, gripper=True)
