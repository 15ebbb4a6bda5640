"""The MJX batch with a controller in the loop (uvms_jax.hover.batch_controlled).

Oracles: CPU MuJoCo (:func:`~uvms_jax.hover.run_plan_hovering` on ``HoverSim``, the controllers
in NumPy) scenario by scenario; the fixes' arrival times written out by hand; the closed-form
spread of a first-order filter of white noise for the navigation; the thrusters' and joints'
limits written out.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax.hover import (CurrentSettings, NavigationSettings, VehicleSettings, batch_controlled, nav_schedule,
                            run_plan_hovering)
from uvms_jax.hover._batch_control import _nav_start, _nav_update, _rotvec
from uvms_jax.planfile import Plan, Segment
from uvms_jax.robot import load_arm

ARM = load_arm("bravo7")
Q_A = (ARM.lower + ARM.upper) / 2
Q_B = Q_A + np.array([0.3, -0.2, 0.2, 0.0, 0.3, 0.0])
POSE = np.array([0.1, -0.2, 1.2, 0.4])
CONTROLS = ("pid", "feed_forward", "whole_body")
# Steady, and gusty (0.1 m/s about 0.3 m/s, knots every second); a current beyond the thrusters.
CURRENTS = (CurrentSettings.gusty((0.0, 0.0, 0.0), 0.0, 1.0, 7.0),
            CurrentSettings.gusty((0.3, -0.1, 0.0), 0.1, 1.0, 7.0, seed=2),
            CurrentSettings.gusty((1.2, 0.6, 0.0), 0.0, 1.0, 7.0))
# MJX against CPU MuJoCo, 6 s of the plan, float64. The gap is the two engines' treatment of the
# drag: the CPU's implicitfast differentiates MuJoCo's own fluid force in its implicit step, MJX
# gets the same force explicitly (docs/hover.md, "A batch with MJX"), so it grows with the
# motion through the water. Measured over 2 poses × 3 currents (still; 0.3 m/s and 0.5 m/s,
# each with gusts) × the 3 controllers: vehicle and tool within 2.7e-4 m (the largest where
# the PID lets the vehicle drift 0.18 m in the 0.5 m/s gusts; 7e-5 m at 0.3 m/s), gate tool
# errors within 2.7e-4 m, the whole-body controller's tool angles within 4.1e-7 rad. The
# tolerances are about twice the largest gap, and 20× below the 10 mm gate.
POSITION_ATOL = 5e-4  # [m] vehicle and tool, every period, and the gate tool errors
ANGLE_ATOL = 1e-6  # [rad] the tool's angle at the gates


def _plan() -> Plan:
    move = lambda a, b, name: Segment(name, (0.0, 1.0, 2.0), tuple(map(tuple, (a, (a + b) / 2, b))))  # noqa: E731
    return Plan(ARM.joint_names, (move(Q_A, Q_B, "there"), Segment("close", (), (), 0.0), move(Q_B, Q_A, "back")))


@pytest.fixture(scope="module")
def batch():
    scenarios = [(c, i) for c in CONTROLS for i in range(len(CURRENTS))]
    knots = np.stack([CURRENTS[i].profile()[1] for _, i in scenarios])
    return scenarios, batch_controlled(ARM, _plan(), POSE[None], knots, current_times=CURRENTS[0].profile()[0],
                                       controls=[c for c, _ in scenarios], record=True)


@pytest.mark.parametrize("control", CONTROLS)
@pytest.mark.parametrize("i", [0, 1])  # still water, the gusts
def test_batch_with_the_controller_is_cpu_mujoco(batch, control, i):
    n, res = batch[0].index((control, i)), batch[1]
    run = run_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CURRENTS[i], control=control)
    rec = res.records
    np.testing.assert_allclose(rec["position"][0, n], run.log.position[1:], atol=POSITION_ATOL)
    np.testing.assert_allclose(rec["tool"][0, n], run.log.tool[1:], atol=POSITION_ATOL)
    np.testing.assert_allclose(res.gate_tool_error[0, n], run.gate_tool_error, atol=POSITION_ATOL)
    if run.gate_tool_angle is not None:
        np.testing.assert_allclose(res.gate_tool_angle[0, n], run.gate_tool_angle, atol=ANGLE_ATOL)
    assert res.thrust_limited_periods[0, n] == run.thrust_limited_periods
    if control == "whole_body":
        assert res.joint_limited_periods[0, n] == run.joint_limited_periods
        assert res.gate_reached[0, n].all()


def test_limits_hold_in_a_current_beyond_the_thrusters(batch):
    """1.3 m/s: beyond the thrusters' 0.8–0.9 m/s (docs/hover.md); the thrusters sit at their
    limits, none is ever past it, no joint target or angle leaves the joint limits."""
    scenarios, res = batch
    strong = [n for n, (_, i) in enumerate(scenarios) if i == 2]
    assert np.all(res.thrust_limited_periods[0, strong] > 0)
    assert np.all(res.peak_thrust[0, strong] <= 40.0 + 1e-9)
    assert np.all(res.thrust_violations[0] == 0) and np.all(res.joint_violations[0] == 0)
    assert np.all(res.worst_gate_tool_error[0, strong] > 0.01)  # the tool does lose its path there
    assert all("thrusters were at their limit" in r for r in res.reasons[0, strong])  # held, with the reason
    assert all(r == "" for r in res.reasons[0][res.gate_reached[0].all(axis=-1)])


def test_fixes_arrive_late_by_hand():
    """10 Hz, 50 ms late, 20 ms periods: the fix of 0.1 j s arrives at the first period k with
    0.02 k ≥ 0.1 j + 0.05 (k = 3, 8, 13, 18) and describes period 5 j."""
    rows, ids, history = nav_schedule(NavigationSettings(rate_hz=10.0, latency_s=0.05), 0.02, 20)
    arrived = np.flatnonzero(rows[:, 0] >= 0)
    np.testing.assert_array_equal(arrived, [3, 8, 13, 18])
    np.testing.assert_array_equal(rows[arrived, 0], [0, 5, 10, 15])
    np.testing.assert_array_equal(ids[arrived, 0], [0, 1, 2, 3])
    assert history == 4  # periods k − 3 … k kept


@pytest.mark.parametrize("gain", [1.0, 0.1])
def test_device_navigation_noise_is_the_fixes_averaged(gain):
    """At rest, a fix every period: the estimate's spread is the fixes' times sqrt(g / (2 − g))
    (a first-order filter of white noise), in position and in angle."""
    s = NavigationSettings(rate_hz=50.0, latency_s=0.0, position_noise_m=0.005, angle_noise_deg=0.2, fix_gain=gain)
    periods = 6000
    rows, ids, history = nav_schedule(s, 0.02, periods)
    p0, R0 = jnp.zeros(3), jnp.eye(3)

    def step(nav, xs):
        k, r, i = xs
        nav = _nav_update(nav, k, r, i, p0, R0, s, 1.0, jax.random.key(5))
        return nav, (nav.p, _rotvec(nav.R))

    _, (p, angle) = jax.lax.scan(step, _nav_start(p0, R0, history), (jnp.arange(periods), rows, ids))
    spread = np.sqrt(gain / (2 - gain))
    # 18 000 correlated samples (correlation time 1/g periods): within 5 % (gain 1) and 10 %
    rel = 0.05 if gain == 1 else 0.1
    assert np.std(np.asarray(p)[100:]) == pytest.approx(0.005 * spread, rel=rel)
    assert np.std(np.asarray(angle)[100:]) == pytest.approx(np.radians(0.2) * spread, rel=rel)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="controls must be among"):
        batch_controlled(ARM, _plan(), POSE, [[0.0, 0.0, 0.0]], controls="replay")
    with pytest.raises(ValueError, match="without navigation settings"):
        batch_controlled(ARM, _plan(), POSE, [[0.0, 0.0, 0.0]], noisy=True)
    with pytest.raises(ValueError, match="currents must be"):
        batch_controlled(ARM, _plan(), POSE, [[0.0, 0.0]])


def test_docking_poses_ranked_by_the_current_they_tolerate():
    """The plan's pose, one nearby (the same tool path by IK) and one 3 m away (out of reach: not
    run). Still water and 0.3 m/s are held by the whole-body controller (the CPU runs above);
    1.3 m/s is beyond the thrusters from every direction: the hull's own drag there,
    ½ ρ A v² = 237 N in surge and 304 N in sway (A = 0.28, 0.36 m²), exceeds the largest
    pure effort, 113 N (docs/hover.md). So both poses tolerate 0.3 m/s, the tie keeps the order
    given, and the far pose ranks last."""
    from uvms_jax.hover import rank_by_current

    poses = np.stack([POSE, POSE + [0.05, -0.03, 0.02, 0.2], POSE + [3.0, 0.0, 0.0, 0.0]])
    ranking = rank_by_current(ARM, _plan(), poses, [0.0, 0.3, 1.3], directions=4, noisy=False, navigation=None)
    assert ranking.path_share[:2].tolist() == [1.0, 1.0] and ranking.path_share[2] < 1.0
    np.testing.assert_array_equal(ranking.tolerated[:2], [0.3, 0.3])
    assert np.isnan(ranking.tolerated[2]) and ranking.order.tolist() == [0, 1, 2] and ranking.chosen == 0
    assert np.all(ranking.worst_gate_tool_error[:2, :2] <= 0.01) and np.all(ranking.worst_gate_tool_error[:2, 2] > 0.01)
    with pytest.raises(ValueError, match="speeds must increase from 0"):
        rank_by_current(ARM, _plan(), poses, [0.3, 0.5])
