"""The hardware stage: ``run_plan`` on each kind of link, ``write_run``'s files; the Bravo 7 data."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from _hw_helpers import BRAVO, BRAVO7, JAWS, DeviceID, Q0, SimRun, bravo7_client, short_plan
from uvms_jax import bravo7
from uvms_jax.hw import (ExecutorSettings, HwRun, PlanError, SimArm, SimSettings, SimServer,
                         UdpTransport, plan_to_dict, parse_plan, run_plan, run_report, sim_spec, write_run)

REPORT_KEYS = {"ok", "status", "reason", "gates", "max_gate_error_rad", "max_gate_error_mm", "grips", "duration_s",
               "abort_after_s", "ticks", "link_timeouts", "rejected_states", "wall_s", "link"}


def test_loopback_run_is_the_executor_run():
    """run_plan on the loopback link is exactly the hand-wired executor on a virtual clock."""
    run = run_plan(short_plan(), BRAVO)
    assert isinstance(run, HwRun) and run.ok and run.link == "loopback"
    ref = SimRun().executor.run(short_plan())
    assert run.result.gates == ref.gates and run.result.ticks == ref.ticks
    assert run.result.duration_s == ref.duration_s
    assert run.sim is not None and (run.sim.limit_violations, run.sim.dropped, run.sim.corrupted) == (0, 0, 0)
    assert run.check.n_segments == 2 and run.check.n_gripper_steps == 1
    assert len(run.log.rows) == run.result.ticks


def test_write_run_files_and_report(tmp_path):
    run = run_plan(short_plan(), BRAVO, sim=SimSettings(drop=0.02, seed=3))
    out = tmp_path / "a" / "b"
    report = write_run(run, out, plan_path="plan.json")
    assert {p.name for p in out.iterdir()} == {"run.csv", "run.png", "results.json"}
    assert json.loads((out / "results.json").read_text()) == report
    assert set(report) == REPORT_KEYS | {"plan", "out", "sim"}
    assert report["plan"] == "plan.json" and report["out"] == str(out) and report["link"] == "loopback"
    assert report["sim"]["dropped"] == run.sim.dropped > 0
    assert report["abort_after_s"] is None and report["duration_s"] == round(run.result.duration_s, 3)
    header = (out / "run.csv").read_text().splitlines()[0].split(",")
    assert header[:4] == ["t_s", "segment", "waypoint", "phase"] and len(header) == 4 + 2 * len(BRAVO7)
    write_run(run, tmp_path / "np", plot=False)
    assert not (tmp_path / "np" / "run.png").exists()


def test_aborted_run_is_a_result_not_an_exception(tmp_path):
    run = run_plan(short_plan(), BRAVO, config=ExecutorSettings(gate_timeout_s=0.5), sim=SimSettings(stuck_joint="B"))
    assert not run.ok and "joint B" in run.result.reason
    report = run_report(run)
    assert not report["ok"] and report["abort_after_s"] is not None and "out" not in report
    assert json.loads(json.dumps(report)) == report  # plain JSON: no NaN


def test_refused_plan_and_bad_link_raise_before_anything_starts():
    obj = plan_to_dict(short_plan())
    obj["segments"][0]["q"][1][0] = 9.0
    with pytest.raises(PlanError, match="joint G = 9.0000 rad outside"):
        run_plan(parse_plan(obj), BRAVO, link="udp")
    with pytest.raises(ValueError, match="link must be one of"):
        run_plan(short_plan(), BRAVO, link="serial")


def test_udp_simulated_and_client_links():
    """``"udp"`` serves a simulated arm; a client link is the caller's (a real arm's path)."""
    run = run_plan(short_plan(), BRAVO, link="udp")
    assert run.ok, run.result.reason
    assert run.link == "udp" and run.sim.limit_violations == 0
    with SimServer(SimArm(BRAVO, SimSettings(), [*Q0, 0.0])) as server:
        with bravo7_client(UdpTransport(*server.address)) as client:
            run = run_plan(short_plan(), BRAVO, link=client)
    assert run.ok, run.result.reason
    assert run.sim is None and run.link == f"udp 127.0.0.1:{server.address[1]}"
    assert "sim" not in run_report(run)


def test_hw_joints_are_the_bravo7_module():
    """Limits, speeds and device ids come from uvms_jax.bravo7 (the jaws converted to mm)."""
    for spec, joint in zip(BRAVO7, bravo7.JOINTS, strict=True):
        scale = 1e3 if joint.kind == "prismatic" else 1.0
        assert (spec.name, int(spec.device_id)) == (joint.name, joint.device_id)
        assert (spec.lower, spec.upper) == (joint.lower * scale, joint.upper * scale)
        if spec is not JAWS:
            assert spec.max_velocity == joint.velocity
        assert DeviceID[joint.name] == joint.device_id


def test_sim_model_geometry_is_the_bravo7_module():
    """The simulator built on the robot's MuJoCo model: joint origins, axes, limits and link
    radius as in uvms_jax.bravo7 (origins to the float32 of the robot's chain)."""
    import mujoco

    model = sim_spec(BRAVO).compile()
    data = mujoco.MjData(model)
    for joint in bravo7.ARM_JOINTS:
        body = model.body(f"link_{joint.name}")
        np.testing.assert_allclose(body.pos, joint.xyz, atol=1e-7)
        j = model.joint(joint.name)
        np.testing.assert_allclose(model.jnt_range[j.id], (joint.lower, joint.upper))
        np.testing.assert_allclose(model.geom_size[model.body_geomadr[body.id], 0], 0.04)  # the card's radius
    # URDF rpy (0, π, 0) on joint B: its axis −z points along +z of the world at q = 0 when the
    # chain above is straight up to it (D's yaw π flips only x and y).
    mujoco.mj_kinematics(model, data)
    axis_b = data.xaxis[model.joint("B").id]
    np.testing.assert_allclose(axis_b, [0.0, 0.0, 1.0], atol=1e-5)
    jaws = model.body("jaws")  # the jaws' slide hangs at the tool frame
    np.testing.assert_allclose(jaws.pos, bravo7.TOOL_XYZ, atol=1e-7)
    assert model.jnt_range[model.joint("A").id][1] == pytest.approx(bravo7.JAWS.upper)
    assert model.nu == 2 * len(bravo7.JOINTS) and math.isclose(model.opt.timestep, 0.002)  # velocity + integral
