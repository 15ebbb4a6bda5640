"""The BPL executor driving the simulated arm on the hovering vehicle
(uvms_jax.hover.execute_plan_hovering, HoverWorld as the SimArm's world).

Oracles: the gates the plan defines (counted by hand from its segments), the arm's forward
kinematics for the pose the device reports relative to its moving base, MuJoCo's tool site for
the vehicle–arm chain at the vehicle's measured displacement, and the replay on position servos
(uvms_jax.hover.run_plan_hovering) for the vehicle's drift in the same current.
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_jax import frames, hw, kin
from uvms_jax.hover import (CurrentSettings, HoverSim, HoverWorld, VehicleSettings, execute_plan_hovering,
                            run_plan_hovering, trimmed, vehicle_arm_chain, vehicle_displacement)

from test_hover_plan import ARM, POSE, Q_A, Q_B, _plan

# The plan's gates: "there" 3 waypoints, the gripper step, "back" 3 waypoints less the one the
# previous gate already holds.
PLAN_GATES = 3 + 1 + 2


@pytest.fixture(scope="module")
def runs():
    return {v: execute_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=(v, 0.0, 0.0)))
            for v in (0.0, 0.4)}


def test_the_executor_passes_its_gates_on_the_hovering_vehicle(runs):
    for v, run in runs.items():
        m = run.summary()
        assert m["driver"] == "BPL executor" and m["status"] == "completed", (v, m["reason"])
        assert m["gates"] == m["gates_reached"] == PLAN_GATES
        assert np.all(run.gate_joint_error <= hw.ExecutorSettings().gate_threshold_rad)
        assert run.executed.sim.limit_violations == 0


def test_a_current_moves_the_tool_that_the_executor_does_not_see(runs):
    still, flowing = runs[0.0].summary(), runs[0.4].summary()
    assert still["gates_tool_within_tolerance"] == PLAN_GATES  # 1.5 mm of drift in still water
    assert flowing["gates_tool_within_tolerance"] < PLAN_GATES
    assert flowing["max_drift_m"] > 10 * still["max_drift_m"]
    assert runs[0.0].tool_error[0] < 1e-5  # at rest at the docked pose: the docked tool


def test_the_drift_matches_the_replay_on_position_servos(runs):
    """Two arm drives (the device's velocity loop under the executor, position servos under the
    replay) on one vehicle model: the same current pushes the vehicle as far, within 10 %."""
    replay = run_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=(0.4, 0.0, 0.0)))
    assert runs[0.4].summary()["max_drift_m"] == pytest.approx(replay.summary()["max_drift_m"], rel=0.1)


def test_the_device_reports_its_pose_relative_to_the_moving_base():
    """KM_END_POS is in the base frame: the arm's forward kinematics, however the vehicle moves."""
    world = HoverWorld(trimmed(VehicleSettings(), ARM, Q_A), current=CurrentSettings(velocity=(0.4, 0.0, 0.0)),
                       xyz=POSE[:3], rpy=(0.1, -0.05, POSE[3]))
    arm = hw.SimArm(ARM, hw.SimSettings(), [*Q_B, 0.0], world)
    arm.step_to(1.0)
    assert np.linalg.norm(arm.data.qpos[:3] - POSE[:3]) > 1e-3  # the vehicle moved
    T = np.asarray(kin.fk(kin.with_dtype(ARM.chain, np.float64), arm.positions()[:-1]))
    pose = arm.end_pose()
    np.testing.assert_allclose(pose[:3], 1e3 * T[:3, 3], atol=1e-6)
    np.testing.assert_allclose(frames.rpy_matrix(pose[3:][::-1]), T[:3, :3], atol=1e-9)


def test_the_vehicle_arm_chain_puts_the_tool_where_mujoco_does():
    """kin.uvms on the docked vehicle frame, at the vehicle's displacement and tilt read from
    MuJoCo's free joint, gives MuJoCo's tool site: the chain the coordination's Jacobian uses."""
    sim = HoverSim(ARM, trimmed(VehicleSettings(), ARM, Q_A), current=CurrentSettings(velocity=(0.4, 0.2, 0.0)),
                   xyz=POSE[:3], rpy=(0.0, 0.0, POSE[3]), q0=Q_A)
    log = sim.run(2.0, thrust=np.zeros(8))  # thrusters off: the vehicle drifts and tilts freely
    chain = kin.with_dtype(vehicle_arm_chain(ARM, VehicleSettings()), np.float64)
    T_dock = frames.pose(frames.rot_z(POSE[3]), POSE[:3])
    assert np.abs(log.rpy[-1, :2]).max() > 1e-3 and np.linalg.norm(log.position[-1] - POSE[:3]) > 1e-2
    for k in (0, len(log.time) // 2, -1):
        q = np.concatenate([vehicle_displacement(T_dock, np.concatenate([log.position[k], log.quat[k]])), log.q[k]])
        p = T_dock @ np.append(np.asarray(kin.fk(chain, q))[:3, 3], 1.0)
        np.testing.assert_allclose(p[:3], log.tool[k], atol=1e-6)
