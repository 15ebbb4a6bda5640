"""docs/robots.md's card and command, as the page writes them, with arms turned into bare MJCF
skeletons by MuJoCo (every geometry stripped): each docks, plans every task-graph edge,
schedules, runs the winner on its simulated arm with every gate reached, hovers, and the
baseline runs from the thesis's fixed mount.

The fast suite runs the Unitree Z1 without the card's ``gripper:`` line (its gripper steps are
dwells); the slow suite runs the 7-joint xArm with it (jaws). The arms' own description files
run in test_pipeline_arms_own.py."""

from __future__ import annotations

import pytest

from _arm_runs import BARE, bare_mjcf, check_run, doc_card, doc_command, run_pipeline


def _bare_run(tmp_path, arm: str, gripper: bool) -> None:
    """The documented command, default stages, with ``arm`` as a bare skeleton, the card's
    gripper line kept or left out."""
    urdf, tip, radius, dof = BARE[arm]
    card = {k: v for k, v in doc_card().items() if gripper or k != "gripper"}
    card.update(description=bare_mjcf(urdf, tmp_path), tip=tip, link_radius=radius)
    run = tmp_path / "run"
    check_run(run_pipeline(doc_command(), run, card, tmp_path), run, dof, gripper)


def test_robots_md_command_with_a_bare_arm_without_gripper(tmp_path):
    """The Unitree Z1 (6 joints) as a bare MJCF file and no gripper: its gripper steps are dwells."""
    _bare_run(tmp_path, "z1", gripper=False)


@pytest.mark.slow
def test_robots_md_command_with_a_bare_7_joint_arm_and_the_gripper(tmp_path):
    """The card's gripper line as written (jaws), and the 7-joint xArm as a bare skeleton."""
    _bare_run(tmp_path, "xarm7", gripper=True)
