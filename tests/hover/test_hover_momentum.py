"""Without water or gravity the vehicle and arm are a free multibody: only internal forces act,
so the whole system's centre of mass stays where it was (linear momentum, zero at the start,
stays zero) while the arm's motion pushes the vehicle the other way.

Oracle: conservation of momentum; the centre of mass is summed here from the bodies' masses
and centres of mass (``body_mass``, ``xipos``), not from the log.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from uvms_jax.hover import ControllerSettings, HoverSim, VehicleSettings, arm_motion
from uvms_jax.robot import load_arm

DRY = VehicleSettings(water_density=0.0, viscosity=0.0, gravity=0.0)
OFF = ControllerSettings(enabled=False)
Q_B = np.array([2.4, 2.2, 2.0, 3.15, 1.2, 3.15])  # [rad] reaching down and to starboard
COM_TOL = 2e-4  # [m] 2 ms steps of a 1.5 s motion (measured ~2e-5)
MOVED = 5e-3  # [m] the vehicle must move at least this (it moves ~1 cm)


def system_com(sim: HoverSim) -> np.ndarray:
    mujoco.mj_kinematics(sim.model, sim.data)
    m = sim.model.body_mass
    return (m[:, None] * sim.data.xipos).sum(axis=0) / m.sum()


@pytest.fixture(scope="module")
def bravo7():
    return load_arm("bravo7")


def test_arm_motion_moves_the_vehicle_not_the_centre_of_mass(bravo7):
    q_a = (bravo7.lower + bravo7.upper) / 2.0
    sim = HoverSim(bravo7, DRY, OFF, q0=q_a)
    com0 = system_com(sim)
    log = sim.run(2.0, arm_trajectory=arm_motion(q_a, Q_B, 0.2, 1.7))
    np.testing.assert_allclose(log.q[-1], Q_B, atol=1e-3)  # the arm did move (weightless, no load)
    assert np.abs(system_com(sim) - com0).max() < COM_TOL
    assert np.abs(log.com - com0).max() < COM_TOL
    assert np.linalg.norm(log.position[-1] - log.position[0]) > MOVED
    # the vehicle's displacement balances the arm's: m_v Δp_v = −Σ m_b Δp_b
    masses = sim.model.body_mass
    assert masses[1] * (log.position[-1] - log.position[0]) == pytest.approx(
        -(masses[2:].sum()) * (arm_com(sim) - arm_com_start(bravo7, q_a)), abs=masses.sum() * COM_TOL)
    mujoco.mj_comVel(sim.model, sim.data)
    mujoco.mj_subtreeVel(sim.model, sim.data)
    assert np.abs(sim.data.subtree_linvel[0]).max() < 1e-4  # [m/s]: still zero momentum


def arm_com(sim: HoverSim) -> np.ndarray:
    """Centre of mass of the arm's bodies (every body after the vehicle) in the world."""
    mujoco.mj_kinematics(sim.model, sim.data)
    m = sim.model.body_mass[2:]
    return (m[:, None] * sim.data.xipos[2:]).sum(axis=0) / m.sum()


def arm_com_start(robot, q) -> np.ndarray:
    return arm_com(HoverSim(robot, DRY, OFF, q0=q))
