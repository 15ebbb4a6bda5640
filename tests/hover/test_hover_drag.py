"""Drag and current: the hull against closed forms of MuJoCo's inertia-box fluid model.

MuJoCo documents the model (Computation → Fluid forces → Inertia model): each body moves
through the fluid as the box with its mass and inertia; along each of the box's axes the force
is ``−½ ρ A |v| v`` (A: the face across that axis) plus the viscous ``−3π d β v`` (d: the box's
mean edge), v the body's velocity relative to the medium (``wind``). The hull is a uniform box,
so its equivalent box is the hull (0.9 × 0.7 × 0.4 m). Oracles: the terminal speed
``F = ½ ρ A v² + 3π d β v``, the approach to it, and the decay of the velocity relative to a
current, ``m v' = −½ ρ A |v| v − 3π d β v`` (a Bernoulli equation, solved in closed form).
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_jax.hover import ControllerSettings, CurrentSettings, HoverSim, VehicleSettings, current_at

RHO = 1000.0
HULL_MASS = 75.0
SIZE = np.array([0.9, 0.7, 0.4])
AREA = np.array([SIZE[1] * SIZE[2], SIZE[0] * SIZE[2], SIZE[0] * SIZE[1]])  # faces across x, y, z [m²]
OFF = ControllerSettings(enabled=False)
HULL = VehicleSettings(mass=HULL_MASS, volume=HULL_MASS / RHO, cob=(0.0, 0.0, 0.05))
VISCOUS = 3.0 * np.pi * SIZE.mean() * HULL.viscosity  # [N·s/m]
SPEED_RTOL = 1e-4  # 2 ms semi-implicit steps against the exact solution (measured ~1e-6)
# [m/s] along the way: the surge path against tanh (which leaves out the viscous term) differs
# by ~3e-4, and 1 % more drag area would move it by 3e-3; the current's exact path by ~6e-5,
# and 1 % more drag would move it by 7e-4.
SURGE_ATOL = 1e-3
CURRENT_ATOL = 3e-4


def relative_speed(v0: float, area: float, t: np.ndarray) -> np.ndarray:
    """Exact solution of m v' = −a v|v| − b v (v0 ≥ 0): with w = 1/v, w' = (a + b w)/m."""
    a, b = 0.5 * RHO * area, VISCOUS
    return 1.0 / ((1.0 / v0 + a / b) * np.exp(b * t / HULL_MASS) - a / b)


def test_surge_thrust_reaches_the_terminal_speed():
    """The four horizontal thrusters at 20 N each push along surge only (their sway and yaw
    cancel), 4 · 20 N · cos 45°; the hull settles where the drag equals that, along
    v(t) = v_T tanh(t / τ) (τ = m / √(F a), the viscous term being ~1e-5 of the drag)."""
    thrust = 20.0
    force = 4 * thrust * np.cos(np.pi / 4)
    a = 0.5 * RHO * AREA[0]
    v_terminal = (-VISCOUS + np.sqrt(VISCOUS ** 2 + 4 * a * force)) / (2 * a)
    log = HoverSim(None, HULL, OFF).run(6.0, thrust=[thrust] * 4 + [0.0] * 4)
    assert log.velocity[-1, 0] == pytest.approx(v_terminal, rel=SPEED_RTOL)
    assert np.abs(log.velocity[:, 1:]).max() < 1e-9 and np.abs(log.rpy).max() < 1e-9
    tau = HULL_MASS / np.sqrt(force * a)
    np.testing.assert_allclose(log.velocity[:, 0], v_terminal * np.tanh(log.time / tau), atol=SURGE_ATOL)
    # and back: the same thrust astern gives the same speed astern
    log = HoverSim(None, HULL, OFF).run(6.0, thrust=[-thrust] * 4 + [0.0] * 4)
    assert log.velocity[-1, 0] == pytest.approx(-v_terminal, rel=SPEED_RTOL)


def test_hull_drifts_towards_the_current():
    """Thrusters off in a steady current: the velocity relative to the water decays along each
    hull axis by its own face's drag, as the closed form says, and the hull's velocity tends to
    the current's."""
    water = np.array([0.3, -0.1, 0.05])
    log = HoverSim(None, HULL, OFF, CurrentSettings(velocity=tuple(water))).run(8.0)
    for axis in range(3):
        want = water[axis] - np.sign(water[axis]) * relative_speed(abs(water[axis]), AREA[axis], log.time)
        np.testing.assert_allclose(log.velocity[:, axis], want, atol=CURRENT_ATOL, err_msg=f"axis {axis}")
    relative = np.abs(log.velocity - water)
    assert np.all(relative[-1] < 0.4 * np.abs(water))  # well on its way…
    assert np.all(np.diff(relative, axis=0) <= 1e-12)  # …and never turning back
    np.testing.assert_allclose(log.current, np.broadcast_to(water, log.current.shape))


def test_current_profile_is_piecewise_linear():
    """A profile is linear between its knots and held outside them, as np.interp says, and the
    simulator sets it as MuJoCo's wind."""
    times, values = (1.0, 2.0, 4.0), ((0.0, 0.0, 0.0), (0.4, -0.2, 0.0), (0.1, 0.0, 0.1))
    current = CurrentSettings(times=times, velocities=values)
    t = np.linspace(-1.0, 6.0, 71)
    got = np.array([current_at(*current.profile(), s) for s in t])
    want = np.stack([np.interp(t, times, np.array(values)[:, i]) for i in range(3)], axis=-1)
    np.testing.assert_allclose(got, want, atol=1e-15)
    log = HoverSim(None, HULL, OFF, current).run(5.0)
    # each row holds the wind of the period's last physics step (2 ms before the row's time)
    want = np.stack([np.interp(np.maximum(log.time - 0.002, 0.0), times, np.array(values)[:, i])
                     for i in range(3)], axis=-1)
    np.testing.assert_allclose(log.current, want, atol=1e-12)
    assert log.velocity[-1, 0] > 0.05  # the water carried it


@pytest.mark.parametrize("bad", [dict(times=(0.0, 0.0), velocities=((0, 0, 0), (1, 0, 0))),
                                 dict(times=(0.0,), velocities=()),
                                 dict(velocity=(0.1, 0, 0), times=(0.0,), velocities=((0, 0, 0),))])
def test_bad_current_raises(bad):
    with pytest.raises(ValueError):
        CurrentSettings(**bad)
