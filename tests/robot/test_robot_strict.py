"""Strict loading: a description that would load wrong is refused with a message that says what
and where — never a lenient second parse, never a traceback from deep inside a parser."""

import numpy as np
import pytest

from uvms_jax import robot

BRAVO7_URDF = (robot.DESCRIPTIONS / "bravo7.urdf").read_text()
N_CUTS = 56


def test_every_truncation_is_malformed_xml_with_its_position():
    """A file cut anywhere before its end is not XML: the error is the parser's, with line and
    column, whether the file is read as a robot or as a URDF."""
    end = len(BRAVO7_URDF.rstrip())
    for cut in np.linspace(1, end - 1, N_CUTS).astype(int):
        for load in (lambda t: robot.load_robot(t, link_radius=0.04), lambda t: robot.chain_from_urdf(t, tip_link="tool")):
            with pytest.raises(ValueError, match=r"is not well-formed XML: .*line \d+, column \d+"):
                load(BRAVO7_URDF[:cut])


def _urdf(joints: str, links: str = "<link name='base'/><link name='a'/><link name='b'/>") -> str:
    return f"<robot name='r'>{links}{joints}</robot>"


JOINT_AB = ("<joint name='{name}' type='revolute'><parent link='{p}'/><child link='{c}'/>"
            "<origin xyz='{xyz}'/><axis xyz='{axis}'/><limit lower='-1' upper='1' velocity='1' effort='1'/></joint>")


def _joint(name="j1", p="base", c="a", xyz="0 0 0.1", axis="0 0 1") -> str:
    return JOINT_AB.format(name=name, p=p, c=c, xyz=xyz, axis=axis)


@pytest.mark.parametrize("text, message", [
    (_urdf(_joint() + _joint("j2", "a", "b") + _joint("j3", "base", "b")),
     r"link 'b' is the child of two joints \('j2' and 'j3'\): a closed loop"),
    (_urdf(_joint("j1", "b", "a") + _joint("j2", "a", "b"), "<link name='a'/><link name='b'/>"),
     "form a cycle: a closed loop"),
    (_urdf(_joint(), "<link name='base'/><link name='a'/><link name='a'/>"), r"link names repeat: \['a'\]"),
    (_urdf(_joint() + _joint("j1", "a", "b")), r"joint names repeat: \['j1'\]"),
    (_urdf(_joint(axis="nan 0 1")), "joint 'j1': axis 'nan 0 1' is not finite"),
    (_urdf(_joint(axis="0 0 0")), r"joint 'j1': axis \[0. 0. 0.\] has zero length"),
    (_urdf(_joint(xyz="0 nan 0.1")), "joint 'j1': origin xyz '0 nan 0.1' is not finite"),
    (_urdf(_joint(xyz="0 0.1")), "joint 'j1': origin xyz '0 0.1' is not 3 numbers"),
    (_urdf(_joint(c="z")), "joint 'j1' names an unknown child link 'z'"),
    (_urdf("<joint name='j1' type='fixed'><parent link='base'/></joint>"), r"joint 'j1' has no <child link=\.\.\.>"),
    (_urdf("", "<link/>"), "a <link> has no name"),
])
def test_bad_urdfs_are_refused_by_name(text, message):
    with pytest.raises(ValueError, match=message):
        robot.chain_from_urdf(text)
    with pytest.raises(ValueError, match=message):
        robot.load_robot(text, link_radius=0.04)


def test_the_wrong_format_is_named():
    mjcf = robot.robot_mjcf(robot.load_arm("bravo7"))
    with pytest.raises(ValueError, match=r"<text> is MJCF \(<mujoco>\), not URDF \(<robot>\)"):
        robot.chain_from_urdf(mjcf)
    with pytest.raises(ValueError, match=r"<text> is URDF \(<robot>\), not MJCF \(<mujoco>\)"):
        robot.chain_from_mjcf(BRAVO7_URDF)
    with pytest.raises(ValueError, match="is not well-formed XML"):
        robot.chain_from_urdf(b"\x89PNG\r\n\x1a\n")
    with pytest.raises(ValueError, match="empty string"):
        robot.chain_from_urdf("")
