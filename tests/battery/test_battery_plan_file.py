"""Bad plan files are refused by ``uvms-hw run`` (exit 2, one line) before anything is sent: a
repeated key (which ``segments`` counts?), nesting deeper than planfile.MAX_NESTING, a motion
longer than planfile.MAX_MOTION_S, a version that is not the integer 1, NaN times, YAML alias
bombs."""

from __future__ import annotations

import json
import time

import pytest
from _battery import CASE_LIMIT_S, ROOT, USAGE_EXIT

from uvms_jax.hw import cli
from uvms_jax.planfile import MAX_MOTION_S, PlanError, load_plan

THESIS = (ROOT / "examples" / "thesis_plan.json").read_text()


def _edited(edit) -> str:
    plan = json.loads(THESIS)
    edit(plan)
    return json.dumps(plan)


def _out_of_limits(plan):
    plan["segments"][0]["q"][-1][0] = 99.0


CASES = {
    # A first `segments` out of limits, then a good one: the last would win without a word.
    "repeated_key.json": ('{"segments": ' + json.dumps(json.loads(_edited(_out_of_limits))["segments"]) + ", "
                          + THESIS.strip()[1:], "repeated keys ['segments'] in one object"),
    "deep.json": ("[" * 100_000 + "]" * 100_000, "nested 100000 levels deep; a plan has at most 16"),
    "long.json": (_edited(lambda p: p["segments"][0]["t"].__setitem__(-1, 1e9)),
                  f"total planned motion time 1e+09 s is not within the sanity limit of {MAX_MOTION_S:g} s"),
    "version_true.json": (_edited(lambda p: p.update(version=True)), "unsupported plan version True"),
    "version_text.json": (_edited(lambda p: p.update(version="1")), "unsupported plan version '1'"),
    "nan_time.json": (_edited(lambda p: p["segments"][0]["t"].__setitem__(-1, float("nan"))), "not within"),
    "bomb.yaml": ("a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [{', '.join([f'*{p}'] * 9)}]\n" for p, c in zip("abcdefgh", "bcdefghi")),
        "with its aliases expanded, the document holds more than 100000"),
    "repeated.yaml": ("version: 1\nversion: 1\n", "found duplicate key 'version'"),
}


@pytest.mark.parametrize("name", CASES)
def test_bad_plan_file_is_one_line_exit_2(tmp_path, capsys, name):
    text, expected = CASES[name]
    path = tmp_path / name
    path.write_text(text)
    t = time.perf_counter()
    code = cli.main(["run", str(path), "--sim", "--no-plot", "--out", str(tmp_path / "out")])
    assert time.perf_counter() - t < CASE_LIMIT_S
    captured = capsys.readouterr()
    lines = [line for line in (captured.out + captured.err).splitlines() if line.strip()]
    assert code == USAGE_EXIT and len(lines) == 1, lines
    assert lines[0].startswith("uvms-hw: ") and expected in lines[0], lines[0]
    assert not (tmp_path / "out").exists()  # nothing started


def test_the_example_plan_still_loads():
    plan = load_plan(ROOT / "examples" / "thesis_plan.json")
    assert plan.segments and sum(s.t[-1] for s in plan.segments if s.t) < MAX_MOTION_S


def test_repeated_keys_are_refused_at_any_depth(tmp_path):
    path = tmp_path / "p.json"
    path.write_text(_edited(lambda p: None).replace('"gripper": null', '"gripper": null, "gripper": null', 1))
    with pytest.raises(PlanError, match=r"repeated keys \['gripper'\]"):
        load_plan(path)
