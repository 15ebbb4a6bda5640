"""Hovering scenarios batched with MJX (uvms_jax.hover._batch).

Oracles: CPU MuJoCo. The fluid wrench computed in JAX/NumPy must give MuJoCo's own
``qfrc_fluid`` (its inertia-box model, wind included) on a moving, tilted vehicle; and the whole
MJX batch — K poses × N currents in one jitted call — must reproduce :class:`HoverSim` (MuJoCo's C
engine, stepped one scenario at a time) scenario by scenario, in the vehicle's position and the
tool's. Ordering: a stronger current drifts the vehicle further. And the one modelling difference
isolated: with MuJoCo's fluid replaced on the CPU by the same explicit wrench, MJX in float64 is
MuJoCo's C engine to rounding.
"""

from __future__ import annotations

import contextlib
import io

import jax
import mujoco
import numpy as np
import pytest

from uvms_jax import frames
from uvms_jax.hover import (ControllerSettings, CurrentSettings, HoverSim, VehicleSettings, _sim, arm_motion,
                            hover_model, trimmed)
from uvms_jax.hover._batch import batch_scenarios, fluid_bodies, fluid_xfrc, hover_mjx
from uvms_jax.robot import load_arm

with contextlib.redirect_stdout(io.StringIO()):
    from mujoco import mjx

ARM = load_arm("bravo7")
Q_A = (ARM.lower + ARM.upper) / 2
Q_B = Q_A + np.array([0.3, -0.2, 0.2, 0.0, 0.3, 0.0])
POSES = np.array([[0.1, -0.2, 1.2, 0.4], [-0.3, 0.5, 0.8, -2.5]])  # [m, rad] K = 2 docked poses
CURRENTS = np.array([[0.0, 0.0, 0.0], [0.35, 0.35, 0.0]])  # [m/s] N = 2: still water, ~0.5 m/s
DURATION = 1.2  # [s] 60 control periods, 600 physics steps
GATE = 1.0  # [s] the arm has arrived (move 0.1–0.8 s)
PERIOD = ControllerSettings().period
# MJX (the fluid force explicit) against MuJoCo (implicitfast differentiating the fluid force too):
# the vehicle's and the tool's paths agree to POS_TOL while the vehicle drifts by 4–52 mm. Measured:
# 24 µm and 56 µm at most, the same in float64 (which tests/conftest.py turns on) and in float32 (MJX's
# default outside the tests), so the gap is the CPU's implicit fluid derivative, not the precision
# (the float64 test at the end). EXACT_TOL, FLUID_RTOL: float64 rounding.
POS_TOL = 2e-4  # [m]
EXACT_TOL = 1e-10  # [m]
FLUID_RTOL = 1e-9


def _targets():
    move = arm_motion(Q_A, Q_B, 0.1, 0.8)
    return np.array([move(k * PERIOD) for k in range(round(DURATION / PERIOD))])


def test_fluid_wrench_is_mujocos_inertia_box_model():
    """On a tilted, spinning vehicle with the arm moving, in a current, ``fluid_xfrc`` applied
    at the bodies' centres of mass gives MuJoCo's ``qfrc_fluid`` (every body, every axis)."""
    model = hover_model(ARM, VehicleSettings(), xyz=(0.2, -0.1, 1.0), rpy=(0.2, -0.3, 1.1),
                        current=(0.4, -0.3, 0.1))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(3)
    data.qvel[:] = rng.normal(size=model.nv) * 0.7
    mujoco.mj_forward(model, data)
    ids, box = fluid_bodies(model)
    assert len(ids) == model.nbody - 1  # the hull and every arm link
    rows = fluid_xfrc(data.xipos[ids], data.ximat[ids], data.cvel[ids], data.subtree_com[model.body_rootid[ids]], box,
                      model.opt.density, model.opt.viscosity, model.opt.wind)
    qfrc = np.zeros(model.nv)
    for b, row in zip(ids, rows):
        mujoco.mj_applyFT(model, data, row[:3], row[3:], data.xipos[b], b, qfrc)
    assert np.abs(data.qfrc_fluid).max() > 1.0  # a real drag, not zeros
    np.testing.assert_allclose(qfrc, data.qfrc_fluid, rtol=FLUID_RTOL, atol=FLUID_RTOL * np.abs(data.qfrc_fluid).max())


def test_mjx_refuses_its_own_fluid_with_implicitfast():
    """Why the fluid is applied as a wrench: MJX 3.17 does not put the model as it is."""
    with pytest.raises(NotImplementedError, match="fluid"):
        mjx.put_model(hover_model(ARM, VehicleSettings(), current=(0.3, 0.0, 0.0)))


@pytest.fixture(scope="module")
def sim():
    """The MJX model of the file's batches (one per process: its batch is traced once)."""
    return hover_mjx(ARM, VehicleSettings(), ControllerSettings())


@pytest.fixture(scope="module")
def batch(sim):
    return batch_scenarios(ARM, VehicleSettings(), ControllerSettings(), POSES, CURRENTS, _targets(), DURATION,
                           gate_times=[GATE], sim=sim)


@pytest.fixture(scope="module")
def cpu():
    """The same scenarios on HoverSim, one at a time: ``{(k, n): HoverLog}``."""
    table = _targets()
    logs = {}
    for k, pose in enumerate(POSES):
        for n, current in enumerate(CURRENTS):
            sim = HoverSim(ARM, trimmed(VehicleSettings(), ARM, table[0]), ControllerSettings(),
                           CurrentSettings(velocity=tuple(current)), xyz=pose[:3], rpy=(0.0, 0.0, pose[3]), q0=table[0])
            logs[k, n] = sim.run(DURATION, arm_trajectory=lambda t: table[min(round(t / PERIOD), len(table) - 1)])
    return logs


def test_batch_reproduces_cpu_mujoco_scenario_by_scenario(batch, cpu):
    assert batch.position.shape == (2, 2, len(_targets()) + 1, 3)
    for (k, n), log in cpu.items():
        np.testing.assert_allclose(batch.time, log.time, atol=1e-9)
        np.testing.assert_allclose(batch.position[k, n], log.position, atol=POS_TOL, err_msg=f"pose {k} current {n}")
        np.testing.assert_allclose(batch.tool[k, n], log.tool, atol=POS_TOL, err_msg=f"pose {k} current {n}")
        np.testing.assert_allclose(batch.q[k, n], log.q, atol=1e-4)
        # the drift being compared is real: millimetres at least
        assert np.linalg.norm(log.position - POSES[k, :3], axis=-1).max() > 10 * POS_TOL


def test_docked_tool_and_gates(batch):
    """At the start the tool is where FK at the docked base puts it; the gate's errors are the
    records' at the gate time."""
    np.testing.assert_allclose(batch.tool_error[:, :, 0], 0.0, atol=1e-5)
    row = round(GATE / PERIOD)
    np.testing.assert_allclose(batch.gate_tool_error[..., 0], batch.tool_error[:, :, row])
    np.testing.assert_allclose(batch.gate_joint_error[..., 0], np.abs(batch.q[:, :, row] - Q_B).max(axis=-1))
    assert batch.gate_share.shape == (2, 2)


def test_a_stronger_current_drifts_further(batch):
    assert np.all(batch.max_drift[:, 1] > 2 * batch.max_drift[:, 0])
    assert np.all(batch.max_tool_error[:, 1] > batch.max_tool_error[:, 0])


def test_step_is_jittable_for_one_scenario(sim):
    """The one-scenario control step runs under jit on its own (state in, state out)."""
    state = jax.jit(sim.init)(POSES[0], Q_A)  # one program, not MJX's kinematics op by op
    state2, rec = jax.jit(sim.control_step)(state, Q_A, np.array([0.2, 0.0, 0.0]), POSES[0])
    assert np.all(np.isfinite(np.asarray(rec.position)))
    assert float(state2.data.time) == pytest.approx(PERIOD, rel=1e-5)
    R = frames.rpy_matrix((0.0, 0.0, POSES[0, 3]))
    np.testing.assert_allclose(np.asarray(state.data.xmat[sim.vehicle_id]), R, atol=1e-6)


def test_float64_mjx_is_cpu_mujoco_given_the_same_fluid_wrench(batch, monkeypatch):
    """MuJoCo's fluid switched off on the CPU and ``fluid_xfrc`` applied instead, as MJX gets it
    (with buoyancy, between ``mj_step1`` and ``mj_step2``): MJX in float64 follows MuJoCo's C
    engine to rounding, controller and all. So the gap of the test above is the CPU's
    implicitfast differentiating its own fluid force, which MJX cannot do.

    The MJX side is the batch's scenario (k, n) (float64: tests/conftest.py turns it on), over
    its first ``periods`` control periods, which read only the first ``periods`` target rows."""
    k, n, periods = 1, 1, 20
    assert jax.config.jax_enable_x64  # the batch computed in float64
    table = _targets()[:periods]
    pose, current = POSES[k], CURRENTS[n]
    sim = HoverSim(ARM, trimmed(VehicleSettings(), ARM, table[0]), ControllerSettings(),
                   CurrentSettings(velocity=tuple(current)), xyz=pose[:3], rpy=(0.0, 0.0, pose[3]), q0=table[0])
    m = sim.model
    ids, box = fluid_bodies(m)
    rho, beta = float(m.opt.density), float(m.opt.viscosity)
    m.opt.density, m.opt.viscosity, m.opt.wind[:] = 0.0, 0.0, 0.0
    lift = _sim.apply_buoyancy

    def lift_and_drag(model, data, bodies, density):
        data.xfrc_applied[:] = 0.0
        lift(model, data, bodies, density)
        data.xfrc_applied[ids] += fluid_xfrc(data.xipos[ids], data.ximat[ids], data.cvel[ids],
                                             data.subtree_com[model.body_rootid[ids]], box, rho, beta, current)

    monkeypatch.setattr(_sim, "apply_buoyancy", lift_and_drag)
    log = sim.run(periods * PERIOD, arm_trajectory=lambda t: table[min(round(t / PERIOD), periods - 1)])
    assert len(log.position) == periods + 1
    np.testing.assert_allclose(batch.position[k, n, :periods + 1], log.position, atol=EXACT_TOL)
    np.testing.assert_allclose(batch.tool[k, n, :periods + 1], log.tool, atol=EXACT_TOL)
    np.testing.assert_allclose(batch.thrust[k, n, :len(log.thrust)], log.thrust, atol=1e-8)


def test_robustness_plot_is_written(batch, tmp_path):
    from uvms_jax.hover._batch import plot_robustness

    plot_robustness(batch, tmp_path / "robustness.png")
    assert (tmp_path / "robustness.png").stat().st_size > 10_000


def test_candidates_follow_the_docked_tool_path_and_the_unreachable_is_left_out(sim):
    """Three docking candidates for one plan: its own pose, one nearby, one 3 m away. The
    nearby one moves the tool along the same world path (the docked pose's forward kinematics,
    to the IK tolerance), the far one cannot reach it and is left out of the batch."""
    from uvms_jax.hover import batch_candidates
    from uvms_jax.planfile import Plan, Segment

    plan = Plan(ARM.joint_names, (Segment("there", (0.0, 0.4, 0.8), tuple(map(tuple, (Q_A, (Q_A + Q_B) / 2, Q_B)))),))
    poses = np.stack([POSES[0], POSES[0] + [0.05, -0.03, 0.02, 0.2], POSES[0] + [3.0, 0.0, 0.0, 0.0]])
    # The batch fixture's shapes (2 poses kept, both currents, DURATION with the plan's final
    # period) on its sim: the same traced and compiled program.
    dwell = DURATION - PERIOD - 0.8
    res, reached = batch_candidates(ARM, plan, poses, CURRENTS, dwell_s=dwell, gripper_s=0.0, sim=sim)
    assert reached[:2].tolist() == [1.0, 1.0] and reached[2] < 1.0 and res.poses.shape == (2, 4)
    assert res.time.size == round(DURATION / PERIOD) + 1
    np.testing.assert_allclose(res.docked_tool[1], res.docked_tool[0], atol=2e-4)  # float32 IK tolerance 1e-4
    assert np.all(res.gate_share[:, 0] == 1.0)  # still water: every gate, from both poses
