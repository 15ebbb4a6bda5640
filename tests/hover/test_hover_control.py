"""Thrust allocation and station keeping.

Oracles: MuJoCo's own site transmission (the generalised force the thrusters' actuators put on
the free joint) for the thrust configuration matrix; ``B u = w`` and NumPy's least-squares
minimum-norm solution (``lstsq``, not the pseudo-inverse the code is given) for feasible
wrenches; geometry (parallel to the demand, within the limits, one thruster at its limit) for
the rest; the PID written out by hand; and, in the simulator, the same arm motion without
station keeping, which drifts beyond the tolerance the controlled run keeps.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from uvms_jax import frames
from uvms_jax.hover import (DEFAULT_THRUSTERS, ControllerSettings, HoverSim, VehicleSettings, allocate_thrust,
                            arm_motion, buoyancy_xfrc, current_at, hover_model, station_keeping, thrust_matrix,
                            thruster_name, wrap_angle, yaw_of_quat)
from uvms_jax.robot import load_arm

POS = np.array([t.pos for t in DEFAULT_THRUSTERS])
DIR = np.array([t.direction for t in DEFAULT_THRUSTERS])
LIMITS = np.array([t.max_thrust for t in DEFAULT_THRUSTERS])
B = thrust_matrix(POS, DIR)
B_PINV = np.linalg.pinv(B)
WRENCH_ATOL = 1e-9  # [N, N·m] float64 products
HOLD_POS = 0.01  # [m] station keeping holds V's origin this close while the arm moves (~3.5 mm)
HOLD_YAW = np.deg2rad(1.5)  # [rad] … and its heading (~0.7°); without it: ~34 mm and ~14°
Q_B = np.array([2.4, 2.2, 2.0, 3.15, 1.2, 3.15])  # [rad] reaching down and to starboard


def test_thrust_matrix_is_mujocos_transmission():
    """Each thruster alone at 10 N, the hull level at the origin: the generalised force MuJoCo's
    actuator puts on the free joint (world force, then moment about the body origin in the body
    frame) is 10 N × B's column; the default layout commands all six axes."""
    model = hover_model(None, VehicleSettings())
    data = mujoco.MjData(model)
    for k in range(len(DEFAULT_THRUSTERS)):
        data.ctrl[:] = 0.0
        data.ctrl[model.actuator(thruster_name(k)).id] = 10.0
        mujoco.mj_forward(model, data)
        np.testing.assert_allclose(data.qfrc_actuator[:6], 10.0 * B[:, k], atol=1e-12)
    assert np.linalg.matrix_rank(B) == 6


def test_allocation_reproduces_feasible_wrenches():
    """Wrenches whose minimum-norm thrusts fit the limits are met exactly, by those thrusts."""
    rng = np.random.default_rng(0)
    wrench = rng.normal(size=(200, 6)) * [40, 40, 60, 10, 10, 15]
    exact = np.linalg.lstsq(B, wrench.T, rcond=None)[0].T  # (200, 8) minimum-norm solutions
    feasible = np.all(np.abs(exact) <= LIMITS, axis=1)
    assert 50 < feasible.sum() < 200  # both kinds drawn
    u = allocate_thrust(wrench, B_PINV, LIMITS)
    np.testing.assert_allclose(u[feasible] @ B.T, wrench[feasible], atol=WRENCH_ATOL)
    np.testing.assert_allclose(u[feasible], exact[feasible], atol=WRENCH_ATOL)


def test_allocation_never_exceeds_a_limit():
    """Beyond the allocator's reach the wrench is scaled down whole: B u is w times a factor in
    (0, 1), one thruster sits at its limit and none beyond — also for huge demands."""
    rng = np.random.default_rng(1)
    wrench = rng.normal(size=(300, 6)) * [200, 200, 300, 50, 50, 80] * rng.uniform(0.5, 100.0, size=(300, 1))
    u = allocate_thrust(wrench, B_PINV, LIMITS)
    assert np.all(np.abs(u) <= LIMITS * (1 + 1e-12))
    exact = np.linalg.lstsq(B, wrench.T, rcond=None)[0].T
    over = ~np.all(np.abs(exact) <= LIMITS, axis=1)
    assert over.sum() > 250
    got = u[over] @ B.T
    factor = np.sum(got * wrench[over], axis=1) / np.sum(wrench[over] ** 2, axis=1)
    assert np.all((factor > 0) & (factor < 1))
    np.testing.assert_allclose(got, factor[:, None] * wrench[over], atol=1e-8 * np.abs(wrench).max())
    np.testing.assert_allclose(np.max(np.abs(u[over]) / LIMITS, axis=1), 1.0, rtol=1e-12)


def test_station_keeping_by_hand():
    """The PID in the world frame, turned into V: V yawed 90° (its x is the world's y), an error
    of 1 m along the world's x (beyond the integral band: not integrated) and 0.2 rad of yaw
    (within it), moving 0.1 m/s along the world's y, turning at 0.05 rad/s."""
    kp, kd, ki, lim, band = (np.array(v, dtype=float) for v in (
        (100, 110, 120, 40), (200, 210, 220, 60), (20, 21, 22, 5), (30, 30, 30, 10), (0.5, 0.5, 0.5, 0.5)))
    R = frames.rot_z(np.pi / 2)
    error = np.array([1.0, 0.0, 0.0, 0.2])
    wrench, integral = station_keeping(error, np.array([0.0, 0.1, 0.0]), 0.05, np.zeros(4), R, kp, kd, ki, lim, band,
                                       0.02)
    np.testing.assert_allclose(integral, [0.0, 0.0, 0.0, 0.2 * 0.02])
    f_world = np.array([100.0, -210 * 0.1, 0.0])
    np.testing.assert_allclose(R @ wrench[:3], f_world, atol=1e-12)
    np.testing.assert_allclose(wrench[:3], [-21.0, -100.0, 0.0], atol=1e-12)  # world x is V's −y
    np.testing.assert_allclose(wrench[3:], [0.0, 0.0, 40 * 0.2 - 60 * 0.05 + 5 * 0.2 * 0.02], atol=1e-12)
    # the integral stops where ki · integral reaches its limit, and never starts outside the band
    integral = np.zeros(4)
    error = np.array([1.0, 0.3, 0.0, 0.2])
    for _ in range(10_000):
        _, integral = station_keeping(error, np.zeros(3), 0.0, integral, np.eye(3), kp, kd, ki, lim, band, 0.02)
    np.testing.assert_allclose(ki * integral, [0.0, 30.0, 0.0, 10.0])


def test_pure_functions_run_under_jax():
    """The same formulas with jax.numpy under jit (what an MJX simulator would call) give the
    NumPy results, batched where they broadcast."""
    rng = np.random.default_rng(2)
    wrench = rng.normal(size=(5, 6)) * 80
    got = jax.jit(functools.partial(allocate_thrust, xp=jnp))(wrench, B_PINV, LIMITS)
    np.testing.assert_allclose(got, allocate_thrust(wrench, B_PINV, LIMITS), atol=1e-12)
    np.testing.assert_allclose(thrust_matrix(jnp.asarray(POS), jnp.asarray(DIR), xp=jnp), B, atol=1e-15)
    c = ControllerSettings()
    gains = [np.array(v, dtype=float) for v in (c.kp, c.kd, c.ki, c.integral_limit, c.integral_band)]
    R = frames.rpy_matrix([0.1, -0.2, 2.0])
    args = (np.array([0.3, -0.2, 0.1, 3.0]), np.array([0.1, 0.0, -0.1]), 0.2, np.array([0.01, 0.0, 0.0, 0.1]), R)
    got = jax.jit(lambda *a: station_keeping(*a, *gains, 0.02, xp=jnp))(*args)
    want = station_keeping(*args, *gains, 0.02)
    for g, w in zip(got, want):
        np.testing.assert_allclose(g, w, atol=1e-12)
    quat = rng.normal(size=(7, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    want_yaw = [frames.matrix_rpy(frames.quat_matrix(q))[2] for q in quat]
    np.testing.assert_allclose(yaw_of_quat(quat), want_yaw, atol=1e-12)
    np.testing.assert_allclose(jax.jit(functools.partial(yaw_of_quat, xp=jnp))(quat), want_yaw, atol=1e-12)
    np.testing.assert_allclose(wrap_angle(jnp.array([3.5, -3.5, 7.0])), wrap_angle(np.array([3.5, -3.5, 7.0])))
    xpos, xipos = rng.normal(size=(2, 3, 3))
    xmat = np.stack([frames.rpy_matrix(r).ravel() for r in rng.normal(size=(3, 3))])
    volume, cob = np.array([0.08, 0.001, 0.0]), rng.normal(size=(3, 3)) * 0.1
    args = (xpos, xmat, xipos, volume, cob, 1000.0, np.array([0.0, 0.0, -9.81]))
    np.testing.assert_allclose(jax.jit(functools.partial(buoyancy_xfrc, xp=jnp))(*args), buoyancy_xfrc(*args),
                               atol=1e-10)
    times, values = np.array([0.0, 1.0]), np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]])
    np.testing.assert_allclose(jax.jit(functools.partial(current_at, xp=jnp))(times, values, 0.25), [0.25, 0.5, 0.75])


@pytest.fixture(scope="module")
def bravo7():
    return load_arm("bravo7")


def test_station_keeping_holds_while_the_arm_moves(bravo7):
    """Still water, the trimmed default vehicle, the arm swung from mid-range down to starboard
    over 2 s: with station keeping V's origin stays within 10 mm and 1.5° of where it started;
    without it the same motion carries it further (the test can tell)."""
    q_a = (bravo7.lower + bravo7.upper) / 2.0
    logs = {}
    for on in (True, False):
        sim = HoverSim(bravo7, VehicleSettings(), ControllerSettings(enabled=on), q0=q_a)
        logs[on] = sim.run(5.0, arm_trajectory=arm_motion(q_a, Q_B, 0.5, 2.5))
        np.testing.assert_allclose(logs[on].q[-1], Q_B, atol=0.05)  # the servos carry the load
    held, drifted = logs[True], logs[False]
    assert np.linalg.norm(held.position, axis=1).max() < HOLD_POS
    assert np.abs(wrap_angle(held.rpy[:, 2])).max() < HOLD_YAW
    assert np.linalg.norm(drifted.position, axis=1).max() > HOLD_POS
    assert np.abs(wrap_angle(drifted.rpy[:, 2])).max() > HOLD_YAW
    assert np.all(np.abs(held.thrust) <= LIMITS) and np.abs(held.thrust).max() > 0


def test_station_keeping_returns_to_a_new_reference(bravo7):
    """Heading 160°, a step of the reference 0.3 m along the world's x, 0.2 m down and 30° of
    yaw (to −170°: across ±π, the short way round): the vehicle gets there (within 2 cm and 2°
    after 12 s), thrusts within their limits all the way. (At this heading a controller that
    forgot to turn the world force into V would push the wrong way.)"""
    start, goal = np.deg2rad(160.0), np.deg2rad(-170.0)
    sim = HoverSim(bravo7, VehicleSettings(), ControllerSettings(), xyz=(1.0, 2.0, -5.0), rpy=(0.0, 0.0, start))
    sim.set_reference((1.3, 2.0, -5.2), goal)
    log = sim.run(12.0)
    np.testing.assert_allclose(log.position[-1], [1.3, 2.0, -5.2], atol=0.02)
    assert abs(wrap_angle(log.rpy[-1, 2] - goal)) < np.deg2rad(2.0)
    turned = np.unwrap(log.rpy[:, 2]) - start  # the short way: +30°, never the long way round
    assert turned.min() > -np.deg2rad(5.0) and turned.max() < np.deg2rad(40.0)
    assert np.all(np.abs(log.thrust) <= LIMITS)
