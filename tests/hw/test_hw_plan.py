"""plan.json parsing and the dry-run check."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from _hw_helpers import BRAVO
from uvms_jax.hw import ExecutorSettings, PlanError, check_plan, load_plan, parse_plan, plan_to_dict

EXAMPLE = Path(__file__).parents[2] / "examples" / "thesis_plan.json"
GOOD = {
    "joint_names": list("GFEDCB"),
    "segments": [
        {"name": "a", "t": [0.0, 1.0], "q": [[1, 1, 1, 1, 1, 1], [1.2, 1, 1, 1, 1, 1]], "gripper": {"jaws_mm": 20}},
        {"name": "b", "t": [0.0, 2.0], "q": [[1.2, 1, 1, 1, 1, 1], [1.2, 1.5, 1, 1, 1, 1]]},
        {"name": "c", "gripper": {"jaws_mm": 0}},
    ],
}


def mutate(path, value):
    obj = copy.deepcopy(GOOD)
    target = obj
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return obj


def test_example_plan_passes():
    s = check_plan(load_plan(EXAMPLE), BRAVO)
    assert s.n_segments > 20 and s.n_gripper_steps > 5 and s.max_speed_ratio <= 1
    assert s.estimated_s >= s.planned_s


def test_good_plan_and_round_trip():
    p = parse_plan(GOOD)
    s = check_plan(p, BRAVO)
    assert (s.n_segments, s.n_waypoints, s.n_gripper_steps) == (3, 4, 2)
    assert parse_plan(json.loads(json.dumps(plan_to_dict(p)))) == p
    assert p.base_rpy is None and "base_rpy" not in plan_to_dict(p)
    hanging = parse_plan({**GOOD, "base_rpy": [3.14159, 0, 0.5]})
    assert hanging.base_rpy == (3.14159, 0.0, 0.5)
    assert parse_plan(json.loads(json.dumps(plan_to_dict(hanging)))) == hanging


@pytest.mark.parametrize(("path", "value", "message"), [
    (["segments", 0, "q", 1, 0], 6.4, "joint G = 6.4000 rad outside"),
    (["segments", 1, "q", 1, 2], -0.1, "joint E = -0.1000 rad outside"),
    (["segments", 0, "q", 1, 1], float("nan"), "joint F is nan"),
    (["segments", 0, "t", 1], 0.3, "joint G needs 0.667 rad/s > limit 0.500"),
    (["segments", 1, "t", 0], 0.5, "t[0] = 0.5 s, must be 0"),
    (["segments", 1, "t"], [0.0, 0.0], "not increasing"),
    (["segments", 1, "q", 0, 0], 1.25, "0.0500 rad away from the previous segment's end on joint G"),
    (["segments", 2, "gripper", "jaws_mm"], 40.0, "jaws 40.0 mm outside"),
])
def test_bad_plans_refused_with_clear_message(path, value, message):
    with pytest.raises(PlanError, match="plan refused") as e:
        check_plan(parse_plan(mutate(path, value)), BRAVO)
    assert message in str(e.value)


@pytest.mark.parametrize(("obj", "message"), [
    (mutate(["joint_names"], list("GFEDC")), "6 values for 5 joints"),
    (mutate(["segments"], []), "non-empty"),
    (mutate(["segments", 0, "speed"], 1), "unknown keys"),
    (mutate(["segments", 0, "t"], [0.0]), "1 times but 2 waypoints"),
    (mutate(["segments", 0, "gripper"], {"mm": 3}), "gripper"),
    (mutate(["segments", 0, "q", 0, 0], "1.0"), "expected numbers"),
    (mutate(["version"], 2), "unsupported plan version"),
    ({"joint_names": list("GFEDCB"), "segments": [{"name": "x"}]}, "neither waypoints nor a gripper"),
    (mutate(["base_rpy"], [3.1, 0.0]), r"plan.base_rpy: expected 3 finite angles"),
    (mutate(["base_rpy"], [3.1, float("inf"), 0.0]), r"plan.base_rpy: expected 3 finite angles"),
    (mutate(["base_rpy"], "up"), r"plan.base_rpy: expected a list of numbers"),
    ([1, 2], "JSON object"),
])
def test_malformed_plans(obj, message):
    with pytest.raises(PlanError, match=message):
        parse_plan(obj)


def test_joint_order_and_speed_scale():
    with pytest.raises(PlanError, match="must be"):
        check_plan(parse_plan(mutate(["joint_names"], list("BCDEFG"))), BRAVO)
    with pytest.raises(PlanError, match="needs"):  # 0.25 rad/s over a 0.1 × 0.5 rad/s budget
        check_plan(parse_plan(GOOD), BRAVO, ExecutorSettings(speed_scale=0.1))


def test_many_problems_listed_and_capped():
    obj = copy.deepcopy(GOOD)
    for seg in obj["segments"][:2]:
        seg["q"] = [[9.0] * 6, [9.0] * 6]
    with pytest.raises(PlanError) as e:
        check_plan(parse_plan(obj), BRAVO, max_problems=5)
    assert "more" in str(e.value) and str(e.value).count("outside") == 5


def test_unreadable_file(tmp_path):
    with pytest.raises(PlanError, match="cannot read"):
        load_plan(tmp_path / "missing.json")
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(PlanError, match="cannot read"):
        load_plan(tmp_path / "bad.json")
