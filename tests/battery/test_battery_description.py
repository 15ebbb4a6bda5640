"""Bad robot descriptions: read strictly, never a lenient second parse (a DTD, an entity, an
entity bomb refused in one line); mesh file names quoted in MJCF; an arm whose Jacobian has full
rank nowhere (w = 0 everywhere) warned about; ``uvms-hw`` refuses such files with exit 2."""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np
import pytest
from _battery import CASE_LIMIT_S, ROOT, USAGE_EXIT

from uvms_jax import robot
from uvms_jax.hw import cli
from uvms_jax.robot import load_arm, robot_spec
from uvms_jax.robot._geometry import Shape
from uvms_jax.robot._parse import read_urdf

LIMIT = '<limit lower="-3" upper="3" effort="1" velocity="1"/>'


def _urdf(n: int = 2, axes=("0 0 1", "0 1 0")) -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(n + 1))
    joints = "".join(f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
                     f'<origin xyz="0.1 0 0"/><axis xyz="{axes[i % len(axes)]}"/>{LIMIT}</joint>' for i in range(n))
    return f'<robot name="r">{links}{joints}</robot>'


def _bomb() -> str:
    ents = '<!ENTITY a "aaaaaaaaaa">' + "".join(f'<!ENTITY {c} "{("&" + p + ";") * 10}">'
                                                 for p, c in zip("abcdef", "bcdefg"))
    return f'<?xml version="1.0"?><!DOCTYPE robot [{ents}]>' + _urdf().replace('name="r"', 'name="&g;"')


CASES = {
    # yourdfpy's own parser fails on this and used to retry in recovery mode, which loaded it.
    "external_entity": ('<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY x SYSTEM "file:///etc/hostname">]>'
                        + _urdf().replace('<link name="l0"/>', '<link name="l0">&x;</link>'), "declares a DTD"),
    "internal_entity": ('<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY x "r2">]>' + _urdf(), "declares a DTD"),
    "entity_bomb": (_bomb(), "is not well-formed XML: Maximum entity amplification factor exceeded"),
    "deep": (_urdf().replace('<link name="l0"/>', '<link name="l0">' + "<x>" * 300 + "</x>" * 300 + "</link>"),
             "is not well-formed XML: Excessive depth in document"),
    "garbage_tail": (_urdf() + "<robot>", "is not well-formed XML: Extra content at the end of the document"),
}


@pytest.mark.parametrize("name", CASES)
def test_bad_urdf_is_refused_without_a_second_parse(tmp_path, name):
    text, expected = CASES[name]
    t = time.perf_counter()
    with pytest.raises(ValueError, match=expected) as e:
        read_urdf(text)
    assert time.perf_counter() - t < CASE_LIMIT_S and "\n" not in str(e.value)


@pytest.mark.parametrize("name", CASES)
def test_uvms_hw_refuses_an_arm_card_of_a_bad_urdf(tmp_path, capsys, name):
    (tmp_path / "arm.urdf").write_text(CASES[name][0])
    (tmp_path / "arm.yaml").write_text("description: arm.urdf\nlink_radius: 0.04\n")
    code = cli.main(["run", str(ROOT / "examples" / "thesis_plan.json"), "--dry-run", "--robot",
                     str(tmp_path / "arm.yaml")])
    captured = capsys.readouterr()
    lines = [line for line in (captured.out + captured.err).splitlines() if line.strip()]
    assert code == USAGE_EXIT and len(lines) == 1 and lines[0].startswith("uvms-hw: "), lines
    assert "Traceback" not in captured.err


def test_parallel_axes_are_warned_about(caplog):
    with caplog.at_level(logging.WARNING, logger="uvms_jax.robot._parse"):
        robot.chain_from_urdf(_urdf(6, axes=("0 0 1",)))
    [record] = caplog.records
    assert "its Jacobian has rank 3 at best" in record.getMessage()
    assert "the dexterity index w is 0 at every pose" in record.getMessage()


@pytest.mark.parametrize("axes", [("0 0 1",), ("0 0 1", "0 1 0")])
def test_full_rank_chains_load_quietly(caplog, axes):
    """A planar 2R (rank 2 = its joints) and a spatial 2R: w > 0 somewhere, no warning."""
    with caplog.at_level(logging.WARNING, logger="uvms_jax.robot._parse"):
        robot.chain_from_urdf(_urdf(2, axes))
        load_arm("bravo7")
    assert not caplog.records


def test_mesh_file_names_reach_mujoco_as_written():
    robot = load_arm("bravo7")
    odd = Shape(body=0, kind="mesh", pose=tuple(np.eye(4).ravel()), file='/x/a"b<c>&d.stl', link=robot.link_names[1])
    spec = robot_spec(dataclasses.replace(robot, shapes=(odd,)))
    assert [m.file for m in spec.meshes] == ['/x/a"b<c>&d.stl']  # one name, as written
