"""docs/robots.md's card and command, as the page writes them, with arms turned into bare MJCF
skeletons by MuJoCo (every geometry stripped): each docks, plans every task-graph edge,
schedules and runs the winner on its simulated arm with every gate reached.

The fast suite runs the Unitree Z1 without the card's ``gripper:`` line (its gripper steps are
dwells) through every stage: it also hovers, and the baseline runs from the thesis's fixed
mount. The slow suite runs the 7-joint xArm with the line (jaws) through the stages that plan
and run the jaws, docking to execution; the Panda runs every stage with them
(test_pipeline_arms_panda.py). The arms' own description files run in
test_pipeline_arms_own.py and test_pipeline_arms_panda.py."""

from __future__ import annotations

import pytest

from _arm_runs import BARE, DOCK_TO_RUN, STAGES, bare_mjcf, check_run, doc_card, doc_command, run_pipeline


def _bare_run(tmp_path, arm: str, gripper: bool, stages: list[str] = STAGES) -> None:
    """The documented command with ``arm`` as a bare skeleton, the card's gripper line kept or
    left out, through ``stages`` (default: every stage)."""
    urdf, tip, radius, dof = BARE[arm]
    card = {k: v for k, v in doc_card().items() if gripper or k != "gripper"}
    card.update(description=bare_mjcf(urdf, tmp_path), tip=tip, link_radius=radius)
    run = tmp_path / "run"
    check_run(run_pipeline(doc_command(stages), run, card, tmp_path), run, dof, gripper, stages=stages)


def test_robots_md_command_with_a_bare_arm_without_gripper(tmp_path):
    """The Unitree Z1 (6 joints) as a bare MJCF file and no gripper: its gripper steps are dwells."""
    _bare_run(tmp_path, "z1", gripper=False)


@pytest.mark.slow
def test_robots_md_command_with_a_bare_7_joint_arm_and_the_gripper(tmp_path):
    """The card's gripper line as written (jaws), and the 7-joint xArm as a bare skeleton: the
    jaws are planned (plan.json's gripper steps) and run on the simulated arm."""
    _bare_run(tmp_path, "xarm7", gripper=True, stages=DOCK_TO_RUN)
