"""The pipeline (tiny preset) with real arms' own description files (examples/arms.yaml: their
collision geometry, or capsules), each with the jaws the file lacks, through docs/robots.md's
command and the docking to execution stages: each docks, plans every task-graph edge, schedules
and runs the winner on its simulated arm with every gate reached. The Panda's run with every
stage is test_pipeline_arms_panda.py's. All slow; files of their own so that pytest's workers
(one file each) share these runs with test_pipeline_arms.py's."""

from __future__ import annotations

import pytest

from _arm_runs import DOCK_TO_RUN, check_run, doc_command, own_card, run_pipeline

pytestmark = pytest.mark.slow

# The joint counts are the oracle of what loads.
ARMS = {"z1": 6, "ur5": 6}


@pytest.mark.parametrize("arm", list(ARMS))
def test_pipeline_with_another_arm(tmp_path, arm):
    card = own_card(arm)
    run = tmp_path / "run"
    res = run_pipeline(doc_command(DOCK_TO_RUN), run, card, tmp_path)
    assert res["arm"]["source"] == card["description"]
    check_run(res, run, ARMS[arm], gripper=True, stages=DOCK_TO_RUN)
