"""One world: docking's collision test is the planner's model in JAX (uvms_jax.plan.docking_world).

On random configurations at docked vehicle poses of the demo it agrees with the planner's
sphere checker and errs, where it disagrees with it or with MuJoCo (the planner's reference),
only towards calling a collision; every IK solution the docking fitness accepts is valid for
the planner in each context its target is checked in; the body frames of the JAX forward
kinematics are MuJoCo's."""

from pathlib import Path

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from uvms_jax import evo, kin
from uvms_jax import plan
from uvms_jax.evo import _world_gpu
from uvms_jax.plan import docked_scene
from uvms_jax.robot import load_arm
from uvms_jax.settings import from_mapping

CONFIG_DIR = Path(__file__).resolve().parents[2] / "configs"
BRAVO7 = load_arm("bravo7")
# Vehicle poses [x, y, z, ψ]: the demo's docked pose (benchmarks/results/docking_reference_demo_h100.json)
# and one over the other tables.
POSES = np.array([[-0.262, 0.300, 1.205, -0.873], [0.15, -0.35, 1.0, 2.2]])
N_CONFIGS = 10_000  # random configurations, spread over the poses and the targets
SPHERES_AGREE = 0.995  # share of configurations where the JAX test and the sphere checker agree
FRAME_ATOL = 1e-5  # [m] float32 FK against MuJoCo's float64 body positions


@pytest.fixture(scope="module")
def demo():
    """The demo's scenario, docking problem (with the planner's world) and planning margin."""
    with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
        cfg = OmegaConf.to_container(compose("pipeline"), resolve=True)
        docking = OmegaConf.to_container(compose("docking", overrides=["docking/preset=demo"]), resolve=True)
    scenario, margin = cfg["scenario"], cfg["plan"]["margin"]
    settings = from_mapping(evo.DockingSettings, docking)
    task = plan.docking_task(plan.build_scene(BRAVO7, scenario), vehicle=settings.scene, margin=margin)
    return scenario, evo.docking_problem(settings.scene, "float32", task, BRAVO7), margin


def _planner(scenario, problem, pose, margin):
    """The docked scene of a vehicle pose, its MuJoCo checker and sphere checker, the targets'
    contexts (docking_task's order) and the arm's base pose."""
    _, T_world_base, spec = docked_scene(scenario, problem, pose)
    scene = plan.build_scene(BRAVO7, spec)
    reference = plan.CollisionChecker(scene, margin)
    contexts = [plan.node_contexts(scene, n) for n in sorted(scene.objects) + sorted(scene.bases)]
    return reference, plan.SphereChecker(reference), [(c["down"], c["up"]) for c in contexts], T_world_base


def test_jax_frames_are_mujocos_bodies(demo):
    scenario, problem, margin = demo
    reference, *_, T_world_base = _planner(scenario, problem, POSES[0], margin)
    m, d = reference.scene.model, mujoco.MjData(reference.scene.model)
    q = np.random.default_rng(0).uniform(BRAVO7.lower, BRAVO7.upper, (20, BRAVO7.n_joints))
    T = np.asarray(kin.kinematics(problem.chain, jnp.asarray(q, jnp.float32)).T_base_joint)
    ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, n) for n in BRAVO7.link_names]
    for qi, Ti in zip(q, T):
        d.qpos[:] = qi
        mujoco.mj_kinematics(m, d)
        np.testing.assert_allclose(T_world_base[:3, :3] @ Ti[:, :3, 3].T + T_world_base[:3, 3:], d.xpos[ids].T,
                                   atol=FRAME_ATOL)
        np.testing.assert_allclose(T_world_base[:3, :3] @ Ti[:, :3, :3], d.xmat[ids].reshape(-1, 3, 3), atol=FRAME_ATOL)


def test_random_configurations_agree_on_the_safe_side(demo):
    """1e4 configurations, uniform in the joint limits, at two docked poses and every target:
    the JAX test calls a collision wherever the sphere checker or MuJoCo does (in any of the
    target's contexts), and agrees with the sphere checker on nearly all; its GPU kernel
    gives the same answers as its XLA form."""
    scenario, problem, margin = demo
    n_rows = problem.n_groups
    per = N_CONFIGS // (len(POSES) * n_rows)
    rng = np.random.default_rng(1)
    Q = rng.uniform(BRAVO7.lower, BRAVO7.upper, (len(POSES), n_rows, per, BRAVO7.n_joints))
    T_world_base = np.stack([docked_scene(scenario, problem, p)[1] for p in POSES])
    frames = kin.kinematics(problem.chain, jnp.asarray(Q, jnp.float32)).T_base_joint
    args = (problem.world, jnp.arange(n_rows), jnp.asarray(T_world_base, jnp.float32), frames)
    jax_free = ~np.asarray(jax.jit(evo.world_collides)(*args))
    kernel = jax.jit(lambda *a: _world_gpu.world_collides_kernel(*a, interpret=True))  # the GPU path, emulated
    np.testing.assert_array_equal(~np.asarray(kernel(*args)), jax_free)
    spheres_free, mujoco_free = np.zeros_like(jax_free), np.zeros_like(jax_free)
    for i, pose in enumerate(POSES):
        reference, spheres, contexts, _ = _planner(scenario, problem, pose, margin)
        for r, ctxs in enumerate(contexts):
            spheres_free[i, r] = np.logical_and.reduce([spheres.spheres_free(Q[i, r], c) for c in ctxs])
            mujoco_free[i, r] = np.logical_and.reduce([reference.is_valid_batch(Q[i, r], c) for c in ctxs])
    n = jax_free.size
    rates = {"configurations": n, "jax_free": jax_free.mean(), "agree_spheres": np.mean(jax_free == spheres_free),
             "agree_mujoco": np.mean(jax_free == mujoco_free),
             "jax_collision_spheres_free": int(np.sum(~jax_free & spheres_free)),
             "jax_collision_mujoco_free": int(np.sum(~jax_free & mujoco_free))}
    print("one world:", {k: round(float(v), 4) for k, v in rates.items()})
    assert n == N_CONFIGS
    assert not np.any(jax_free & ~spheres_free)  # the safe side only
    assert not np.any(jax_free & ~mujoco_free)
    assert rates["agree_spheres"] >= SPHERES_AGREE
    assert 0.1 < rates["jax_free"] < 0.9  # both answers occur


def test_every_accepted_target_configuration_is_valid_for_the_planner(demo):
    """At the demo's docked pose and a second one, each IK solution the docking fitness counts
    (reached, within the limits, free in the world) passes the planner's MuJoCo check in both
    contexts of its target (the way down and the way up, margin included)."""
    scenario, problem, margin = demo
    q, valid, _ = (np.asarray(a) for a in evo.arm_solutions_jit(problem, jnp.asarray(POSES, jnp.float32)))
    group = np.asarray(problem.group)
    checked = 0
    for i, pose in enumerate(POSES):
        reference, spheres, contexts, _ = _planner(scenario, problem, pose, margin)
        for k, s in zip(*np.nonzero(valid[i])):
            for ctx in contexts[group[k]]:
                assert reference.is_valid(q[i, k, s], ctx), (pose, k, s, reference.contacts(q[i, k, s], ctx))
                assert spheres.spheres_free(q[i, k, s][None], ctx)[0]
            checked += 1
    assert checked >= 20  # the poses reach their targets with many solutions
