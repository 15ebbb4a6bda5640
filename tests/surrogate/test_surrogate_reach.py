"""The learned docking fitness: the map's inputs, its error against the analytic scores it never
saw, the surrogate problem's terms against the analytic ones, and the GA on the map."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from uvms_jax import evo, surrogate

BATCH = 32  # vehicle poses per analytic call everywhere below: one shape, one compile of the IK


@pytest.fixture(scope="module")
def problem():
    """The Bravo 7 under its vehicle beside a panel: 4 corners, a box where some poses reach
    them all; few IK seeds (small and fast)."""
    scene = evo.ArmSceneSettings(panel=evo.PanelSettings(points_per_side=2), pose_low=(-1.3, -0.5, -0.1, -0.6),
                                 pose_high=(-0.8, 0.0, 0.4, 1.2), ik_seeds=6, ik_iterations=25)
    return evo.arm_docking_problem(scene, dtype=jnp.float32)


def test_features_are_position_and_two_axes():
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", [0.3, -0.2, 1.1]).as_matrix()
    T[:3, 3] = [0.1, -0.4, 0.7]
    x = np.asarray(surrogate.reach_features(jnp.asarray(T)))
    np.testing.assert_allclose(x, np.concatenate([T[:3, 3], T[:3, 0], T[:3, 2]]), atol=1e-12)


def test_terms_from_one_w_per_pose_equal_the_analytic_terms(problem):
    """With the analytic best w of each tool pose in place of a map, the surrogate's formula
    (S = 1) gives the analytic fitness: eq. 15 is written once."""
    poses = jax.random.uniform(jax.random.key(3), (BATCH, 4), jnp.float32, problem.pose_low, problem.pose_high)
    _, _, w = evo.arm_solutions_jit(problem, poses)
    ours = jax.jit(evo.arm_terms)(problem, poses, jnp.max(w, axis=-1)[..., None])  # one compile, not op by op
    ref = evo.evaluate_arm(problem, poses)
    # float32 sums over the targets, fused differently in the two programs: a few ulp apart.
    np.testing.assert_allclose(ours.fitness, ref.fitness, rtol=1e-5)
    np.testing.assert_allclose(ours.M_a, ref.M_a, rtol=1e-5)


def test_map_beats_the_mean_on_held_out_poses_and_docks(problem):
    # chunk = infill: the analytic scoring of the dataset and of the infill poses is one compile.
    settings = surrogate.ReachMapSettings(n_poses=192, hidden=16, steps=1500, chunk=BATCH, rounds=2, infill=BATCH)
    run = surrogate.run_reach_map(problem, settings)
    assert run.n_train + run.n_test == 192 and run.train.w.shape == (run.n_train, 4)
    # Held-out error under the spread of w (predicting the mean would score the spread; 153 poses
    # train it here, the demo 800).
    assert run.test["rmse_w"] < 0.8 * float(np.std(run.train.w)), run.test
    assert run.history[-1] < run.history[0]
    ga = evo.GASettings(population_size=16, max_generations=8, eval_chunk=None)
    md = surrogate.dock_with_map(problem, run, ga, n_runs=2, seed=0, rounds=2, infill=BATCH, timing_batch=BATCH)
    assert md.poses.shape == (2, 4) and md.analytic_evaluations == BATCH and np.all(md.evaluations > 0)
    # The reported analytic scores are the analytic fitness at the returned poses (scored in a
    # batch of BATCH, the shape evaluate_arm is compiled for above; the fitness is per pose).
    ref = evo.evaluate_arm(problem, np.resize(md.poses, (BATCH, 4))).fitness[:2]
    np.testing.assert_allclose(md.fitness, ref, rtol=1e-5)
    assert md.eval_seconds > 0


def test_settings_are_checked():
    with pytest.raises(ValueError, match="n_poses"):
        surrogate.ReachMapSettings(n_poses=3)
    with pytest.raises(ValueError, match="rounds"):
        surrogate.ReachMapSettings(rounds=0)
