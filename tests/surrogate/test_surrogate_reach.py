"""The learned docking fitness: the map's inputs, its samples against the analytic IK, its error
on samples it never saw, the corrected map against the analytic fitness, and docking with it."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from uvms_jax import evo, surrogate
from uvms_jax.surrogate._reach import _best_w, _sample_tool_poses

BATCH = 4  # vehicle poses per analytic call below: one shape, one compile of the IK
# A pose's analytic fitness (float32) scored again in a batch of another shape: measured
# bit-identical in batches of 4 and 16 under XLA's default, AVX and SSE4.2 ISAs on an Intel Xeon;
# it differs by up to 1.1e-6 (relative) between those ISAs. The tolerance is 10× that.
REEVALUATED_RTOL = 1e-5
# A sample's label against the analytic report's w (float32, two code paths to the same IK):
# measured at most 7.7e-7 relative (w > 1e-3), 1.1e-8 absolute (w ≤ 0.015), under XLA's default,
# AVX and SSE4.2 ISAs on an Intel Xeon; the tolerances are ~100× those.
LABEL_RTOL, LABEL_ATOL = 1e-4, 1e-6


@pytest.fixture(scope="module")
def problem():
    """The Bravo 7 under its vehicle beside a panel: 4 corners, a box where some poses reach
    them all; few IK seeds (small and fast)."""
    scene = evo.ArmSceneSettings(panel=evo.PanelSettings(points_per_side=2), pose_low=(-1.3, -0.5, -0.1, -0.6),
                                 pose_high=(-0.8, 0.0, 0.4, 1.2), ik_seeds=6, ik_iterations=25)
    return evo.arm_docking_problem(scene, dtype=jnp.float32)


# The panel's corners are approached sideways: the map samples every approach (a cone of 180°).
SETTINGS = surrogate.ReachMapSettings(n_samples=4096, approach_cone_deg=180.0, hidden=32, steps=1500, chunk=256,
                                      candidates=BATCH, refine_iterations=3, refine_stages=2)


@pytest.fixture(scope="module")
def run(problem):
    return surrogate.run_reach_map(problem, SETTINGS)


def _pose(rpy, xyz) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", rpy).as_matrix()
    T[:3, 3] = xyz
    return T


def test_features_by_hand_and_blind_to_a_turn_about_the_base_axis():
    T = _pose([0.3, -0.2, 1.1], [0.3, -0.4, 0.7])
    x = np.asarray(surrogate.reach_features(jnp.asarray(T)))
    a = np.arctan2(-0.4, 0.3)
    unturn = Rotation.from_euler("z", -a).as_matrix()
    np.testing.assert_allclose(x, np.concatenate([[0.5, 0.7, np.cos(a), np.sin(a)], unturn @ T[:3, 0],
                                                  unturn @ T[:3, 2]]), atol=1e-6)
    turned = _pose([0, 0, 0.8], [0, 0, 0]) @ T  # the same tool pose, the arm's first joint turned
    y = np.asarray(surrogate.reach_features(jnp.asarray(turned)))
    np.testing.assert_allclose(np.delete(y, [2, 3]), np.delete(x, [2, 3]), atol=1e-6)


def test_samples_approach_within_the_cone_and_are_rotations(problem):
    T = np.asarray(_sample_tool_poses(jax.random.key(0), problem, 512, 30.0, 0.03))
    R = T[:, :3, :3]
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-5)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-5)
    # The tool's z axis in the world (the vehicle only yaws: at ψ = 0 the base's rotation is the mount's).
    z_world = np.asarray(problem.T_vehicle_base)[:3, :3] @ R[:, :, 2].T
    angle = np.degrees(np.arccos(np.clip(-z_world[2], -1, 1)))
    assert angle.max() <= 30.0 + 1e-3 and angle.max() > 25.0  # fills the cone, never leaves it


def test_labels_are_the_analytic_w_without_the_scene(problem):
    """A sample's label is the w the analytic fitness finds for that tool pose: the tool poses
    of vehicle poses seen from the base, labelled, equal the analytic report's w there."""
    free = problem.replace(T_world_box=jnp.zeros((0, 4, 4)), scene_half=jnp.zeros((0, 3)))
    poses = jax.random.uniform(jax.random.key(3), (BATCH, 4), jnp.float32, problem.pose_low, problem.pose_high)
    T = evo.arm_tool_poses(problem, poses)[2]  # (BATCH, k, 4, 4)
    labels = np.asarray(_best_w(problem, T.reshape(-1, 4, 4))).reshape(BATCH, -1)
    w = evo.arm_report(free, poses).w
    assert np.any(w > 0)
    np.testing.assert_allclose(labels, w, rtol=LABEL_RTOL, atol=LABEL_ATOL)


def test_map_beats_the_mean_on_held_out_samples(run):
    assert run.n_train + run.n_test == SETTINGS.n_samples and 0 < run.test["reached_fraction"] < 1
    # Held-out error under the spread of w (predicting the mean would score the spread).
    assert run.test["rmse_w"] < 0.8 * run.test["w_std"], run.test
    assert run.history[-1] < run.history[0]


def test_the_corrected_map_is_the_analytic_fitness_at_its_pose(problem, run):
    """Shifted by the analytic w minus its own at a pose, the map's fitness there is the analytic
    one (the trust-region step's model agrees with the fitness where it stands)."""
    poses = jax.random.uniform(jax.random.key(4), (BATCH, 4), jnp.float32, problem.pose_low, problem.pose_high)
    report = evo.arm_report(problem, poses)
    learned = surrogate.SurrogateDockingProblem(problem, run.reach, jnp.zeros(problem.group.shape))
    for i in range(BATCH):
        own = learned.reach(evo.arm_tool_poses(problem, poses[i])[2])
        corrected = learned.replace(shift=jnp.asarray(report.w[i]) - own)
        np.testing.assert_allclose(corrected.fitness(poses[i]), report.terms.fitness[i], rtol=REEVALUATED_RTOL,
                                   atol=1e-5)


def test_docking_reports_the_analytic_fitness_of_its_pose(problem, run):
    ga = evo.GASettings(population_size=16, max_generations=8, eval_chunk=None)
    md = surrogate.dock_with_map(problem, run, ga, n_runs=2, seed=0, timing_batch=BATCH)
    s = SETTINGS
    assert md.candidates.shape[1] == 4 and s.candidates <= md.analytic_evaluations <= s.candidates + s.refine_iterations
    assert md.map_evaluations > 0 and md.eval_seconds > 0
    # The reported score is the analytic fitness at the returned pose (scored in a batch of BATCH,
    # the shape the analytic calls above are compiled for; the fitness is per pose).
    ref = evo.evaluate_arm(problem, np.resize(md.pose, (BATCH, 4)))
    np.testing.assert_allclose(md.fitness, ref.fitness[0], rtol=REEVALUATED_RTOL)
    np.testing.assert_allclose(md.M_a, ref.M_a[0], rtol=REEVALUATED_RTOL)
    # Refinement keeps the best analytic score: never below the best candidate, never falling.
    assert md.refine_fitness[0] == pytest.approx(float(np.max(md.candidate_fitness)))
    assert np.all(np.diff(md.refine_fitness) >= 0) and md.fitness == md.refine_fitness[-1]


def test_a_task_outside_the_sampled_cone_is_refused(problem, run):
    narrow = surrogate.ReachMapRun(run.reach, surrogate.ReachMapSettings(approach_cone_deg=30.0), run.n_train,
                                   run.n_test, run.analytic_seconds, run.train_seconds, run.history, run.test)
    with pytest.raises(ValueError, match="outside the map's sampled cone of 30.0°"):
        surrogate.dock_with_map(problem, narrow, evo.GASettings(), n_runs=1, seed=0)


def test_settings_are_checked():
    with pytest.raises(ValueError, match="n_samples"):
        surrogate.ReachMapSettings(n_samples=3)
    with pytest.raises(ValueError, match="refine_width"):
        surrogate.ReachMapSettings(refine_width=0)
