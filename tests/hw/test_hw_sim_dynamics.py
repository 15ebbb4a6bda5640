"""The simulated arm carries the manufacturer's masses under gravity and buoyancy: its drives'
currents follow the static load, and it sags while moving a load."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_jax import bravo7, kin
from uvms_jax.hw import Mode, PacketID, SimArm, SimSettings

from _hw_helpers import BRAVO, DeviceID, SimRun, urdf_link_frames, ypr_matrix

G = 9.81
K_T = np.array([j.effort for j in bravo7.JOINTS[:6]]) / 2.0  # N·m per A: the effort at 2000 mA


def static_torques(q, water_density, base_rpy=(0.0, 0.0, 0.0)):
    """Independent statics: the drive torque [N·m] each joint G…B needs to hold pose q, from the
    mapped masses and buoyancy (weights down at the centres of mass, lifts up at the centres of
    buoyancy) and the URDF frames, all in the base frame; the base sits in the world at URDF
    roll, pitch, yaw ``base_rpy`` [rad], so "up" is the world's z seen from the base."""
    roll, pitch, yaw = base_rpy
    up = ypr_matrix(yaw, pitch, roll).T @ np.array([0.0, 0.0, 1.0])  # world z in the base frame
    U = [np.eye(4)] + urdf_link_frames(q)  # base, G…B, tool
    forces = []
    for body_frame, inertial in zip(U, kin.bravo7_inertials()):
        R, p = body_frame[:3, :3], body_frame[:3, 3]
        forces.append((p + R @ inertial.com, -inertial.mass * G * up))
        forces.append((p + R @ inertial.cob, water_density * inertial.volume * G * up))
    tau = np.zeros(6)
    for j, joint in enumerate(bravo7.ARM_JOINTS):
        axis, at = U[j + 1][:3, :3] @ np.array(joint.axis), U[j + 1][:3, 3]
        carried = range(2 * (j + 1), len(forces))  # the bodies beyond joint j
        tau[j] = -sum(np.cross(forces[i][0] - at, forces[i][1]) @ axis for i in carried)
    return tau


TAU_MAX = K_T * 4.0  # the drives saturate at 4000 mA


# base orientations in the world: URDF roll, pitch, yaw [rad]
UPRIGHT, HANGING, TILTED = (0.0, 0.0, 0.0), (np.pi, 0.0, 0.0), (2.5, 0.6, -1.1)


@pytest.mark.parametrize(("water", "base_rpy"), [(1000.0, UPRIGHT), (0.0, UPRIGHT), (1000.0, HANGING),
                                                 (0.0, HANGING), (1000.0, TILTED)])
def test_holding_currents_are_the_static_load(rng, water, base_rpy):
    poses = rng.uniform([0.5, 0.3, 0.3, 0.5, 0.3, 0.5], [5.5, 3.2, 3.2, 5.5, 3.2, 5.5], (20, 6))
    # in air the outstretched arm is more than the drives can hold: poses they can
    poses = [q for q in poses if np.all(np.abs(static_torques(q, water, base_rpy)) < 0.9 * TAU_MAX)]
    assert len(poses) >= 3
    for q in poses[:3]:
        run = SimRun(SimSettings(water_density=water, base_rpy=base_rpy), q0=list(q))
        run.clock.sleep(0.5)
        got = run.client.read([PacketID.CURRENT], list(DeviceID)[:-1])
        current = np.array([got[(j.device_id, PacketID.CURRENT)][0] for j in bravo7.ARM_JOINTS])  # mA
        np.testing.assert_allclose(current * 1e-3 * K_T, static_torques(q, water, base_rpy), atol=0.02)
        assert run.client.read_state().positions[:6] == pytest.approx(list(q), abs=1e-4)  # held


def test_water_carries_part_of_the_load():
    q = [3.15, 1.57, 3.1, 3.15, 1.75, 3.15, 0.0]  # forearm out
    currents = {}
    for name, config in (("water", SimSettings()), ("air", SimSettings(water_density=0.0)),
                         ("weightless", SimSettings(dynamics=False))):
        arm = SimArm(BRAVO, config, q)
        arm.step_to(0.2)
        currents[name] = np.abs(arm.currents())
    assert currents["air"][1] > currents["water"][1] > 1000  # mA at the shoulder F
    assert np.max(currents["weightless"]) < 5.0  # nothing to carry


def test_the_arm_sags_while_it_moves_a_load():
    """Shoulder F swinging the outstretched arm: the load pulls it behind its demand; heavier in
    air than in water; a weightless arm only lags by its servo."""

    def lag(config):
        arm = SimArm(BRAVO, config, [3.15, 1.0, 2.5, 3.15, 1.75, 3.15, 0.0])
        worst = 0.0
        arm.mode[1] = Mode.VELOCITY
        arm.vel_target[1] = 0.5  # lifting: against gravity
        for k in range(1, 101):
            arm.step_to(0.01 * k)
            worst = max(worst, 0.5 - arm.velocities()[1])
        return worst

    water, air, weightless = lag(SimSettings()), lag(SimSettings(water_density=0.0)), lag(SimSettings(dynamics=False))
    assert air > water > weightless
