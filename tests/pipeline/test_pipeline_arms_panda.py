"""The pipeline (tiny preset, default stages) with the Franka Panda's own description file (its
collision meshes) and the jaws it lacks, through docs/robots.md's command: it docks, plans every
task-graph edge, schedules, runs the winner on its simulated arm with every gate reached, hovers,
and the baseline runs from the thesis's fixed mount. Slow; a file of its own so that pytest's
workers (one file each) share it with the other arms' runs (test_pipeline_arms*.py)."""

from __future__ import annotations

import pytest

from _arm_runs import check_run, doc_command, own_card, run_pipeline


@pytest.mark.slow
def test_pipeline_with_the_panda(tmp_path):
    run = tmp_path / "run"
    check_run(run_pipeline(doc_command(), run, own_card("panda"), tmp_path, optimised=True), run, 7, gripper=True)
