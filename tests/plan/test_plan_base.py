"""The arm's base pose is a parameter of the scene: the MuJoCo arm, the IK targets and the
planned paths follow it."""

from pathlib import Path

import jax
import mujoco
import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from uvms_jax import kin
from uvms_jax.plan import (CollisionChecker, Context, IkSettings, build_scene, pick_place_targets, plan_motion,
                            seed_ompl)
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
FK_ATOL = 1e-9  # float64 FK of kin vs MuJoCo bodies: same maths, round-off only
POSE_ATOL = 1e-6  # float64 IK converges to 1e-8


def _moved(T_world_base: np.ndarray) -> np.ndarray:
    """The thesis mount turned 0.3 rad about the world z axis (the cage's vertical axis): the
    base moves 2 cm sideways and turns; the thesis's tight grasps stay reachable (a shift of
    3 cm towards the tables already makes node 2 infeasible)."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("z", 0.3).as_matrix()
    return T @ T_world_base


@pytest.fixture(scope="module")
def scenes():
    raw = yaml.safe_load(SCENARIO.read_text())
    home = build_scene(BRAVO7, raw)
    T_new = _moved(home.T_world_base)
    return home, build_scene(BRAVO7, raw, T_world_base=T_new), T_new


def test_base_pose_moves_the_mujoco_arm(scenes):
    home, moved, T_new = scenes
    chain = kin.bravo7()
    q = np.asarray(home.spec.start_q)
    # The tool site in MuJoCo sits at T · fk(q) (kin's FK the oracle), the base link at T.
    T_base_tool = np.asarray(kin.fk(chain, q))  # kin: the tool frame in the base frame
    for scene, T in ((home, home.spec.T_world_base), (moved, T_new)):
        d = mujoco.MjData(scene.model)
        d.qpos[:] = q
        mujoco.mj_kinematics(scene.model, d)
        tool = mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_SITE, "tool")
        np.testing.assert_allclose(d.site_xpos[tool], (T @ T_base_tool)[:3, 3], atol=FK_ATOL)
        base = mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_BODY, "base_link")
        np.testing.assert_allclose(d.xpos[base], T[:3, 3], atol=FK_ATOL)
        np.testing.assert_allclose(d.xmat[base].reshape(3, 3), T[:3, :3], atol=FK_ATOL)
    np.testing.assert_allclose(moved.T_world_base, T_new, atol=1e-12)
    # The mount plate moved with the base: its geom centre is half its height above the base.
    g = home.obstacle_geoms["mount"][0]
    d = mujoco.MjData(moved.model)
    mujoco.mj_kinematics(moved.model, d)
    above = T_new @ np.array([0.0, 0.0, -moved.spec.mount_size[2] / 2, 1.0])
    np.testing.assert_allclose(d.geom_xpos[g], above[:3], atol=FK_ATOL)


def test_base_pose_in_config_equals_base_pose_in_code(scenes):
    home, moved, T_new = scenes
    raw = yaml.safe_load(SCENARIO.read_text())
    raw["arm"]["mount_pos"] = T_new[:3, 3].tolist()
    raw["arm"]["mount_rpy"] = Rotation.from_matrix(T_new[:3, :3]).as_euler("xyz").tolist()
    np.testing.assert_allclose(build_scene(BRAVO7, raw).T_world_base, T_new, atol=1e-12)


@pytest.mark.parametrize("T", [np.eye(3), np.diag([1.0, 1.0, -1.0, 1.0]), np.full((4, 4), np.nan)])
def test_bad_base_pose_is_refused(scenes, T):
    with pytest.raises(ValueError, match="T_world_base"):
        scenes[0].spec.with_base(T)


def test_paths_in_the_moved_scene_are_collision_free(scenes):
    """Plans made in the moved scene pass the moved scene's dense re-check, and the same
    configurations mean different world poses than at home (the planner saw the new base)."""
    home, moved, _ = scenes
    seed_ompl(0)
    checker = CollisionChecker(moved)
    rng = np.random.default_rng(1)
    q0 = np.asarray(moved.spec.start_q)
    ctx = Context()
    assert checker.is_valid(q0, ctx)
    goals = [q for q in rng.uniform(checker.lower, checker.upper, (400, 6)) if checker.is_valid(q, ctx)][:3]
    assert len(goals) == 3
    for q1 in goals:
        r = plan_motion(checker, q0, q1, ctx, "RRTConnect", budget_s=5.0)
        assert r.success
        reference = CollisionChecker(moved)
        assert reference.path_is_valid(r.path, ctx, 0.005, margin=0.0)


@pytest.mark.slow  # one numerical-IK compile (~30 s on 2 cores)
def test_ik_targets_follow_the_base(scenes):
    _, moved, T_new = scenes
    checker = CollisionChecker(moved)
    targets = pick_place_targets(jax.random.PRNGKey(0), moved, checker, IkSettings(n_seeds=48))
    chain = kin.bravo7()
    for tg in targets.values():
        T_reached = T_new @ np.asarray(kin.fk(chain, tg.q_at))
        np.testing.assert_allclose(T_reached, tg.T_world_at, atol=POSE_ATOL)
        assert checker.is_valid(tg.q_pre, Context())  # arriving at an object, leaving a base
