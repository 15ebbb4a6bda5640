"""The whole-body controller in the BPL executor's loop on the simulated arm of the hovering
vehicle (uvms_jax.hover.execute_plan_hovering(control="whole_body"), ExecutorWholeBody).

Oracles: the plan's gates counted by hand from its segments and their targets written out (the
docked arm's forward kinematics at each gate's waypoint, at the docked base), MuJoCo's tool site
for where the tool is, the joint table's limits for every demand put on the wire, and the hold
the executor sends when a fault stops it.
"""

from __future__ import annotations

import dataclasses
import threading

import numpy as np
import pytest

from uvms_jax import frames, hw, kin
from uvms_jax.hover import (CurrentSettings, NavigationSettings, VehicleSettings, WholeBodySettings,
                            execute_plan_hovering, executor_settings)
from uvms_jax.planfile import Plan, Segment

from test_hover_executor import PLAN_GATES
from test_hover_plan import ARM, POSE, Q_A, Q_B, _plan

TOOL_TOLERANCE_M = 0.01  # the acceptance's gate: the tool within 10 mm of its planned pose
TOOL_TOLERANCE_DEG = 2.0
THRUST_LIMIT = 40.0  # [N] the default thrusters' limit, written out
# The gates' waypoints in the plan's order (by hand): "there" Q_A, mid, Q_B, the gripper step at
# Q_B, "back" mid, Q_A.
GATE_WAYPOINTS = [Q_A, (Q_A + Q_B) / 2, Q_B, Q_B, (Q_A + Q_B) / 2, Q_A]


def _docked_tool(q) -> np.ndarray:
    v = VehicleSettings()
    T = frames.pose(frames.rot_z(POSE[3]), POSE[:3]) @ frames.rpy_pose(v.mount_xyz, v.mount_rpy)
    return (T @ np.append(np.asarray(kin.fk(kin.with_dtype(ARM.chain, np.float64), q))[:3, 3], 1.0))[:3]


@pytest.fixture
def demands(monkeypatch):
    """Every POSITION demand the executor's client is asked to send, ``(device id, value)``."""
    sent = []
    send = hw.ReachArm.set_positions

    def recording(self, pairs):
        pairs = list(pairs)
        sent.extend(pairs)
        return send(self, pairs)

    monkeypatch.setattr(hw.ReachArm, "set_positions", recording)
    return sent


def _assert_within_the_joint_table(sent) -> None:
    spec = {j.device_id: j for j in hw.joint_specs(ARM)}
    bad = [(d, v) for d, v in sent if not spec[d].contains(v)]
    assert not bad, bad[:5]


@pytest.mark.parametrize("navigation", [None, NavigationSettings()])
def test_every_gate_within_10_mm_at_0_3_m_s_over_bpl(navigation, demands):
    run = execute_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=(0.3, 0.0, 0.0)),
                                control="whole_body", navigation=navigation, tool_tolerance_m=TOOL_TOLERANCE_M,
                                tool_tolerance_deg=TOOL_TOLERANCE_DEG)
    m = run.summary()
    assert m["driver"] == "BPL executor, whole-body controller"
    assert m["status"] == "completed", m["reason"]
    assert m["gates"] == m["gates_reached"] == m["gates_tool_within_tolerance"] == PLAN_GATES
    # Where the tool is (MuJoCo's site) at each gate, against the docked arm at the gate's waypoint.
    rows = np.searchsorted(run.log.time, run.gate_times - 1e-9).clip(max=len(run.log.time) - 1)  # the last: the run's end
    errors = [np.linalg.norm(run.log.tool[r] - _docked_tool(q)) for r, q in zip(rows, GATE_WAYPOINTS)]
    assert max(errors) <= TOOL_TOLERANCE_M, errors
    np.testing.assert_allclose(errors, run.gate_tool_error, atol=1e-9)
    assert max(m["gate_tool_angle_deg"]) <= TOOL_TOLERANCE_DEG
    assert run.executed.sim.limit_violations == 0 and np.abs(run.log.thrust).max() <= THRUST_LIMIT + 1e-9
    assert m["thrust_limited_periods"] == 0 and m["joint_limited_periods"] is not None
    _assert_within_the_joint_table(demands)
    assert len(demands) >= 6 * len(run.executed.log.rows)  # every arm joint, every tick


def test_a_joint_driven_onto_its_limit_in_a_current_is_never_asked_past_it(demands):
    """Joint G (table limit 6.3 rad, the arm's float32 6.30000019) ends 1 mrad short of it while
    a current pushes the vehicle: the controller's bounds hold it, the client sends nothing past
    the table's limit, the device counts no violation."""
    q_end = Q_A.copy()
    q_end[0] = hw.joint_specs(ARM)[0].upper - 1e-3
    T = abs(q_end[0] - Q_A[0]) / 0.25  # [s] at 0.25 rad/s, half the joint's speed limit
    plan = Plan(ARM.joint_names, (Segment("to", (0.0, T / 2, T), tuple(map(tuple, (Q_A, (Q_A + q_end) / 2, q_end)))),))
    run = execute_plan_hovering(ARM, plan, POSE, VehicleSettings(), current=CurrentSettings(velocity=(0.4, 0.2, 0.0)),
                                control="whole_body")
    m = run.summary()
    assert m["status"] == "completed", m["reason"]
    assert m["joint_limited_periods"] > 0
    _assert_within_the_joint_table(demands)
    g = [v for d, v in demands if d == hw.joint_specs(ARM)[0].device_id]
    assert max(g) > q_end[0] - 1e-3  # it did go up to the limit
    assert run.executed.sim.limit_violations == 0


def test_a_fault_mid_run_stops_holding_and_hands_the_thrusters_back(monkeypatch):
    holds = []
    hold = hw.ReachArm.hold
    monkeypatch.setattr(hw.ReachArm, "hold", lambda self, *a, **k: holds.append(1) or hold(self, *a, **k))
    sim = hw.SimSettings(fault_joint="D", fault_bits=int(hw.HardwareStatus.MOTOR_DRIVER_FAULT), fault_after_s=2.0)
    run = execute_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=(0.3, 0.0, 0.0)),
                                control="whole_body", sim=sim)
    m = run.summary()
    assert m["status"] == "aborted" and "MOTOR_DRIVER_FAULT" in m["reason"] and "joint D" in m["reason"]
    assert holds and m["gates_reached"] < PLAN_GATES
    r = run.executed.result
    assert r.abort_after_s <= hw.ExecutorSettings().status_period_s + 0.1
    assert not run.world.thrust_commanded  # the station keeping holds the docked pose again
    assert run.executed.sim.limit_violations == 0


def test_the_executor_tick_must_be_the_controllers_period():
    with pytest.raises(ValueError, match="must be the whole-body controller's period"):
        execute_plan_hovering(ARM, _plan(), POSE, control="whole_body", config=hw.ExecutorSettings(rate_hz=100.0))


def test_the_executors_settings_lead_the_simulated_servo():
    s = executor_settings(WholeBodySettings(), 8.0)
    assert s.servo_lead_s == pytest.approx(1 / 8.0) and s.tool_gain < 1.0
    assert dataclasses.replace(s, servo_lead_s=0.03, tool_gain=1.0) == WholeBodySettings()
    with pytest.raises(ValueError, match="servo_gain"):
        executor_settings(WholeBodySettings(), 0.0)


def test_the_stage_runs_over_bpl_and_writes_its_plot_table_and_results(tmp_path):
    from uvms_jax.hover import HoverFilmed, run_hover, write_hover

    filmed = []  # what the film hook was given, and how many runs were done when it was called

    def film(run, label):
        filmed.append((run, label, threading.current_thread() is not threading.main_thread()))
        return HoverFilmed(None, None, label, "none made in this test")

    stage = run_hover(ARM, _plan(), POSE, VehicleSettings(), current=(0.3, 0.0, 0.0), film=film)
    assert list(stage.runs) == ["still water", "current [0.3, 0.0, 0.0] m/s",
                                "current [0.3, 0.0, 0.0] m/s, whole-body controller"]
    assert stage.main == "current [0.3, 0.0, 0.0] m/s, whole-body controller"
    # the main run was filmed once, in a thread of its own
    assert [(r, label, other) for r, label, other in filmed] == [(stage.runs[stage.main], stage.main, True)]
    res, table, notes = write_hover(stage, tmp_path, docked={"status": "completed", "gates": PLAN_GATES})
    assert (tmp_path / "hover.png").stat().st_size > 10_000 and not (tmp_path / "hover.mp4").exists()
    assert res["driver"] == "BPL executor, whole-body controller" and res["status"] == "completed"
    assert res["gates_tool_within_tolerance"] == res["gates"] == PLAN_GATES
    assert len(res["gate_tool_error_m"]) == PLAN_GATES and res["joint_limited_periods"] is not None
    plain = res["runs"]["current [0.3, 0.0, 0.0] m/s"]
    removes = res["coordination_removes"]["max_gate_tool_error_m"]
    assert removes == pytest.approx(1.0 - res["max_gate_tool_error_m"] / plain["max_gate_tool_error_m"]) and removes > 0.5
    assert len(table.splitlines()) == 2 + 4 and "docked (hw stage)" in table and len(notes) == 2
    assert notes[1] == "No video of the hovering run: none made in this test." and "video_frames" not in res
    still_only = run_hover(ARM, _plan(), POSE, VehicleSettings(), whole_body=None)
    assert list(still_only.runs) == ["still water"] and "coordination_removes" not in still_only.results()
