"""The simulated arm's base orientation (``SimSettings.base_rpy``): gravity and buoyancy follow
the world's z, so a base hanging under a vehicle carries the negated loads of an upright one and
still runs a plan through every gate. (The holding loads against an independent statics sum for
hanging and tilted bases are in test_hw_sim_dynamics.py.)"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from _hw_helpers import BRAVO, Q0, SimRun, assert_within_limits, short_plan
from uvms_jax.hw import ExecutorSettings, HwSettings, SimArm, SimSettings, plan_to_dict
from uvms_jax.hw import cli
from uvms_jax.settings import from_mapping

HANGING = (math.pi, 0.0, 0.0)
SETTLE_S = 0.3  # simulated time at rest before the currents are read [s]
SATURATED_MA = 0.9 * 4000.0  # near the drives' current limit: a pose they may not hold [mA]


def holding_currents(config, q):
    """(7,) currents [mA] of the arm at rest at ``q`` (G…B [rad], jaws [mm]) after
    ``SETTLE_S``, checking that the drives held it there unless they saturate."""
    arm = SimArm(BRAVO, config, q)
    arm.step_to(SETTLE_S)
    currents = arm.currents()
    if np.all(np.abs(currents) < SATURATED_MA):
        np.testing.assert_allclose(arm.positions(), q, atol=1e-6)  # held where it was
    return currents


@pytest.mark.parametrize("water", [1000.0, 0.0])
def test_flipped_base_negates_the_holding_loads(rng, water):
    """Weight and buoyancy are both along the world's z: turning the base upside down negates
    every joint's gravity-plus-buoyancy load at the same joint angles."""
    checked = 0
    for q in rng.uniform([0.5, 0.3, 0.3, 0.5, 0.3, 0.5], [5.5, 3.2, 3.2, 5.5, 3.2, 5.5], (6, 6)):
        q = [*q, 0.0]
        upright = holding_currents(SimSettings(water_density=water), q)
        if np.any(np.abs(upright) >= SATURATED_MA):  # in air the drives cannot hold every pose
            continue
        hanging = holding_currents(SimSettings(water_density=water, base_rpy=HANGING), q)
        assert np.max(np.abs(upright)) > 100.0  # a real load, not noise
        np.testing.assert_allclose(hanging, -upright, rtol=1e-6, atol=1e-6)
        checked += 1
    assert checked >= 3


def test_yaw_does_not_change_the_loads():
    """A vehicle's heading turns the base about the world's z, along which the loads act."""
    q = [3.15, 1.57, 3.1, 3.15, 1.75, 3.15, 0.0]  # forearm out
    hanging = holding_currents(SimSettings(base_rpy=HANGING), q)
    turned = holding_currents(SimSettings(base_rpy=(math.pi, 0.0, 2.0)), q)
    np.testing.assert_allclose(turned, hanging, rtol=1e-6, atol=1e-6)


def test_weightless_arm_ignores_the_base_orientation():
    q = [3.15, 1.57, 3.1, 3.15, 1.75, 3.15, 0.0]
    currents = holding_currents(SimSettings(dynamics=False, base_rpy=(1.0, -0.5, 0.3)), q)
    assert np.max(np.abs(currents)) < 5.0


def test_hanging_arm_runs_a_plan_through_every_gate():
    run = SimRun(SimSettings(base_rpy=HANGING))
    res = run.executor.run(short_plan())
    assert res.ok, res.reason
    assert len(res.gates) == 4  # start, out, jaws, back
    assert res.max_gate_error_rad <= ExecutorSettings().gate_threshold_rad
    assert all(g.error_mm <= ExecutorSettings().gate_threshold_mm for g in res.gates)
    np.testing.assert_allclose(run.arm.positions()[:6], Q0, atol=ExecutorSettings().gate_threshold_rad)
    assert_within_limits(run.sent_packets())
    assert run.arm.limit_violations == 0
    # the drives carry the hanging loads: those of the upright arm in the same pose, negated
    run.arm.step_to(run.arm.time + 1.0)  # settled (the executor left the arm holding still)
    upright = holding_currents(SimSettings(), run.arm.positions())[:6]
    assert np.max(np.abs(upright)) > 1000.0  # mA: a real load
    np.testing.assert_allclose(run.arm.currents()[:6], -upright, atol=5.0)


@pytest.mark.parametrize("bad", [(0.0, 0.0), (0.0, math.nan, 0.0), (math.inf, 0.0, 0.0), ("x", 0.0, 0.0), 1.0])
def test_base_rpy_must_be_three_finite_angles(bad):
    with pytest.raises(ValueError, match="base_rpy must be 3 finite angles"):
        SimSettings(base_rpy=bad)


def test_base_rpy_from_a_config_mapping():
    sim = from_mapping(HwSettings, {"sim": {"base_rpy": [math.pi, 0, 0.5]}}, "hw").sim
    assert sim.base_rpy == (math.pi, 0.0, 0.5)
    with pytest.raises(ValueError, match=r"hw.sim.base_rpy: expected 3 values"):
        from_mapping(HwSettings, {"sim": {"base_rpy": [0.0, 0.0]}}, "hw")


@pytest.fixture
def plan_file(tmp_path):
    p = tmp_path / "plan.json"
    p.write_text(json.dumps(plan_to_dict(short_plan())))
    return p


def test_cli_base_rpy_reaches_the_simulated_arm(plan_file, tmp_path, monkeypatch, capsys):
    """``uvms-hw run --sim --base-rpy R P Y`` builds the simulated arm with that orientation
    (run here on the in-process link, not over UDP in real time)."""
    seen = []

    def run_plan(plan, robot, *, link, config, sim, **kw):
        seen.append(sim)
        return real_run_plan(plan, robot, link="loopback", config=config, sim=sim, **kw)

    real_run_plan = cli.run_plan
    monkeypatch.setattr(cli, "run_plan", run_plan)
    assert cli.main(["run", str(plan_file), "--sim", "--base-rpy", "3.1", "0", "-0.5", "--no-plot",
                     "--out", str(tmp_path / "out")]) == 0
    assert seen and seen[0].base_rpy == (3.1, 0.0, -0.5)
    assert cli.main(["run", str(plan_file), "--sim", "--base-rpy", "nan", "0", "0"]) == 2
    assert "base_rpy must be 3 finite angles" in capsys.readouterr().err
    assert cli.main(["run", str(plan_file), "--udp", "127.0.0.1:9", "--base-rpy", "3.1", "0", "0"]) == 2
    assert "need --sim" in capsys.readouterr().err
    # A plan that records its base: simulated as recorded, unless --base-rpy says otherwise.
    hanging_plan = tmp_path / "hanging.json"
    hanging_plan.write_text(json.dumps({**plan_to_dict(short_plan()), "base_rpy": list(HANGING)}))
    seen.clear()
    for flags, want in (([], HANGING), (["--base-rpy", "0", "0.2", "0"], (0.0, 0.2, 0.0))):
        assert cli.main(["run", str(hanging_plan), "--sim", *flags, "--no-plot", "--overwrite",
                        "--out", str(tmp_path / "o")]) == 0
        assert seen[-1].base_rpy == tuple(want)
