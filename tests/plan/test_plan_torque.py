"""The torque metric's statics: the links' weight and buoyancy and the held object's force,
against MuJoCo's gravity forces of the simulated arm and against the gradient of the potential
energy, for an upright, a hanging (the thesis cage) and a tilted base."""

from pathlib import Path

import mujoco
import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from uvms_jax import bravo7, kin
from uvms_jax.hw import sim_spec
from uvms_jax.plan import build_scene, static_torques, trajectory_metrics
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
G = 9.81
RHO = 1000.0
ATOL = 1e-9  # float64; the same statics by other means differ by round-off
FD_ATOL = 1e-6  # central differences, h = 1e-6: truncation ~1e-12, round-off ~1e-10 [N·m]


@pytest.fixture(scope="module")
def gravities():
    """Gravity in the base frame [m/s²]: upright, hanging in the thesis cage, tilted."""
    cage = build_scene(BRAVO7, yaml.safe_load(SCENARIO.read_text()))
    down = np.array([0.0, 0.0, -G])
    tilted = Rotation.from_euler("xyz", [0.4, -0.7, 1.1]).as_matrix().T @ down
    hanging = cage.T_base_world[:3, :3] @ down
    assert hanging[2] > 0.99 * G  # the cage's arm hangs: gravity along its base's +z
    return {"upright": down, "hanging": hanging, "tilted": tilted}


@pytest.fixture(scope="module")
def poses():
    rng = np.random.default_rng(7)
    lo, hi = np.array([j.lower for j in bravo7.ARM_JOINTS]), np.array([j.upper for j in bravo7.ARM_JOINTS])
    return rng.uniform(lo, hi, (6, 6))


@pytest.fixture(scope="module")
def sim():
    """The simulator's arm (the manufacturer's inertials on the URDF bodies, jaws' fingers
    gravity compensated)."""
    model = sim_spec(BRAVO7, dynamics=True).compile()
    return model, mujoco.MjData(model)


@pytest.mark.parametrize("base", ["upright", "hanging", "tilted"])
@pytest.mark.parametrize("water", [0.0, RHO])
def test_matches_mujoco(sim, gravities, poses, base, water):
    """At rest MuJoCo's ``qfrc_bias`` (less the fingers' compensation) is the torque the drives
    hold the arm with under gravity: −τ. Buoyancy (up, at each centre of buoyancy) enters
    through MuJoCo's own point Jacobians (``mj_applyFT``)."""
    model, data = sim
    g = gravities[base]
    model.opt.gravity[:] = g
    tau = static_torques(BRAVO7, poses, gravity_base=g, water_density=water)
    for q, t in zip(poses, tau):
        data.qpos[:] = 0.0
        data.qpos[:6] = q
        data.qvel[:] = 0.0
        mujoco.mj_forward(model, data)
        expected = -(data.qfrc_bias - data.qfrc_gravcomp)
        for inertial in BRAVO7.inertials:
            if inertial.body == -1:  # the base link: welded, it turns no joint
                continue
            b = model.body(BRAVO7.link_names[inertial.body]).id
            cob = data.xpos[b] + data.xmat[b].reshape(3, 3) @ np.asarray(inertial.cob)
            mujoco.mj_applyFT(model, data, -water * inertial.volume * g, np.zeros(3), cob, b, expected)
        np.testing.assert_allclose(t, expected[:6], atol=ATOL)
        assert np.abs(t).max() > 0.1  # every pose carries a real load


def _pose(R, p=(0.0, 0.0, 0.0)):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


def _urdf_frames(q):
    """Frames of the base, links G…B and the tool ``(8, 4, 4)`` for ``q (6,)``, by the URDF rule
    (origin, then a turn about the joint axis) read straight off the joint table."""
    out = [np.eye(4)]
    for joint, angle in zip(bravo7.ARM_JOINTS, q):
        turn = Rotation.from_rotvec(angle * np.asarray(joint.axis)).as_matrix()
        out.append(out[-1] @ _pose(Rotation.from_euler("xyz", joint.rpy).as_matrix(), joint.xyz) @ _pose(turn))
    out.append(out[-1] @ _pose(Rotation.from_euler("xyz", bravo7.TOOL_RPY).as_matrix(), bravo7.TOOL_XYZ))
    return out


def _potential(q, g, water, force_tool):
    """U(q) = −Σ f·p [J] of the constant point loads, from the URDF joint table's own frames
    (:func:`_urdf_frames`, not the library's kinematics)."""
    frames = _urdf_frames(q)
    body = {"base": 0, "tool": 7} | {name: i + 1 for i, name in enumerate("GFEDCB")}
    U = 0.0
    for name, inertial in zip(bravo7.INERTIAL_BODIES, kin.bravo7_inertials()):
        T = frames[body[name]]
        U -= inertial.mass * g @ (T[:3, :3] @ inertial.com + T[:3, 3])
        U += water * inertial.volume * g @ (T[:3, :3] @ inertial.cob + T[:3, 3])
    return U - force_tool @ frames[7][:3, 3]


@pytest.mark.parametrize("base", ["upright", "hanging", "tilted"])
def test_is_the_gradient_of_the_potential(gravities, poses, base):
    """Loads of constant direction are conservative: the drives' torque −τ = ∂U/∂q (central
    differences), weight, buoyancy and a held object together."""
    g = gravities[base]
    f = np.array([0.3, -0.5, -2.0])
    tau = static_torques(BRAVO7, poses, gravity_base=g, water_density=RHO, force_base=f)
    h = 1e-6
    for q, t in zip(poses, tau):
        grad = [(_potential(q + h * e, g, RHO, f) - _potential(q - h * e, g, RHO, f)) / (2 * h) for e in np.eye(6)]
        np.testing.assert_allclose(-t, grad, atol=FD_ATOL)


def test_metric_is_the_largest_torque(gravities, poses):
    """trajectory_metrics' max_torque is max |τ| over points and joints; with the arm's weight
    even a move holding nothing has torque; loads add (τ is linear in them)."""
    chain, g = BRAVO7, gravities["hanging"]
    f = np.array([0.0, 0.0, 3.0])
    arm = static_torques(chain, poses, gravity_base=g, water_density=RHO)
    held = static_torques(chain, poses, gravity_base=np.zeros(3), water_density=RHO, force_base=f)
    both = static_torques(chain, poses, gravity_base=g, water_density=RHO, force_base=f)
    np.testing.assert_allclose(both, arm + held, atol=ATOL)
    _, _, tau = trajectory_metrics(chain, poses, f, gravity_base=g, water_density=RHO)
    assert tau == pytest.approx(np.abs(both).max(), abs=ATOL)
    _, _, alone = trajectory_metrics(chain, poses, gravity_base=g, water_density=RHO)
    assert alone == pytest.approx(np.abs(arm).max(), abs=ATOL) and alone > 0.1
    # Water carries part of the weight: less torque than in air at every point.
    air = static_torques(chain, poses, gravity_base=g, water_density=0.0)
    assert np.all(np.abs(air).max(axis=1) > np.abs(arm).max(axis=1))


def test_bad_loads_are_named():
    chain, q = BRAVO7, np.zeros((1, 6))
    with pytest.raises(ValueError, match="gravity_base"):
        static_torques(chain, q, gravity_base=[0.0, -G], water_density=RHO)
    with pytest.raises(ValueError, match="water_density"):
        static_torques(chain, q, gravity_base=[0.0, 0.0, -G], water_density=-1.0)
    with pytest.raises(ValueError, match="force_base"):
        static_torques(chain, q, gravity_base=[0.0, 0.0, -G], water_density=RHO, force_base=[np.nan, 0, 0])
    # An arm whose description has no mass properties carries only the held object's load.
    alpha5 = load_arm("alpha5")
    q5 = np.zeros((1, alpha5.n_joints))
    weightless = static_torques(alpha5, q5, gravity_base=[0.0, 0.0, -G], water_density=RHO)
    assert not alpha5.inertials and np.all(weightless == 0.0)
