"""Any Reach arm: the hardware path takes its joints, ids and model from a Robot (the Reach
Alpha 5 beside the Bravo 7), and a plan runs only on the arm it was made for."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from _hw_helpers import BRAVO, Recorder, short_plan
from uvms_jax import planfile
from uvms_jax.hw import (ExecutorSettings, PacketID, PacketReader, PlanError, ReachArm, SimArm, SimSettings, check_arm,
                         check_plan, device_ids, joint_specs, run_plan, sim_spec)
from uvms_jax.hw.cli import main
from uvms_jax.robot import load_arm

ALPHA = load_arm("alpha5")
A0 = [1.0, 1.5, 1.5, 1.5]  # axis_e … axis_b [rad]
A1 = [1.2, 1.3, 1.7, 1.6]


def alpha_plan(arm=ALPHA.record()):
    """Out and back on the Alpha 5 with a jaws step (mm) in between; 0.25 rad/s at most."""
    return planfile.Plan(ALPHA.joint_names, (
        planfile.Segment("out", (0.0, 0.8), (tuple(A0), tuple(A1)), 10.0),
        planfile.Segment("back", (0.0, 0.8), (tuple(A1), tuple(A0))),
    ), arm=arm)


def test_alpha5_joint_table_is_its_card():
    specs = joint_specs(ALPHA)
    assert [(j.name, j.device_id, j.unit) for j in specs] == [
        ("axis_e", 5, "rad"), ("axis_d", 4, "rad"), ("axis_c", 3, "rad"), ("axis_b", 2, "rad"), ("axis_a", 1, "mm")]
    # limits as the URDF writes them (not the float32 above them), the jaws' metres as mm
    assert [(j.lower, j.upper) for j in specs] == [(0.0, 6.1), (0.0, 3.49), (0.0, 3.22), (0.0, 3.22), (0.0, 15.0)]
    assert [j.max_velocity for j in specs[:-1]] == [0.5] * 4


def test_alpha5_runs_a_plan_over_bpl_on_the_simulated_arm():
    run = run_plan(alpha_plan(), ALPHA, link="loopback")
    assert run.ok, run.result.reason
    # every waypoint (a segment's first repeats the previous gate) and the jaws step passed its gate
    assert [(g.segment, g.waypoint) for g in run.result.gates] == [(0, 0), (0, 1), (0, -1), (1, 1)]
    assert run.result.max_gate_error_rad <= ExecutorSettings().gate_threshold_rad
    assert run.result.max_gate_error_mm <= ExecutorSettings().gate_threshold_mm
    assert run.sim.limit_violations == 0
    assert run.log.joint_names == ALPHA.actuators


def test_alpha5_speaks_to_its_own_device_ids():
    """What goes on the wire addresses the Alpha's devices 0x05 … 0x01 (or broadcast) only,
    and the simulated Alpha answers as them."""
    from uvms_jax.hw import Executor, LoopbackTransport, SimLink, VirtualClock

    clock = VirtualClock()
    arm = SimArm(ALPHA, SimSettings(), [*A0, 0.0])
    transport = LoopbackTransport(SimLink(arm), clock)
    client = ReachArm(transport, joint_specs(ALPHA), clock=clock.now)
    assert client.read_position_limits()[1] == pytest.approx((0.0, 15.0))  # the jaws [mm]
    res = Executor(client, ExecutorSettings(), sleep=clock.sleep).run(alpha_plan())
    assert res.ok, res.reason
    reader = PacketReader()
    sent = [p for d in transport.sent for p in reader.feed(d)]
    demanded = {p.device_id for p in sent if p.packet_id in (PacketID.POSITION, PacketID.VELOCITY)}
    assert demanded == {5, 4, 3, 2, 1}
    assert {p.device_id for p in sent} <= {5, 4, 3, 2, 1, 0xFF}
    np.testing.assert_allclose(arm.positions()[:4], A0, atol=0.01)


def test_a_plan_for_another_arm_is_refused_naming_both():
    bravo_plan = dataclasses.replace(short_plan(), arm=BRAVO.record())
    with pytest.raises(PlanError) as err:
        run_plan(bravo_plan, ALPHA)
    msg = str(err.value)
    assert "\n" not in msg and "'bravo7'" in msg and "'alpha_5'" in msg
    with pytest.raises(PlanError, match="'alpha_5'.*'bravo7'"):
        run_plan(alpha_plan(), BRAVO)
    # the same name and joints, another description: refused too
    forged = dict(ALPHA.record(), sha256="0" * 64)
    with pytest.raises(PlanError, match="made for arm 'alpha_5'.*sha256 000000000000.*not for arm 'alpha_5'"):
        run_plan(alpha_plan(arm=forged), ALPHA)
    # no arm record: it runs if, and only if, its joints are the robot's
    with pytest.raises(PlanError, match=r"joint_names \['G'.*must be those of arm 'alpha_5'"):
        check_arm(short_plan(), ALPHA)
    check_arm(short_plan(), BRAVO)
    assert run_plan(alpha_plan(arm=None), ALPHA).ok


def test_limits_are_the_robots():
    obj = planfile.plan_to_dict(alpha_plan())
    obj["segments"][0]["gripper"] = {"jaws_mm": 20.0}  # the Bravo's jaws open to 35 mm, the Alpha's to 15
    with pytest.raises(PlanError, match=r"jaws 20.0 mm outside \[0.0, 15.0\]"):
        check_plan(planfile.parse_plan(obj), ALPHA)


def test_an_arm_without_hardware_profile_runs_only_simulated():
    bare = dataclasses.replace(ALPHA, hardware=None)
    assert device_ids(bare) == {"axis_e": 5, "axis_d": 4, "axis_c": 3, "axis_b": 2, "axis_a": 1}
    assert run_plan(alpha_plan(arm=None), bare).ok
    client = ReachArm(Recorder(), joint_specs(bare))
    with pytest.raises(ValueError, match="no hardware profile"):
        run_plan(alpha_plan(arm=None), bare, link=client)


def test_an_arm_without_gripper_runs_its_moves_and_dwells():
    """No gripper (a suction cup, a tool changer, no tool): the joint table is the arm's joints
    alone, a dwell (the arm holding still for a planned time) passes its gate after that time,
    and a plan with a jaws step is refused before anything moves."""
    import mujoco

    bare = dataclasses.replace(ALPHA, gripper=None, hardware=None)
    assert [j.name for j in joint_specs(bare)] == list(ALPHA.joint_names)
    dwell_s = 1.5
    plan = planfile.Plan(bare.joint_names, (
        planfile.Segment("out", (0.0, 0.8), (tuple(A0), tuple(A1))),
        planfile.Segment("hold (dwell: no gripper)", (0.0, dwell_s), (tuple(A1), tuple(A1))),
        planfile.Segment("back", (0.0, 0.8), (tuple(A1), tuple(A0))),
    ), arm=bare.record())
    run = run_plan(plan, bare, link="loopback")
    assert run.ok, run.result.reason
    assert [(g.segment, g.waypoint) for g in run.result.gates] == [(0, 0), (0, 1), (1, 1), (2, 1)]
    assert run.result.max_gate_error_rad <= ExecutorSettings().gate_threshold_rad
    assert np.isnan(run.result.max_gate_error_mm) and run.log.joint_names == bare.joint_names
    # the dwell: from the gate at A1 to the next gate, the arm stood still for at least dwell_s
    ticks = [row for row in run.log.rows if row[1] == 1]
    assert ticks[-1][0] - ticks[0][0] >= dwell_s
    assert mujoco.mj_name2id(SimArm(bare).model, mujoco.mjtObj.mjOBJ_JOINT, "axis_a") == -1
    with pytest.raises(PlanError, match=r"segment 0 \(out\): a gripper step \(10.0 mm\), but the arm has no gripper"):
        run_plan(alpha_plan(arm=bare.record()), bare)


def test_arm_without_mass_properties_is_simulated_weightless():
    """The Alpha 5's description has no inertials: every link is gravity compensated and
    nothing floats, so the arm holds its pose with no load on the drives."""
    import mujoco

    model = sim_spec(ALPHA).compile()
    assert np.all(model.body_gravcomp[1:] == 1.0)
    arm = SimArm(ALPHA, SimSettings(base_rpy=(np.pi, 0.0, 0.0)), [*A0, 5.0])
    assert arm._buoy_ids.size == 0
    arm.step_to(1.0)
    np.testing.assert_allclose(arm.positions()[:4], A0, atol=1e-4)
    assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "axis_a") >= 0
    bravo = sim_spec(BRAVO).compile()  # the Bravo carries its manufacturer's masses
    assert bravo.body_gravcomp[bravo.body("link_G").id] == 0.0


def test_plan_records_its_arm_and_old_plans_still_load(tmp_path):
    plan = alpha_plan()
    obj = planfile.plan_to_dict(plan)
    assert obj["arm"]["name"] == "alpha_5" and obj["arm"]["gripper"]["joint"] == "axis_a"
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(obj))
    assert planfile.load_plan(path) == plan
    assert planfile.parse_plan(planfile.plan_to_dict(short_plan())).arm is None
    bad = dict(obj, arm=dict(obj["arm"], joint_names=list("GFED")))
    with pytest.raises(PlanError, match="differ from plan.joint_names"):
        planfile.parse_plan(bad)
    with pytest.raises(PlanError, match="plan.arm: expected an object with keys"):
        planfile.parse_plan(dict(obj, arm={"name": "x"}))


def test_joint_trajectory_takes_the_jaws_from_the_arm():
    """The Alpha's jaws are ``axis_a``, 15 mm at 0.05 m/s (a 0.3 s step); a plan with jaws
    steps and no gripper known cannot be written."""
    jt = planfile.to_joint_trajectory(alpha_plan())
    assert jt["joint_names"] == [*ALPHA.joint_names, "axis_a"]
    t = [p["time_from_start"]["sec"] + p["time_from_start"]["nanosec"] * 1e-9 for p in jt["points"]]
    assert t == pytest.approx([0.0, 0.8, 1.1, 1.9])
    back = planfile.from_joint_trajectory(jt, ALPHA)
    assert back.arm == ALPHA.record() and [s.jaws_mm for s in back.segments] == [None, 10.0, None]
    assert planfile.from_joint_trajectory(jt).joint_names == (*ALPHA.joint_names, "axis_a")  # no gripper known
    with pytest.raises(PlanError, match="no gripper is known"):
        planfile.to_joint_trajectory(alpha_plan(arm=None))


def test_cli_robot_option(tmp_path, capsys):
    path = tmp_path / "alpha.json"
    path.write_text(json.dumps(planfile.plan_to_dict(alpha_plan())))
    assert main(["run", str(path), "--robot", "alpha5", "--dry-run"]) == 0
    assert "plan ok: 2 segments" in capsys.readouterr().err
    assert main(["run", str(path), "--dry-run"]) == 2  # the default arm is the Bravo 7
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'alpha_5'" in err[0] and "'bravo7'" in err[0]
    ros = tmp_path / "alpha.yaml"
    assert main(["export", str(path), "--robot", "alpha5", "--ros", str(ros)]) == 0
    assert planfile.load_plan(ros, ALPHA).segments[1].jaws_mm == 10.0
    assert main(["run", str(path), "--robot", "no_such_arm", "--dry-run"]) == 2
    assert "no_such_arm" in capsys.readouterr().err
