"""The whole-body controller's formulas (uvms_jax.hover._wbc, _wholebody).

Oracles: MuJoCo's inverse dynamics (``mj_inverse``: the generalised force on the free joint that
holds the hull still while the arm moves, less the buoyancy's generalised force from
``mj_applyFT``) and its fluid force (``qfrc_passive``) for the feed-forward wrench; the arm's
forward kinematics (``kin.fk``, not the Jacobian the controller uses) for the null space: a
step along the second task's rates does not move the tool to first order; the bounds written
out for the limits; NumPy for the same functions under ``jax.jit``.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from uvms_jax import frames, kin
from uvms_jax.hover import VehicleSettings, hover_model, trimmed
from uvms_jax.hover._hydro import buoyancy_xfrc
from uvms_jax.hover._model import VEHICLE_BODY, buoyancy_bodies
from uvms_jax.hover._settings import ControllerSettings, CurrentSettings, NavigationSettings, WholeBodySettings
from uvms_jax.hover._wbc import SECOND_TASK_DAMPING, limited_rates, pose_error, spd_solve, task_priority, weighted_pinv
from uvms_jax.hover._wholebody import NavigationEstimate, WholeBody
from uvms_jax.robot import load_arm

ARM = load_arm("bravo7")
Q_A = (ARM.lower + ARM.upper) / 2
WRENCH_ATOL = 1e-6  # [N, N·m] the feed-forward against MuJoCo's inverse dynamics (float64; ~1e-12 seen)
NULL_ATOL = 1e-9  # [m/s, rad/s] the tool twist of the second task's rates (float64 rounding)
STEP = 1e-6  # [s] a step along the second task's rates: the tool moves O(STEP²) for FK
POSE = np.array([0.1, -0.2, 1.2, 0.4])
PINV_ATOL = 1e-12  # the Cholesky solves against NumPy's SVD pseudo-inverse, undamped (float64 rounding)
SECOND_TASK_RTOL = 1e-4  # the second task's damping: a relative μ²/σ_min² = 1e-6/0.1 at most on these tasks


def _plan(K: int = 7, dt: float = 0.02) -> np.ndarray:
    """``(K, n)`` a smooth joint motion sampled every period (nonzero rates and accelerations)."""
    t = dt * np.arange(K)[:, None]
    return Q_A + 0.4 * np.sin(2.0 * t + np.arange(ARM.n_joints)) * np.array([1, 0.8, -0.7, 1.2, 0.9, -1.1])


def _mujoco_thrust(model, data, vehicle) -> np.ndarray:
    """``(6,)`` in V: the wrench the thrusters must give a hull at rest, by MuJoCo's inverse
    dynamics (the free joint's generalised force, less the buoyancy's)."""
    mujoco.mj_inverse(model, data)
    ids, volume, cob = buoyancy_bodies(model, ARM, vehicle)
    xfrc = buoyancy_xfrc(data.xpos[ids], data.xmat[ids], data.xipos[ids], volume, cob, vehicle.water_density,
                         model.opt.gravity)
    applied = np.zeros(model.nv)
    for b, row in zip(ids, xfrc):
        mujoco.mj_applyFT(model, data, row[:3], row[3:], data.xipos[b], b, applied)
    g = data.qfrc_inverse[:6] - applied[:6]
    R = data.xmat[model.body(VEHICLE_BODY).id].reshape(3, 3)
    return np.concatenate([R.T @ g[:3], g[3:]])  # free joint: world force, moment in the body frame


@pytest.mark.parametrize("tilt, current", [((0.0, 0.0), (0.0, 0.0, 0.0)), ((0.05, -0.08), (0.3, -0.4, 0.05))])
def test_feed_forward_is_mujocos_inverse_dynamics(tilt, current):
    """The arm moving along a plan, the hull held still (level, or tilted in a current), with
    weight, buoyancy (the hull not neutral: a net lift) and drag: the feed-forward
    ``ṗ_arm − w_hydrostatic − w_drag`` is what MuJoCo's inverse dynamics asks of the thrusters
    (``mj_inverse`` takes its fluid force, the drag of every body moving relative to the water,
    as passive)."""
    vehicle = dataclasses.replace(trimmed(VehicleSettings(), ARM, Q_A), volume=0.0795)
    current, q, dt, k = np.asarray(current), _plan(), 0.02, 3
    model = hover_model(ARM, vehicle, current=current)
    wb = WholeBody(ARM, vehicle, ControllerSettings(), WholeBodySettings(smoothing_s=0.0), POSE, q, model)
    data = mujoco.MjData(model)
    joints = [model.joint(j) for j in ARM.joint_names]
    dadr = [model.jnt_dofadr[j.id] for j in joints]
    R = frames.rpy_matrix([*tilt, POSE[3]])
    data.qpos[:3], data.qpos[3:7] = POSE[:3], frames.matrix_quat(R)
    data.qpos[[model.jnt_qposadr[j.id] for j in joints]] = q[k]
    data.qvel[dadr] = (q[k + 1] - q[k - 1]) / (2 * dt)  # the plan's rates and accelerations
    data.qacc[dadr] = (q[k + 1] - 2 * q[k] + q[k - 1]) / dt ** 2
    want = _mujoco_thrust(model, data, vehicle)
    np.testing.assert_allclose(wb.feed_forward(k, R, current, np.zeros(3)), want, atol=WRENCH_ATOL)
    assert np.abs(wb.momentum_rate[k]).max() > 0.1  # the arm's motion matters here
    model.opt.density = model.opt.viscosity = 0.0
    assert np.linalg.norm(want - _mujoco_thrust(model, data, vehicle)) > 0.01  # and so does the water's drag


def _task(seed: int = 0):
    rng = np.random.default_rng(seed)
    chain = kin.uvms(ARM.chain, mount=frames.rpy_pose(VehicleSettings().mount_xyz, VehicleSettings().mount_rpy))
    zeta = np.concatenate([rng.normal(0, 0.05, 6), Q_A + rng.normal(0, 0.3, 6)])
    J = np.asarray(kin.jacobian(chain, zeta), dtype=float)
    J2 = np.concatenate([np.eye(6), np.zeros((6, 6))], axis=1)
    w = np.sqrt(np.r_[np.full(6, 0.01), np.ones(6)])
    return chain, zeta, J, rng.normal(0, 0.1, 6), J2, rng.normal(0, 0.1, 6), w


def test_the_second_task_does_not_move_the_first():
    chain, zeta, J, v1, J2, v2, w = _task()
    rates, second, N1 = task_priority(J, v1, J2, v2, w, 1e-3)
    assert np.abs(J @ second).max() < NULL_ATOL
    assert np.abs(J @ N1).max() < NULL_ATOL
    assert np.linalg.norm(J2 @ second) > 0.01  # the vehicle does move for the second task
    # The tool, by forward kinematics: a step along the second task's rates moves it O(STEP²).
    T0, T1 = (np.asarray(kin.fk(chain, z), dtype=float) for z in (zeta, zeta + STEP * second))
    assert np.abs(pose_error(T1, T0)).max() < 10 * STEP ** 2 * np.linalg.norm(second) ** 2 + 1e-15
    # Without a second task the first task's rates are the same.
    alone, _, _ = task_priority(J, v1, J2, J2 @ (rates - second), w, 1e-3)
    np.testing.assert_allclose(J @ alone, J @ rates, atol=NULL_ATOL)


def test_the_solves_are_the_pseudo_inverses():
    """Oracle: NumPy's SVD pseudo-inverse. The weighted pseudo-inverse and the null-space
    projector are exact; the second task's damped solve is the pseudo-inverse to μ²/σ_min²."""
    rng = np.random.default_rng(3)
    M = rng.normal(size=(6, 6))
    rhs = rng.normal(size=(6, 4))
    np.testing.assert_allclose(spd_solve(M @ M.T + np.eye(6), rhs), np.linalg.solve(M @ M.T + np.eye(6), rhs),
                               atol=PINV_ATOL)
    for seed in range(5):
        _, _, J, v1, J2, v2, w = _task(seed)
        w[8] = 0.0  # a joint held: its column out of the first task
        np.testing.assert_allclose(weighted_pinv(J, w), w[:, None] * np.linalg.pinv(J * w), atol=PINV_ATOL)
        rates, second, N1 = task_priority(J, v1, J2, v2, w, 1e-3)
        np.testing.assert_allclose(N1, np.eye(12) - w[:, None] * np.linalg.pinv(J * w) @ J, atol=PINV_ATOL)
        A = J * w
        first = w * (A.T @ np.linalg.solve(A @ A.T + 1e-6 * np.eye(6), v1))
        C = J2 @ N1
        assert np.linalg.svd(C, compute_uv=False)[-1] ** 2 > SECOND_TASK_DAMPING ** 2 / SECOND_TASK_RTOL
        want = N1 @ np.linalg.pinv(C) @ (v2 - J2 @ first)
        np.testing.assert_allclose(second, want, atol=SECOND_TASK_RTOL * np.abs(want).max())
        np.testing.assert_allclose(rates - second, first, atol=PINV_ATOL)


def test_rate_bounds_are_never_exceeded():
    _, _, J, v1, J2, v2, w = _task(1)
    arm = np.arange(6, 12)
    lo, hi = np.full(6, -0.05), np.full(6, 0.05)
    lo[2], hi[4] = 0.0, 0.0  # joints on a limit
    rates, limited = limited_rates(J, 20 * v1, J2, v2, w, 1e-3, arm, lo, hi)
    assert limited
    assert np.all(rates[arm] <= hi + 1e-15) and np.all(rates[arm] >= lo - 1e-15)
    free, limited = limited_rates(J, 1e-3 * v1, J2, 1e-3 * v2, w, 1e-3, arm, np.full(6, -1.0), np.full(6, 1.0))
    assert not limited
    np.testing.assert_allclose(free, task_priority(J, 1e-3 * v1, J2, 1e-3 * v2, w, 1e-3)[0], atol=1e-15)


def test_the_same_code_runs_under_jit():
    _, _, J, v1, J2, v2, w = _task(2)
    arm = np.arange(6, 12)
    lo, hi = np.full(6, -0.05), np.full(6, 0.05)
    run = jax.jit(functools.partial(limited_rates, xp=jnp))
    got = run(*map(jnp.asarray, (J, 5 * v1, J2, v2, w)), 1e-3, jnp.asarray(arm), jnp.asarray(lo), jnp.asarray(hi))
    want = limited_rates(J, 5 * v1, J2, v2, w, 1e-3, arm, lo, hi)
    np.testing.assert_allclose(np.asarray(got[0]), want[0], atol=1e-9)
    assert bool(got[1]) == want[1]


def test_navigation_fixes_arrive_late_and_are_carried_forward():
    """10 fixes a second, 50 ms late, no noise, the vehicle moving and turning: dead reckoning
    and every fix agree with the truth, so the estimate is the true pose; how many fixes have
    arrived is written out by hand."""
    v, dt = np.array([0.1, -0.05, 0.02]), 0.02
    true_pose = lambda t: (np.array([1.0, 2.0, 3.0]) + v * t, frames.rot_z(0.3 * t))  # noqa: E731
    nav = NavigationEstimate(NavigationSettings(rate_hz=10.0, latency_s=0.05, position_noise_m=0.0,
                                                angle_noise_deg=0.0, fix_gain=0.5), *true_pose(0.0))
    for k in range(20):
        t = k * dt
        p, R = nav.estimate(t, *true_pose(t))
        np.testing.assert_allclose(p, true_pose(t)[0], atol=1e-12)
        np.testing.assert_allclose(R, true_pose(t)[1], atol=1e-12)
    assert nav._next == 4  # fixes of 0, 0.1, 0.2 and 0.3 s have arrived by 0.38 s (0.35 s ≤ 0.38 s < 0.45 s)


@pytest.mark.parametrize("gain", [1.0, 0.1])
def test_navigation_noise_is_the_fixes_averaged(gain):
    """A vehicle at rest, a fix every period: with gain 1 the estimate is each fix, of the fixes'
    standard deviation; with gain g the filter's, sqrt(g / (2 − g)) of it (a first-order filter
    of white noise)."""
    s = NavigationSettings(rate_hz=50.0, latency_s=0.0, position_noise_m=0.005, angle_noise_deg=0.2, fix_gain=gain,
                           seed=3)
    nav = NavigationEstimate(s, np.zeros(3), np.eye(3))
    got = np.array([nav.estimate(0.02 * k, np.zeros(3), np.eye(3))[0] for k in range(6000)])
    # 18 000 correlated samples (correlation time 1/g periods): the spread within 5 % (gain 1) and 10 %
    assert np.std(got[100:]) == pytest.approx(0.005 * np.sqrt(gain / (2 - gain)), rel=0.05 if gain == 1 else 0.1)


def test_a_gusty_current_varies_about_its_mean():
    c = CurrentSettings.gusty((0.3, 0.0, 0.0), 0.1, 2.0, 600.0, seed=1)
    t, v = c.profile()
    np.testing.assert_allclose(np.diff(t), 2.0)
    assert t[-1] >= 600.0 and np.all(v[:, 2] == 0.0)
    gusts = v[:, :2] - (0.3, 0.0)  # 602 knots: the sample mean within ~3σ/sqrt(600), the spread within 10 %
    assert np.abs(gusts.mean(axis=0)).max() < 0.015 and np.std(gusts) == pytest.approx(0.1, rel=0.1)
    with pytest.raises(ValueError, match="gusty current"):
        CurrentSettings.gusty((0.3, 0.0, 0.0), -0.1, 2.0, 10.0)


def test_a_control_period_is_the_same_under_jit():
    """:meth:`WholeBody.step` with ``jax.numpy`` under ``jit`` (the period a traced index, as a
    batch would run it) gives the NumPy commands, on a drifted, tilted vehicle in a current."""
    vehicle = trimmed(VehicleSettings(), ARM, Q_A)
    q = _plan()
    wb = WholeBody(ARM, vehicle, ControllerSettings(), WholeBodySettings(), POSE, q, hover_model(ARM, vehicle))
    R = frames.rpy_matrix([0.02, -0.03, POSE[3] + 0.05])
    state = (POSE[:3] + [0.02, -0.01, 0.005], R, np.array([0.05, 0.02, -0.01]), np.array([0.01, -0.02, 0.03]),
             q[2] + 0.01, np.array([0.01, 0.0, -0.02, 0.01]), np.array([0.3, -0.2, 0.0]), np.array([0.01, 0.0, 0.0]))
    want = wb.step(2, *state)
    got = jax.jit(functools.partial(wb.step, xp=jnp))(jnp.asarray(2), *map(jnp.asarray, state))
    for name, a, b in zip(want._fields, want, got):
        np.testing.assert_allclose(np.asarray(b), a, atol=1e-9, err_msg=name)


def test_the_feed_forwards_plan_is_smoothed_over_its_window():
    """A corner in the plan (rest, then 0.4 rad/s): unsmoothed, one period carries the whole
    change of rate; over a 3-period window twice, it is spread over 5 periods with the weights
    1, 2, 3, 2, 1 (/9), and the rate far from the corner is the plan's."""
    dt, k = 0.02, np.arange(40)
    q = Q_A + 0.4 * dt * np.maximum(k - 20, 0)[:, None] * np.ones(ARM.n_joints)
    vehicle = trimmed(VehicleSettings(), ARM, Q_A)
    model = hover_model(ARM, vehicle)
    raw, smooth = (WholeBody(ARM, vehicle, ControllerSettings(), WholeBodySettings(smoothing_s=w), POSE, q, model)
                   for w in (0.0, 0.06))
    # (q₂₁ − 2q₂₀ + q₁₉) / dt²: the whole change of rate in one period
    np.testing.assert_allclose(raw.q_ddot[:, 0][18:23], [0, 0, 0.4 / dt, 0, 0], atol=1e-9)
    np.testing.assert_allclose(smooth.q_ddot[:, 0].max(), 3 / 9 * 0.4 / dt, rtol=1e-9)  # the middle weight
    np.testing.assert_allclose(smooth.q_ddot[10:30, 0].sum() * dt, 0.4, rtol=1e-9)  # the corner's change of rate
    np.testing.assert_allclose(smooth.q_dot[25:35, 0], 0.4, rtol=1e-9)  # away from both ends
