"""The docking stage's pose places the arm in the planning scene: the MuJoCo model's base link
and the vehicle's hull sit where the pose and the scene file's mount put them."""

from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf
from scipy.spatial.transform import Rotation

from _pipeline_helpers import CONFIG_DIR
from uvms_jax import evo, plan
from uvms_jax.plan import docked_scene
from uvms_jax.settings import from_mapping
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")


@pytest.fixture(scope="module")
def demo():
    """The demo's scenario and docking problem (configs/pipeline.yaml, docking/preset=demo)."""
    with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
        scenario = OmegaConf.to_container(compose("pipeline"), resolve=True)["scenario"]
        docking = OmegaConf.to_container(compose("docking", overrides=["docking/preset=demo"]), resolve=True)
    settings = from_mapping(evo.DockingSettings, docking)
    task = plan.docking_task(plan.build_scene(BRAVO7, scenario), vehicle=settings.scene)
    problem = evo.docking_problem(settings.scene, "float64", task)
    return scenario, problem


@pytest.mark.parametrize("pose", [(0.01, 0.41, 1.2, -1.62), (-0.3, 0.25, 1.05, 2.8)])
def test_base_link_sits_on_the_docked_vehicle(demo, pose):
    scenario, problem = demo
    T_world_vehicle, T_world_base, spec = docked_scene(scenario, problem, pose)
    # Independently: the vehicle at (x, y, z) yawed by ψ, the arm 0.35 m ahead and 0.2 m below
    # its centre, hanging (half a turn about x) — configs/docking/scene/bravo7_tables.yaml.
    expected_vehicle = np.eye(4)
    expected_vehicle[:3, :3] = Rotation.from_euler("z", pose[3]).as_matrix()
    expected_vehicle[:3, 3] = pose[:3]
    mount = np.array([[1.0, 0, 0, 0.35], [0, -1.0, 0, 0], [0, 0, -1.0, -0.2], [0, 0, 0, 1.0]])
    np.testing.assert_allclose(T_world_vehicle, expected_vehicle, atol=1e-9)
    np.testing.assert_allclose(T_world_base, expected_vehicle @ mount, atol=1e-9)

    scene = plan.build_scene(BRAVO7, spec)
    np.testing.assert_allclose(scene.T_world_base, expected_vehicle @ mount, atol=1e-9)
    m, d = scene.model, mujoco.MjData(scene.model)
    mujoco.mj_kinematics(m, d)
    base = m.body("base_link").id
    np.testing.assert_allclose(d.xpos[base], (expected_vehicle @ mount)[:3, 3], atol=1e-9)
    np.testing.assert_allclose(d.xmat[base].reshape(3, 3), (expected_vehicle @ mount)[:3, :3], atol=1e-9)
    # The hull (a convex mesh; MuJoCo re-centres meshes on their inertia frame): its vertices in
    # the world, seen from the vehicle frame, span the box of the scene file, 0.9 × 0.7 × 0.4 m.
    hull = m.geom("vehicle0")
    verts = m.mesh_vert[m.mesh_vertadr[hull.dataid[0]]:][: m.mesh_vertnum[hull.dataid[0]]]
    world = d.geom_xpos[hull.id] + verts @ d.geom_xmat[hull.id].reshape(3, 3).T
    local = (world - np.asarray(pose[:3])) @ expected_vehicle[:3, :3]
    np.testing.assert_allclose(local.min(axis=0), [-0.45, -0.35, -0.2], atol=1e-6)
    np.testing.assert_allclose(local.max(axis=0), [0.45, 0.35, 0.2], atol=1e-6)
    assert "ceiling" not in {m.geom(i).name for i in range(m.ngeom)}  # open water: no cage


def test_open_water_scene_keeps_the_tables_and_drops_the_cage(demo):
    scenario, _ = demo
    model = plan.build_scene(BRAVO7, scenario).model
    names = {model.geom(i).name for i in range(model.ngeom)}
    assert {"start_left", "dest_inclined", "n1:cube1", "n5:base_cube1"} <= names
    assert not any(n.startswith("cage:") for n in names) and "ceiling" not in names


def test_fixed_mount_M_a_leaves_out_the_hull(demo):
    """The baseline's M_a at a fixed mount: the docking problem's with the vehicle's hull gone.
    Oracle: the problem without any hull box (its arrays emptied) and without the hull in the
    arm's collision world, scored by evaluate_arm."""
    _, problem = demo
    pose = (0.01, 0.41, 1.2, -1.62)  # the tiny experiment's box: reaches every target
    _, T_world_base, _ = docked_scene(demo[0], problem, pose)
    dtype = problem.T_vehicle_box.dtype
    empty = problem.replace(T_vehicle_box=jnp.zeros((0, 4, 4), dtype), vehicle_half=jnp.zeros((0, 3), dtype),
                            world=problem.world.without_vehicle())
    expected = float(evo.evaluate_arm(empty, np.asarray(pose)).M_a)
    assert expected > 0
    np.testing.assert_allclose(evo.fixed_base_M_a(problem, T_world_base), expected, rtol=1e-9)
