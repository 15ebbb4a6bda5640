"""Settings from plain mappings, their checks, and the model they build (names, limits, pose)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from uvms_jax import frames
from uvms_jax.hover import (DEFAULT_THRUSTERS, ControllerSettings, CurrentSettings, HoverSim, Thruster,
                            VehicleSettings, hover_mjcf, hover_model, servo_name, thruster_name)
from uvms_jax.robot import TOOL_SITE, load_arm
from uvms_jax.settings import SettingsError, from_mapping


@pytest.fixture(scope="module")
def bravo7():
    return load_arm("bravo7")


def test_settings_from_a_mapping():
    """A config's dict builds the settings (lists become tuples, thrusters nested); the defaults
    are the dataclasses'."""
    d = {"size": [1.0, 0.8, 0.5], "mass": 90, "thrusters": [{"pos": [0.4, 0.3, 0.0], "direction": [1, 0, 0]},
                                                          {"pos": [0, 0, 0], "direction": [0, 0, 1], "max_thrust": 50}]}
    v = from_mapping(VehicleSettings, d, "vehicle")
    assert v.size == (1.0, 0.8, 0.5) and v.mass == 90.0
    assert v.thrusters == (Thruster((0.4, 0.3, 0.0), (1, 0, 0)), Thruster((0, 0, 0), (0, 0, 1), 50.0))
    assert from_mapping(VehicleSettings, {}) == VehicleSettings()
    assert from_mapping(ControllerSettings, {"kp": [1, 2, 3, 4]}).kp == (1, 2, 3, 4)
    c = from_mapping(CurrentSettings, {"times": [0, 10], "velocities": [[0, 0, 0], [0.5, 0, 0]]})
    assert c.profile()[1].shape == (2, 3)


@pytest.mark.parametrize("cls, mapping, message", [
    (VehicleSettings, {"mass": -1.0}, "vehicle.mass"),
    (VehicleSettings, {"size": [0.9, 0.0, 0.4]}, "vehicle.size"),
    (VehicleSettings, {"cob": [0.0, 0.0, -0.01]}, "above the centre of mass"),
    (VehicleSettings, {"thrusters": [{"pos": [0, 0, 0], "direction": [1, 1, 0]}]}, "unit vector"),
    (VehicleSettings, {"thrusters": [{"pos": [0, 0, 0], "direction": [1, 0, 0], "max_thrust": 0}]}, "max_thrust"),
    (ControllerSettings, {"period": 0}, "vehicle.period"),
    (ControllerSettings, {"kd": [1, 2, 3]}, "vehicle.kd"),
    (ControllerSettings, {"ki": [1, -2, 3, 4]}, "vehicle.ki"),
])
def test_bad_settings_raise_naming_the_key(cls, mapping, message):
    with pytest.raises(SettingsError, match=message):
        from_mapping(cls, mapping, "vehicle")


def test_default_layout_is_a_vectored_eight():
    """Four horizontal thrusters at ±45° in the hull's corners, four vertical ones, inside the
    0.9 × 0.7 × 0.4 m hull, 40 N each way."""
    assert len(DEFAULT_THRUSTERS) == 8
    half = np.array(VehicleSettings().size) / 2
    for k, t in enumerate(DEFAULT_THRUSTERS):
        d = np.array(t.direction)
        assert np.all(np.abs(t.pos) <= half) and t.max_thrust == 40.0
        if k < 4:
            assert d[2] == 0 and abs(abs(d[0]) - math.sqrt(0.5)) < 1e-12 and abs(abs(d[1]) - math.sqrt(0.5)) < 1e-12
        else:
            assert tuple(d) == (0.0, 0.0, 1.0)


def test_model_names_limits_and_pose(bravo7):
    """The model has one motor per thruster (ctrl = thrust [N], ±limit), one position servo per
    arm joint (its limits), the hull's mass and the arm's, the fluid option, no contacts; the
    vehicle starts at the pose asked for (e.g. a docking pose)."""
    vehicle = VehicleSettings()
    xyz, rpy = (0.5, -0.3, 1.2), (0.0, 0.0, 0.8)
    model = hover_model(bravo7, vehicle, xyz=xyz, rpy=rpy, current=(0.1, 0.0, 0.0))
    for k, t in enumerate(vehicle.thrusters):
        a = model.actuator(thruster_name(k))
        np.testing.assert_allclose(a.ctrlrange, [-t.max_thrust, t.max_thrust])
    for j, lo, hi in zip(bravo7.joint_names, bravo7.lower, bravo7.upper):
        np.testing.assert_allclose(model.actuator(servo_name(j)).ctrlrange, [lo, hi])
    assert model.nu == 8 + bravo7.n_joints
    assert model.body_mass.sum() == pytest.approx(vehicle.mass + sum(p.mass for p in bravo7.inertials))
    assert (model.opt.density, model.opt.viscosity) == (1000.0, 0.0009)
    np.testing.assert_allclose(model.opt.wind, [0.1, 0.0, 0.0])
    assert not np.any(model.geom_contype) and not np.any(model.geom_conaffinity)
    np.testing.assert_allclose(model.qpos0[:3], xyz)
    np.testing.assert_allclose(frames.quat_matrix(model.qpos0[3:7]), frames.rpy_matrix(rpy), atol=1e-12)
    # the arm hangs under the hull: its base at the mount, its tool below the hull's centre
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    R = frames.rpy_matrix(rpy)
    np.testing.assert_allclose(R.T @ (data.xpos[model.body("base_link").id] - xyz), vehicle.mount_xyz, atol=1e-12)
    assert (R.T @ (data.site_xpos[model.site(TOOL_SITE).id] - xyz))[2] < 0
    hull = mujoco.MjModel.from_xml_string(hover_mjcf(None))  # the hull alone, written as MJCF and read back
    assert hull.nu == 8 and np.all(hull.actuator_trntype == mujoco.mjtTrn.mjTRN_SITE)
    assert np.all(hull.actuator_biastype == mujoco.mjtBias.mjBIAS_NONE)  # motors, no servo


def test_simulator_refuses_what_it_cannot_do(bravo7):
    """Targets outside the joint limits, thrusts beyond a thruster's limit, a control period that
    is no whole number of physics steps: each raises, nothing is clipped."""
    sim = HoverSim(bravo7, VehicleSettings(), ControllerSettings(enabled=False))
    with pytest.raises(ValueError, match="outside"):
        sim.step(arm_targets=bravo7.upper + 0.1)
    with pytest.raises(ValueError, match="thrust"):
        sim.step(thrust=[41.0] + [0.0] * 7)
    with pytest.raises(ValueError, match="whole number"):
        HoverSim(None, VehicleSettings(), ControllerSettings(period=0.005), physics_dt=0.002)
    with pytest.raises(ValueError, match="outside"):
        HoverSim(bravo7, VehicleSettings(), q0=bravo7.lower - 0.1)
