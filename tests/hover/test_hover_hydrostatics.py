"""Buoyancy and hydrostatics of the hovering vehicle.

Oracles: Archimedes (lift = ρ V g), the neutral-buoyancy and level-trim sums written out here
from the arm card's numbers, MuJoCo's own ``mj_applyFT`` applying the lift at the centre of
buoyancy, and the rigid pendulum: a hull whose centre of buoyancy is h above its centre of mass
rolls as ``I φ'' = −ρ V g h sin φ`` (period ``4 K(sin²(φ₀/2)) / ω₀``), with drag as MuJoCo
documents its inertia-box model (integrated here by SciPy).
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from uvms_jax.hover import (ControllerSettings, HoverSim, VehicleSettings, buoyancy_bodies, buoyancy_xfrc,
                            hover_model, trimmed)
from uvms_jax.robot import load_arm

G = 9.81
RHO = 1000.0
HULL_MASS = 75.0
SIZE = (0.9, 0.7, 0.4)
H = 0.05  # [m] centre of buoyancy above the centre of mass
OFF = ControllerSettings(enabled=False)
# A neutral hull alone: displaced water weighs what the hull does, buoyancy right over the mass.
NEUTRAL_HULL = VehicleSettings(mass=HULL_MASS, volume=HULL_MASS / RHO, cob=(0.0, 0.0, H))
STILL_TOL = 1e-9  # [m, rad] nothing moves a neutral hull: forces cancel to rounding
ARM_STILL_TOL = 5e-3  # [m] the trimmed vehicle with the arm: the servos sag ~0.016 rad under load
ARM_LEVEL_TOL = np.deg2rad(1.0)  # [rad] … which tilts it a fraction of a degree
PERIOD_RTOL = 1e-4  # the undamped roll period: 2 ms steps of a 2.1 s oscillation
ROLL_ATOL = 2e-3  # [rad] damped roll against SciPy (measured 4e-4); 10 % more drag moves it 4e-3


@pytest.fixture(scope="module")
def bravo7():
    return load_arm("bravo7")


def test_buoyancy_wrench_is_the_lift_at_the_centre_of_buoyancy(bravo7):
    """The xfrc rows (force and torque at the centre of mass) give the same generalised forces as
    MuJoCo applying ρ V g straight up at the centre of buoyancy, for a tilted vehicle."""
    vehicle = VehicleSettings()
    model = hover_model(bravo7, vehicle, xyz=(0.3, -0.2, 1.0), rpy=(0.3, -0.2, 0.7))
    data = mujoco.MjData(model)
    data.qpos[7:] = [1.0, 2.0, 1.0, 2.0, 2.5, 1.0]
    mujoco.mj_forward(model, data)
    ids, volume, cob = buoyancy_bodies(model, bravo7, vehicle)
    xfrc = buoyancy_xfrc(data.xpos[ids], data.xmat[ids], data.xipos[ids], volume, cob, RHO, model.opt.gravity)
    got, want = np.zeros(model.nv), np.zeros(model.nv)
    for row, b, v, c in zip(xfrc, ids, volume, cob):
        mujoco.mj_applyFT(model, data, row[:3].copy(), row[3:].copy(), data.xipos[b].copy(), int(b), got)
        point = data.xpos[b] + data.xmat[b].reshape(3, 3) @ c
        mujoco.mj_applyFT(model, data, np.array([0.0, 0.0, RHO * v * G]), np.zeros(3), point, int(b), want)
    np.testing.assert_allclose(got, want, atol=1e-9)
    # Archimedes: the lifts sum to the weight of the water displaced, hull and arm card volumes
    arm_volume = sum(p.volume for p in bravo7.inertials)
    assert xfrc[:, 2].sum() == pytest.approx(RHO * G * (vehicle.volume + arm_volume), rel=1e-12)


def test_trim_is_the_closed_form(bravo7):
    """Neutral: V_h = (m_h + Σ m) / ρ − Σ V, from the arm card alone; the defaults are that trim
    (to 10 g of water) for the Bravo 7 at mid-range."""
    arm_mass = sum(p.mass for p in bravo7.inertials)
    arm_volume = sum(p.volume for p in bravo7.inertials)
    want = (HULL_MASS + arm_mass) / RHO - arm_volume
    got = trimmed(VehicleSettings(), bravo7)
    assert got.volume == pytest.approx(want, rel=1e-12)
    assert VehicleSettings().volume == pytest.approx(want, abs=1e-5)
    assert np.allclose(VehicleSettings().cob, got.cob, atol=1e-4)
    assert trimmed(NEUTRAL_HULL).volume == pytest.approx(HULL_MASS / RHO)
    assert trimmed(NEUTRAL_HULL).cob == (0.0, 0.0, H)


def test_neutral_hull_stays_put():
    """Thrusters off, still water, neutral and level: no force, no motion, for 3 s."""
    sim = HoverSim(None, NEUTRAL_HULL, OFF, xyz=(1.0, 2.0, -3.0))
    log = sim.run(3.0)
    assert np.abs(log.position - [1.0, 2.0, -3.0]).max() < STILL_TOL
    assert np.abs(log.rpy).max() < STILL_TOL


def test_heavy_hull_sinks_at_the_drag_terminal_speed():
    """2 kg short of neutral: it sinks until ½ ρ A_z v² + 3π d β v = Δm g (A_z = 0.9 × 0.7 m²,
    MuJoCo's inertia box, d its mean edge), which takes about 1 s; at 6 s it is there."""
    deficit = 2.0  # [kg]
    hull = dataclasses.replace(NEUTRAL_HULL, volume=(HULL_MASS - deficit) / RHO)
    log = HoverSim(None, hull, OFF).run(6.0)
    a, b = 0.5 * RHO * SIZE[0] * SIZE[1], 3.0 * np.pi * np.mean(SIZE) * hull.viscosity
    v_terminal = (-b + np.sqrt(b * b + 4.0 * a * deficit * G)) / (2.0 * a)
    assert log.velocity[-1, 2] == pytest.approx(-v_terminal, rel=1e-4)
    assert np.abs(log.velocity[-1, :2]).max() < 1e-12


def test_tilted_hull_rolls_as_a_pendulum_without_drag():
    """MuJoCo's drag off, buoyancy on: the roll period is the pendulum's, 4 K(k²)/ω₀ with
    ω₀² = ρ V g h / I_xx and k = sin(φ₀/2); the hull turns about its unmoving centre of mass."""
    roll0 = np.deg2rad(10.0)
    sim = HoverSim(None, NEUTRAL_HULL, OFF, rpy=(roll0, 0.0, 0.0))
    sim.model.opt.density = 0.0  # the drag only: buoyancy takes the density from the settings
    sim.model.opt.viscosity = 0.0
    log = sim.run(5.0)
    inertia = HULL_MASS * (SIZE[1] ** 2 + SIZE[2] ** 2) / 12.0
    w0 = np.sqrt(RHO * NEUTRAL_HULL.volume * G * H / inertia)
    period = 4.0 * ellipk(np.sin(roll0 / 2.0) ** 2) / w0
    roll = log.rpy[:, 0]
    down = np.flatnonzero((roll[:-1] > 0) & (roll[1:] <= 0))  # downward zero crossings
    crossings = log.time[down] + (log.time[down + 1] - log.time[down]) * roll[down] / (roll[down] - roll[down + 1])
    assert len(crossings) >= 2
    np.testing.assert_allclose(np.diff(crossings), period, rtol=PERIOD_RTOL)
    assert np.abs(log.position).max() < STILL_TOL
    assert roll.max() == pytest.approx(roll0, abs=1e-6)  # no drag, no loss
    assert roll.min() == pytest.approx(-roll0, abs=1e-3)


def test_tilted_hull_rights_itself_in_water():
    """With MuJoCo's drag: the roll decays as I φ'' = −ρ V g h sin φ − (ρ/64) a (b⁴ + c⁴) |φ'| φ'
    − π d³ β φ' (the inertia-box model's documented angular drag and viscous torque), solved
    by SciPy; each swing is smaller than the last, and after four the roll is below 40 % of
    the start."""
    roll0 = np.deg2rad(10.0)
    log = HoverSim(None, NEUTRAL_HULL, OFF, rpy=(roll0, 0.0, 0.0)).run(9.0)
    a, b, c = SIZE
    inertia = HULL_MASS * (b * b + c * c) / 12.0
    k = RHO * NEUTRAL_HULL.volume * G * H
    quad = RHO / 64.0 * a * (b ** 4 + c ** 4)
    lin = np.pi * np.mean(SIZE) ** 3 * NEUTRAL_HULL.viscosity

    def rhs(t, y):
        return [y[1], (-k * np.sin(y[0]) - quad * abs(y[1]) * y[1] - lin * y[1]) / inertia]

    want = solve_ivp(rhs, (0.0, log.time[-1]), [roll0, 0.0], t_eval=log.time, rtol=1e-10, atol=1e-12).y[0]
    np.testing.assert_allclose(log.rpy[:, 0], want, atol=ROLL_ATOL)
    roll = log.rpy[:, 0]
    peaks = roll[1:-1][(roll[1:-1] > roll[:-2]) & (roll[1:-1] >= roll[2:])]
    assert len(peaks) == 4 and np.all(np.diff(np.r_[roll0, peaks]) < 0)
    assert peaks[-1] < 0.4 * roll0


def test_trimmed_vehicle_with_arm_stays_put(bravo7):
    """The default vehicle with the Bravo 7 at mid-range, thrusters off, still water: neutral
    and level, so it stays within millimetres and a degree for 4 s; the same vehicle with its
    centre of buoyancy right over the hull's mass (untrimmed) pitches nose down by tens of
    degrees — the trim is what holds it."""
    log = HoverSim(bravo7, VehicleSettings(), OFF).run(4.0)
    assert np.abs(log.position).max() < ARM_STILL_TOL
    assert np.abs(log.com - log.com[0]).max() < ARM_STILL_TOL
    assert np.abs(log.rpy).max() < ARM_LEVEL_TOL
    untrimmed = dataclasses.replace(VehicleSettings(), cob=(0.0, 0.0, H))
    log = HoverSim(bravo7, untrimmed, OFF).run(4.0)
    assert np.abs(log.rpy[:, 1]).max() > np.deg2rad(20.0)
