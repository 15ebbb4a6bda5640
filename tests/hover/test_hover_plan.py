"""A plan replayed on the hovering vehicle (uvms_jax.hover.run_plan_hovering).

Oracles: the gate times and targets written out from the plan's segment times by hand; the
docked tool position from the arm's forward kinematics at the docked base, which a vehicle held
still must reproduce; and the ordering a current must produce (more drift than still water).
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_jax import frames, kin
from uvms_jax.hover import (ControllerSettings, CurrentSettings, VehicleSettings, level_attitude, plan_targets,
                            run_plan_hovering)
from uvms_jax.planfile import Plan, Segment
from uvms_jax.robot import load_arm

ARM = load_arm("bravo7")
Q_A = (ARM.lower + ARM.upper) / 2
Q_B = Q_A + np.array([0.3, -0.2, 0.2, 0.0, 0.3, 0.0])
POSE = np.array([0.1, -0.2, 1.2, 0.4])  # [m, rad] a docked vehicle pose


def _plan() -> Plan:
    move = lambda a, b, name: Segment(name, (0.0, 1.0, 2.0), tuple(map(tuple, (a, (a + b) / 2, b))))  # noqa: E731
    return Plan(ARM.joint_names, (move(Q_A, Q_B, "there"), Segment("close", (), (), 0.0), move(Q_B, Q_A, "back")))


def test_targets_follow_the_segments_and_dwell_at_the_gates():
    targets, gates, duration = plan_targets(_plan(), dwell_s=0.5, gripper_s=1.0)
    # there: 0–2 s, gate at 2.5 s; close: 2.5–3.5 s; back: 3.5–5.5 s, gate at 6.0 s.
    np.testing.assert_allclose(gates, [2.5, 6.0])
    assert duration == pytest.approx(6.0)
    np.testing.assert_allclose(targets(0.0), Q_A)
    np.testing.assert_allclose(targets(1.5), Q_A + 0.75 * (Q_B - Q_A))
    np.testing.assert_allclose(targets(3.0), Q_B)  # dwelling, then the gripper step
    np.testing.assert_allclose(targets(4.5), (Q_A + Q_B) / 2)
    np.testing.assert_allclose(targets(10.0), Q_A)


def test_a_plan_for_other_joints_is_refused():
    other = Plan(("a", "b"), (Segment("x", (0.0,), ((0.0, 0.0),)),))
    with pytest.raises(ValueError, match="the plan moves"):
        run_plan_hovering(ARM, other, POSE)


@pytest.fixture(scope="module")
def runs():
    return {v: run_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=(v, 0.0, 0.0)))
            for v in (0.0, 0.4)}


def test_the_docked_reference_is_the_arms_forward_kinematics(runs):
    """At the start the vehicle is at the docked pose: the tool is where FK at the docked base
    puts it (the replay's reference, computed here from the mount by hand)."""
    log = runs[0.0].log
    v = VehicleSettings()
    T = frames.pose(frames.rot_z(POSE[3]), POSE[:3]) @ frames.rpy_pose(v.mount_xyz, v.mount_rpy)
    p = T @ np.append(np.asarray(kin.fk(ARM.chain, log.q[0]))[:3, 3], 1.0)
    np.testing.assert_allclose(log.tool[0], p[:3], atol=1e-6)
    assert runs[0.0].tool_error[0] < 1e-6 and runs[0.0].drift[0] < 1e-9


def test_still_water_reaches_every_gate_and_a_current_drifts_more(runs):
    still, current = runs[0.0].summary(), runs[0.4].summary()
    assert still["status"] == "completed" and still["gates_reached"] == still["gates"] == 2
    assert 0.0 < still["max_drift_m"] < current["max_drift_m"]
    assert current["max_tool_error_m"] > still["max_tool_error_m"]
    assert current["peak_thrust_N"] > still["peak_thrust_N"]
    assert still["joint_limited_periods"] is None  # the arm replays its targets: no bounds of its own
    saturated = int(np.sum(np.abs(runs[0.4].log.thrust[1:]).max(axis=-1) >= 40.0 - 1e-9))  # one 40 N limit for all
    assert current["thrust_limited_periods"] == saturated
    if current["status"] != "completed":  # held at a gate, and says why
        assert current["reason"].startswith("gate ")


def test_levelling_moment_is_the_pd_on_roll_and_pitch():
    R = frames.rpy_matrix([0.1, -0.05, 0.7])
    m = level_attitude(R, np.array([0.2, -0.1, 0.3]), 600.0, 110.0)
    np.testing.assert_allclose(m, [-600 * 0.1 - 110 * 0.2, 600 * 0.05 + 110 * 0.1, 0.0], atol=1e-9)


def test_levelling_keeps_the_vehicle_flatter_than_the_hydrostatics_alone(runs):
    free = run_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), ControllerSettings(level_kp=0.0, level_kd=0.0))
    assert runs[0.0].summary()["max_tilt_deg"] < 0.5 * free.summary()["max_tilt_deg"]
    assert runs[0.0].summary()["max_tool_error_m"] < free.summary()["max_tool_error_m"]


def test_the_whole_body_controller_keeps_the_tool_on_its_path(runs):
    """The whole-body controller keeps the tool nearer the docked path than the PID with the arm
    replaying its waypoints, in the same current: every gate within 10 mm and the stated angle,
    the arm's targets within the joint limits, thrusts within theirs (the rates' bounds: test_hover_wbc)."""
    run = run_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=(0.4, 0.0, 0.0)),
                            control="whole_body")
    plain, wbc = runs[0.4].summary(), run.summary()
    assert wbc["coordinated"] and not plain["coordinated"] and wbc["driver"] == "whole-body controller"
    assert wbc["status"] == "completed" and wbc["gates_reached"] == wbc["gates"] == 2
    assert wbc["max_gate_tool_error_m"] < min(0.01, 0.5 * plain["max_gate_tool_error_m"])
    assert max(wbc["gate_tool_angle_deg"]) < wbc["tool_tolerance_deg"] == 2.0
    assert len(wbc["gate_tool_error_m"]) == 2
    log = run.log
    assert np.all((log.q_target >= ARM.lower - 1e-9) & (log.q_target <= ARM.upper + 1e-9))
    assert np.all(np.abs(log.thrust) <= 40.0 + 1e-9)


def test_a_current_beyond_the_thrusters_holds_the_run_within_the_limits():
    """1.2 m/s across the hull needs about 3 × the thrust the layout has: the thrusters sit at their
    limit, never beyond, the arm's targets stay within the joint limits, and the run is held at
    its first gate with the reason."""
    run = run_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=(0.0, 1.2, 0.0)),
                            control="whole_body")
    status, reason = run.status
    assert status == "held" and reason.startswith("gate 1 of 2") and "thrusters were at their limit" in reason
    assert run.thrust_limited_periods > 0 and run.joint_limited_periods > 0
    assert np.all(np.abs(run.log.thrust) <= 40.0 + 1e-9)
    assert np.abs(run.log.thrust).max() == pytest.approx(40.0)
    assert np.all((run.log.q_target >= ARM.lower - 1e-9) & (run.log.q_target <= ARM.upper + 1e-9))


def test_the_feed_forward_alone_keeps_the_vehicle_nearer(runs):
    """The PID with the feed-forward (the arm replaying its waypoints) drifts less than the PID
    alone in the same current, and its gates are judged as the PID's (joints and tool)."""
    ff = run_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=(0.4, 0.0, 0.0)),
                           control="feed_forward")
    plain, fed = runs[0.4].summary(), ff.summary()
    assert not fed["coordinated"] and fed["joint_limited_periods"] is None and "gate_tool_angle_deg" not in fed
    assert fed["max_drift_m"] < 0.5 * plain["max_drift_m"]
    np.testing.assert_allclose(ff.log.q_target[1:], runs[0.4].log.q_target[1:], atol=1e-12)  # the same replay


def test_an_unknown_control_is_refused():
    with pytest.raises(ValueError, match="control must be"):
        run_plan_hovering(ARM, _plan(), POSE, control="replay")
