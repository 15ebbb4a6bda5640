"""ROS-shaped trajectories (``trajectory_msgs/JointTrajectory``): export, import, files, CLI."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from _hw_helpers import BRAVO, Q0, Q1, short_plan
from uvms_jax.hw import check_plan
from uvms_jax.hw.cli import main
from uvms_jax.planfile import (PlanError, from_joint_trajectory, load_plan, parse_plan, plan_to_dict, save_plan,
                               to_joint_trajectory)

ROOT = Path(__file__).parents[2]
GRIPPER = BRAVO.gripper  # the jaws A: 0 … 35 mm at 0.1 m/s
EXAMPLE = ROOT / "examples" / "thesis_plan.json"
TIME_ATOL = 2e-9  # time_from_start keeps nanoseconds: one rounding on the way out, one on the way back
JAWS_STEP_S = 0.035 / 0.1  # the jaws' full travel at their speed limit (docs/theory.md §1.3)
JAWS_ATOL_MM = 1e-9  # mm → m → mm in floating point


def events(plan):
    """What the executor does, segment structure aside: ``("move", q, dt)`` between distinct
    waypoints and ``("jaws", mm)``; the oracle for round trips, computed from the plan alone."""
    out, q_prev = [], None
    for s in plan.segments:
        for k, q in enumerate(s.q):
            if q_prev is None:
                out.append(("start", q, 0.0))
            elif k > 0:
                out.append(("move", q, s.t[k] - s.t[k - 1]))
            q_prev = q
        if s.jaws_mm is not None:
            out.append(("jaws", s.jaws_mm))
    return out


def assert_same_motion(a, b):
    ea, eb = events(a), events(b)
    assert a.joint_names == b.joint_names and len(ea) == len(eb)
    for x, y in zip(ea, eb):
        assert x[0] == y[0]
        if x[0] == "jaws":
            assert x[1] == pytest.approx(y[1], abs=JAWS_ATOL_MM)
        else:
            assert x[1] == y[1] and x[2] == pytest.approx(y[2], abs=TIME_ATOL)


def seconds(d):
    return d["sec"] + d["nanosec"] * 1e-9


def test_thesis_plan_round_trip():
    plan = load_plan(EXAMPLE)
    jt = to_joint_trajectory(plan, gripper=GRIPPER)
    assert jt["joint_names"] == list("GFEDCBA")
    n_moves = sum(1 for e in events(plan) if e[0] == "move")
    n_jaws = sum(1 for s in plan.segments if s.jaws_mm is not None)
    assert len(jt["points"]) == 1 + n_moves + n_jaws
    times = [seconds(p["time_from_start"]) for p in jt["points"]]
    assert times[0] == 0 and all(b > a for a, b in zip(times, times[1:]))
    planned = sum(s.t[-1] for s in plan.segments if s.t)
    assert times[-1] == pytest.approx(planned + n_jaws * JAWS_STEP_S, abs=1e-6)
    for p in jt["points"]:
        assert len(p["positions"]) == len(p["velocities"]) == 7 and set(p["velocities"]) == {0.0}
    # the jaws: the first step's opening from the start, then every step's opening, in metres
    jaws = [s.jaws_mm for s in plan.segments if s.jaws_mm is not None]
    assert jt["points"][0]["positions"][6] == pytest.approx(jaws[0] / 1000)
    assert jt["points"][-1]["positions"][6] == pytest.approx(jaws[-1] / 1000)

    back = from_joint_trajectory(jt, GRIPPER)
    assert_same_motion(plan, back)
    assert to_joint_trajectory(back, gripper=GRIPPER) == jt  # a plan read from a trajectory writes the same trajectory
    # the executor's view is unchanged: same checks pass, same estimated motion time
    s0, s1 = check_plan(plan, BRAVO), check_plan(back, BRAVO)
    assert s1.n_gripper_steps == s0.n_gripper_steps and s1.estimated_s == pytest.approx(s0.estimated_s)


@pytest.mark.parametrize("suffix", [".yaml", ".yml", ".json"])
def test_files_by_suffix(tmp_path, suffix):
    plan = short_plan()
    path = tmp_path / f"traj{suffix}"
    save_plan(plan, path, joint_trajectory=True, jaws_start_mm=20.0, gripper=GRIPPER)
    text = path.read_text()
    obj = json.loads(text) if suffix == ".json" else yaml.safe_load(text)
    assert obj == to_joint_trajectory(plan, 20.0, GRIPPER)
    assert obj["points"][0]["positions"][-1] == pytest.approx(0.020)
    assert_same_motion(plan, load_plan(path, GRIPPER))
    # plan.json's own format still round-trips through save_plan
    save_plan(plan, tmp_path / f"plan{suffix}")
    assert load_plan(tmp_path / f"plan{suffix}") == plan


def test_plan_without_gripper_has_no_jaws_joint():
    plan = parse_plan({"joint_names": list("GFEDCB"),
                       "segments": [{"t": [0.0, 1.0, 2.5], "q": [Q0, Q1, Q0]}]})
    jt = to_joint_trajectory(plan, gripper=GRIPPER)
    assert jt["joint_names"] == list("GFEDCB")
    assert [seconds(p["time_from_start"]) for p in jt["points"]] == [0.0, 1.0, 2.5]
    assert from_joint_trajectory(jt) == parse_plan({"joint_names": list("GFEDCB"), "segments": [
        {"name": "points 0-2", "t": [0.0, 1.0, 2.5], "q": [Q0, Q1, Q0]}]})


def test_time_origin_and_header_are_ignored():
    jt = to_joint_trajectory(short_plan(), gripper=GRIPPER)
    jt["header"] = {"frame_id": "base_link", "stamp": {"sec": 5, "nanosec": 0}}
    for p in jt["points"]:
        p["time_from_start"]["sec"] += 3
    assert_same_motion(short_plan(), from_joint_trajectory(jt, GRIPPER))


def test_dwells_of_an_arm_without_gripper_round_trip():
    """A plan without gripper steps (an arm without a gripper holds still instead) stands still
    between two motions: written as a point that repeats the positions later, read back as the
    same motion with no gripper known."""
    plan = parse_plan({"joint_names": list("GFEDCB"), "segments": [
        {"t": [0.0, 1.0], "q": [Q0, Q1]}, {"name": "close (dwell: no gripper)", "t": [0.0, 2.5], "q": [Q1, Q1]},
        {"t": [0.0, 1.0], "q": [Q1, Q0]}]})
    jt = to_joint_trajectory(plan)
    assert jt["joint_names"] == list("GFEDCB")
    assert [seconds(p["time_from_start"]) for p in jt["points"]] == pytest.approx([0.0, 1.0, 3.5, 4.5], abs=TIME_ATOL)
    assert jt["points"][1]["positions"] == jt["points"][2]["positions"] == list(Q1)
    assert_same_motion(plan, from_joint_trajectory(jt))


def test_unwritable_plans_are_refused():
    def plan(*segments):
        return parse_plan({"joint_names": list("GFEDCB"), "segments": list(segments)})

    with pytest.raises(PlanError, match="starts with a gripper step"):
        to_joint_trajectory(plan({"gripper": {"jaws_mm": 5.0}}, {"t": [0.0, 1.0], "q": [Q0, Q1]}), gripper=GRIPPER)
    with pytest.raises(PlanError, match="stands still"):  # with gripper steps, that reads as one
        to_joint_trajectory(plan({"t": [0.0, 1.0, 2.0], "q": [Q0, Q1, Q1]}, {"gripper": {"jaws_mm": 5.0}}),
                            gripper=GRIPPER)
    with pytest.raises(PlanError, match="does not repeat the previous"):
        to_joint_trajectory(plan({"t": [0.0, 1.0], "q": [Q0, Q1]}, {"t": [0.0, 1.0], "q": [Q0, Q1]}))
    with pytest.raises(PlanError, match="increase strictly"):
        to_joint_trajectory(plan({"t": [0.0, 0.0], "q": [Q0, Q1]}))
    with pytest.raises(PlanError, match=r"jaws_start_mm 40.0 outside \[0.0, 35.0\] mm"):
        to_joint_trajectory(short_plan(), jaws_start_mm=40.0, gripper=GRIPPER)


def _with(mutate):
    jt = to_joint_trajectory(short_plan(), gripper=GRIPPER)
    mutate(jt)
    return jt


@pytest.mark.parametrize("mutate, message", [
    (lambda jt: jt.update(extra=1), r"unknown keys \['extra'\]"),
    (lambda jt: jt.update(joint_names=["G", "G"]), "distinct names"),
    (lambda jt: jt.update(points=[]), "non-empty list"),
    (lambda jt: jt["points"][1]["positions"].pop(), r"points\[1\].positions: 6 values for 7 joints"),
    (lambda jt: jt["points"][1]["velocities"].pop(), r"points\[1\].velocities: 6 values for 7 joints"),
    (lambda jt: jt["points"][1]["positions"].__setitem__(0, "x"), "expected numbers"),
    (lambda jt: jt["points"][1].update(time_from_start={"sec": 1.5, "nanosec": 0}), "sec must be an integer"),
    (lambda jt: jt["points"][1].update(time_from_start={"secs": 1, "nsecs": 0}), "expected {sec: int"),
    (lambda jt: jt["points"][1].update(time_from_start={"sec": 0, "nanosec": 0}), "later than the previous"),
    (lambda jt: jt["points"][1].update(speed=[0]), r"unknown keys \['speed'\]"),
])
def test_malformed_trajectories(mutate, message):
    with pytest.raises(PlanError, match=message):
        from_joint_trajectory(_with(mutate), GRIPPER)


def test_load_detects_format_and_reports_bad_files(tmp_path):
    (tmp_path / "bad.yaml").write_text("points: [unclosed\n")
    with pytest.raises(PlanError, match="cannot read plan"):
        load_plan(tmp_path / "bad.yaml")
    (tmp_path / "t.json").write_text(json.dumps(_with(lambda jt: jt["points"][0].pop("positions"))))
    with pytest.raises(PlanError, match=r"points\[0\].positions: expected a list of numbers"):
        load_plan(tmp_path / "t.json")
    (tmp_path / "p.yaml").write_text(yaml.safe_dump(plan_to_dict(short_plan())))
    assert load_plan(tmp_path / "p.yaml") == short_plan()


def test_cli_export_then_run(tmp_path, capsys):
    ros = tmp_path / "thesis.yaml"
    assert main(["export", str(EXAMPLE), "--ros", str(ros)]) == 0
    assert_same_motion(load_plan(EXAMPLE), load_plan(ros, GRIPPER))
    assert main(["run", str(ros), "--dry-run"]) == 0
    assert "plan ok: " in capsys.readouterr().err
    # refused exports exit 2 with one line naming the problem
    assert main(["export", str(EXAMPLE), "--ros", str(tmp_path / "x.yaml"), "--jaws-start", "99"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["uvms-hw: jaws_start_mm 99.0 outside [0.0, 35.0] mm"]
    assert not (tmp_path / "x.yaml").exists()


def test_cli_runs_a_trajectory_on_the_sim(tmp_path, capsys):
    ros = tmp_path / "short.json"
    save_plan(short_plan(), ros, joint_trajectory=True, gripper=GRIPPER)
    out = tmp_path / "out"
    assert main(["run", str(ros), "--sim", "--no-plot", "--out", str(out)]) == 0
    res = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert res["ok"] and res["max_gate_error_rad"] <= 0.01 and res["plan"] == str(ros)
