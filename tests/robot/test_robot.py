"""The robot model: loading by content, the shipped Bravo 7 against the manufacturer's tables,
the MuJoCo builder against the POE kinematics, and the computed self-collision pairs."""

import re
from pathlib import Path

import mujoco
import numpy as np
import pytest

from uvms_jax import bravo7, kin, robot
from uvms_jax.plan._scene import SELF_COLLISION_MARGIN

ATOL_TEXT = 1e-8  # numbers written to a file with 10 significant digits and read back
N_RANDOM = 50
ATOL_MJ = 1e-9  # MuJoCo and the POE chain in float64: round-off only

SMALL_MJCF = """<mujoco model="two_link">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <body name="upper" pos="0 0 0.1">
        <joint name="shoulder" type="hinge" axis="0 1 0" range="-1.5 1.5"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1.0"/>
        <body name="lower" pos="0.3 0 0" euler="0 0 0.3">
          <joint name="elbow" type="hinge" axis="0 0 1" range="-2 2"/>
          <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.03" mass="0.5"/>
          <site name="hand" pos="0.25 0 0" euler="0.2 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def bravo7_robot() -> robot.Robot:
    return robot.load_arm("bravo7")


def test_bravo7_description_matches_the_manufacturers_tables():
    r = bravo7_robot()
    reference = kin.bravo7()  # written from uvms_jax.bravo7's joint table, not from the file
    for field in ("twists", "T_base_tool0", "T_base_joint0", "lower", "upper", "velocity_limits"):
        np.testing.assert_allclose(np.asarray(getattr(r.chain, field)), np.asarray(getattr(reference, field)),
                                   atol=ATOL_TEXT, err_msg=field)
    assert r.joint_names == tuple(j.name for j in bravo7.ARM_JOINTS)
    assert r.effort_limits == tuple(j.effort for j in bravo7.ARM_JOINTS)
    assert (r.gripper.joint, r.gripper.lower, r.gripper.upper, r.gripper.velocity) == (
        bravo7.JAWS.name, bravo7.JAWS.lower, bravo7.JAWS.upper, bravo7.JAWS.velocity)
    assert dict(r.hardware.device_ids) == {j.name: j.device_id for j in bravo7.JOINTS}
    # Mass properties: the manufacturer's, mapped into the link frames (the jaws on link B).
    body_of = {"base": robot.BASE, **{j.name: i for i, j in enumerate(bravo7.ARM_JOINTS)}, "tool": 5}
    tool_in_b = np.asarray(bravo7.TOOL_XYZ)
    expected = kin.bravo7_inertials()
    assert len(r.inertials) == len(expected)
    for got, name, want in zip(r.inertials, bravo7.INERTIAL_BODIES, expected):
        shift = tool_in_b if name == "tool" else 0.0
        assert got.body == body_of[name]
        assert got.mass == pytest.approx(want.mass)
        assert got.volume == pytest.approx(want.volume)
        np.testing.assert_allclose(got.com, np.asarray(want.com) + shift, atol=ATOL_TEXT)
        np.testing.assert_allclose(got.cob, np.asarray(want.cob) + shift, atol=ATOL_TEXT)
        np.testing.assert_allclose(got.inertia, want.inertia, atol=ATOL_TEXT)


def _mujoco_tool(r: robot.Robot, q: np.ndarray) -> np.ndarray:
    model = robot.robot_spec(r).compile()
    data = mujoco.MjData(model)
    out = []
    for row in q:
        data.qpos[:] = row
        mujoco.mj_kinematics(model, data)
        T = np.eye(4)
        T[:3, :3] = data.site(robot.TOOL_SITE).xmat.reshape(3, 3)
        T[:3, 3] = data.site(robot.TOOL_SITE).xpos
        out.append(T)
    return np.stack(out)


@pytest.mark.parametrize("which", ["bravo7", "mjcf"])
def test_mujoco_model_of_the_robot_follows_its_kinematics(which):
    r = bravo7_robot() if which == "bravo7" else robot.load_robot(SMALL_MJCF, tip="hand", link_radius=0.03)
    q = np.random.default_rng(0).uniform(r.lower, r.upper, (N_RANDOM, r.n_joints))
    np.testing.assert_allclose(_mujoco_tool(r, q), np.asarray(kin.fk(r.chain, q)), atol=ATOL_MJ)


def test_format_is_read_from_the_content(tmp_path):
    mjcf_named_urdf = tmp_path / "arm.urdf"
    mjcf_named_urdf.write_text(SMALL_MJCF)
    r = robot.load_robot(mjcf_named_urdf, tip="hand", link_radius=0.03)
    assert r.joint_names == ("shoulder", "elbow") and r.link_names == ("upper", "lower")
    assert [b.mass for b in r.inertials] == pytest.approx([1.0, 0.5])
    assert r.source == str(mjcf_named_urdf) and len(r.digest) == 64
    text = robot.load_robot((robot.DESCRIPTIONS / "bravo7.urdf").read_text(), tip="tool", link_radius=0.04)
    assert text.joint_names == tuple("GFEDCB") and text.source == "<text>"


@pytest.mark.parametrize("text, message", [
    ("", "empty string"),
    ("<robot name='a'><link name='x'></robot>", "not well-formed XML: Opening and ending tag mismatch: link line 1 "
                                                "and robot, line 1, column 40"),
    ("<sdf version='1.6'/>", "root <sdf>: expected <robot> (URDF) or <mujoco> (MJCF)"),
    ("no/such/file.urdf", "robot description file not found: no/such/file.urdf"),
])
def test_bad_descriptions_say_what_is_wrong(text, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        robot.load_robot(text, link_radius=0.04)


def test_config_errors_name_the_problem():
    cfg = {"card": "bravo7"}
    with pytest.raises(ValueError, match=r"unknown keys \['colour'\]"):
        robot.robot_from_config({**cfg, "colour": "orange"})
    with pytest.raises(ValueError, match="neither a shipped arm"):
        robot.robot_from_config({"card": "bravo8"})
    with pytest.raises(ValueError, match="no device id for joint 'A'"):
        robot.robot_from_config({**cfg, "hardware": {"protocol": "bpl", "device_ids": {j: 2 + i for i, j in
                                                                                     enumerate("BCDEFG")}}})
    with pytest.raises(ValueError, match="gripper joint 'Z' not in the URDF"):
        robot.robot_from_config({**cfg, "gripper": "Z"})
    with pytest.raises(ValueError, match=r"buoyancy names links not in the description: \['link_Q'\]"):
        robot.robot_from_config({**cfg, "buoyancy": {"link_Q": {"volume": 1e-3, "cob": [0, 0, 0]}}})


def test_self_collision_pairs_are_computed():
    arm = bravo7_robot()
    pairs = robot.self_collision_pairs(arm, n_samples=200)
    assert pairs["adjacent"] == [("base_link", "link_G"), ("link_G", "link_F"), ("link_F", "link_E"),
                                 ("link_E", "link_D"), ("link_D", "link_C"), ("link_C", "link_B")]
    # The thesis model's hand-listed pairs: links E and C, whose capsules meet at the wrist
    # cluster in every pose; and, within the planner's margin, the base link and link F, whose
    # capsules meet at the shoulder (the F capsule's end is 81.6 mm from the base capsule's,
    # less than two radii and a 10 mm margin).
    assert pairs["always"] == [("link_E", "link_C")]
    assert robot.self_collision_pairs(arm, n_samples=200, margin=SELF_COLLISION_MARGIN)["always"] == [
        ("base_link", "link_F"), ("link_E", "link_C")]


STAGES = Path(__file__).parents[2] / "uvms_jax"


def test_no_stage_names_a_particular_arm():
    """Planning, scheduling, the pipeline and the plan format receive their arm: none of their
    modules imports or names one."""
    files = [p for d in ("plan", "sched", "pipeline") for p in (STAGES / d).glob("*.py")] + [STAGES / "planfile.py"]
    assert len(files) > 20
    naming = [f"{p.relative_to(STAGES)}:{i}" for p in files for i, line in enumerate(p.read_text().splitlines(), 1)
              if re.search(r"bravo|alpha ?5", line, flags=re.I)]
    assert not naming, naming
