"""Docking objective (paper eq. 1, 3, 14, 15) against a plain NumPy loop reference."""

import jax
import numpy as np
import pytest

from uvms_jax import evo, kin, papers

# Float64 throughout (conftest); the reference shares only elbow_ik and the Jacobian with
# the code under test, so differences are rounding in the pose algebra.
FIT_ATOL = 1e-9

BEST_NEAR = (-0.4755, -0.002, 0.1476, 0.905)  # near the optimum found by grid search
PAPER_BEST = tuple(papers.D11_TABLE3[0, :4])  # Table 3, run 1
ILL_PLACED = papers.D11_ILL_PLACED_POSE  # paper, Fig. 10
FEASIBLE = [BEST_NEAR, PAPER_BEST, ILL_PLACED, (-0.45, 0.0, 0.2, 0.0), (0.0, -0.45, 0.2, 1.2), (0.45, 0.05, 0.25, 3.0)]
INFEASIBLE = [
    (0.1, 0.1, 0.2, 0.0),  # over the task area
    (-0.45, 0.0, 0.35, 0.9),  # above z_A + d
    (-0.45, 0.0, -0.01, 0.9),  # below the face
    (-1.2, 0.0, 0.1, 0.0),  # off the face
    (0.0, 1.05, 0.1, 0.0),  # off the face
]


def _rz(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _skew(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _exp_revolute(xi, theta):
    """exp of a unit revolute twist [v, ω] (Murray et al. eq. 2.36)."""
    v, w = xi[:3], xi[3:]
    W = _skew(w)
    R = np.eye(3) + np.sin(theta) * W + (1.0 - np.cos(theta)) * W @ W
    g = np.eye(4)
    g[:3, :3] = R
    g[:3, 3] = (np.eye(3) - R) @ np.cross(w, v) + np.outer(w, w) @ v * theta
    return g


def _jacobian(chain, q):
    """Geometric Jacobian (tool-point velocity; angular velocity) in plain NumPy, from the
    spatial twists ξ'_i = Ad(exp(ξ1 q1)…exp(ξ(i-1) q(i-1))) ξ_i."""
    twists, T0 = np.asarray(chain.twists), np.asarray(chain.T_base_tool0)
    g = np.eye(4)
    cols = []
    for xi, qi in zip(twists, q):
        R, p = g[:3, :3], g[:3, 3]
        w = R @ xi[3:]
        cols.append((R @ xi[:3] + np.cross(p, w), w))
        g = g @ _exp_revolute(xi, qi)
    p_tool = (g @ T0)[:3, 3]
    return np.array([np.concatenate([v + np.cross(w, p_tool), w]) for v, w in cols]).T


def reference(poses, points, scene):
    """Plain loops: per control point, max of sqrt(det(J Jᵀ)) over valid IK branches; then
    min over points; D and Wd per pose. Returns ``(fitness, M_a, D, in_wd)`` lists."""
    a, b, d, p_bp = scene["a"], scene["b"], scene["d"], np.asarray(scene["p_bp"])
    p_init, psi_init = np.asarray(scene["p_init"]), scene["psi_init"]
    face_half, task_half = scene["block_size"][0] / 2, scene["task_size"] / 2
    assert scene["block_size"][0] == scene["block_size"][1] and scene["task_center"] == [0.0, 0.0, 0.0]
    assert scene["yaw_mode"] == "heading"
    chain = kin.docking_arm(*scene["arm_lengths"])
    targets = []
    for x, y, z, psi in poses:
        R_gb, p_gb = _rz(psi), np.array([x, y, z])
        c, s = np.cos(psi), np.sin(psi)
        # Tool: approach (x) down, z along the heading, y = z × x.
        R_gt = np.column_stack([[0.0, 0.0, -1.0], [-s, c, 0.0], [c, s, 0.0]])
        for p in points:
            T = np.eye(4)
            T[:3, :3] = R_gb.T @ R_gt
            T[:3, 3] = R_gb.T @ (np.asarray(p) - p_gb)
            targets.append(T)
    sol = kin.elbow_ik(chain, np.stack(targets))  # one call; the logic below is NumPy
    q_all, valid_all = np.asarray(sol.q), np.asarray(sol.valid)
    out = []
    for k, (x, y, z, psi) in enumerate(poses):
        per_point = []
        for j in range(len(points)):
            t = k * len(points) + j
            best = 0.0
            for i in range(q_all.shape[1]):
                if valid_all[t, i]:
                    J = _jacobian(chain, q_all[t, i])
                    best = max(best, float(np.sqrt(max(np.linalg.det(J @ J.T), 0.0))))
            per_point.append(best)
        M_a = min(per_point)
        p_i = p_init + _rz(psi_init) @ p_bp
        p_d = np.array([x, y, z]) + _rz(psi) @ p_bp
        D = float(np.sqrt(np.sum((p_i - p_d) ** 2)))
        in_wd = abs(x) <= face_half and abs(y) <= face_half and 0.0 <= z <= d and not (
            abs(x) < task_half and abs(y) < task_half
        )
        out.append(((a * M_a - b * D) if in_wd else 0.0, M_a, D, in_wd))
    return out


@pytest.fixture(scope="module")
def problem(scene):
    return evo.make_docking_problem(**scene)


@pytest.fixture(scope="module")
def random_poses():
    rng = np.random.default_rng(3)
    return rng.uniform([-1.0, -1.0, 0.0, -np.pi], [1.0, 1.0, 0.3, np.pi], size=(10, 4))


@pytest.fixture(scope="module")
def all_poses(random_poses):
    """``(21, 4)`` the feasible, infeasible and random poses: a batch size (one compile of the
    objective's pose algebra) that several tests below share; ``evaluate`` is per pose, so
    slices of it stand for the smaller sets."""
    return np.concatenate([np.array(FEASIBLE + INFEASIBLE), random_poses])


_INFEASIBLE = slice(len(FEASIBLE), len(FEASIBLE) + len(INFEASIBLE))


def test_fitness_matches_numpy_loop(problem, all_poses, scene):
    poses = all_poses
    got = jax.tree_util.tree_map(np.asarray, evo.evaluate(problem, poses))  # NumPy once, then index
    corners = np.asarray(problem.p_control)
    assert corners.shape == (4, 3)
    for k, (pose, (f, M_a, D, in_wd)) in enumerate(zip(poses, reference(poses, corners, scene))):
        assert bool(got.feasible[k]) == in_wd, pose
        np.testing.assert_allclose(float(got.M_a[k]), M_a, atol=FIT_ATOL, err_msg=str(pose))
        np.testing.assert_allclose(float(got.D[k]), D, atol=FIT_ATOL, err_msg=str(pose))
        np.testing.assert_allclose(float(got.fitness[k]), f, atol=FIT_ATOL, err_msg=str(pose))
    # The reference set exercises both M_a > 0 and M_a = 0 inside Wd.
    assert np.any(got.M_a[: len(FEASIBLE)] > 0) and np.any(got.M_a[: len(FEASIBLE)] == 0)


def test_outside_search_set_is_zero(problem, all_poses):
    got = jax.tree_util.tree_map(lambda x: np.asarray(x)[_INFEASIBLE], evo.evaluate(problem, all_poses))
    assert np.array_equal(all_poses[_INFEASIBLE], np.array(INFEASIBLE))
    assert not np.any(got.feasible)
    np.testing.assert_array_equal(got.fitness, 0.0)
    # Not trivially zero: some of these poses do reach the whole task area.
    assert np.any(got.M_a > 0)


def test_denser_control_grid_never_raises_area_manipulability(problem, random_poses, scene):
    dense = evo.make_docking_problem(**{**scene, "control_points_per_side": 5})
    # 16 poses × 25 points stay within the IK's smallest padded target bucket (512): no new IK compile.
    poses = np.concatenate([np.array(FEASIBLE), random_poses])
    m2 = np.asarray(evo.evaluate(problem, poses).M_a)
    m5 = np.asarray(evo.evaluate(dense, poses).M_a)
    assert np.all(m5 <= m2 + 1e-12)
    assert np.any(m2 > 0)


# (3, 7) flattens to the 21 poses of ``all_poses``: the same compiled batch; (4,) and (1, 1)
# share the one-pose batch of test_fixed_tool_yaw_mode.
@pytest.mark.parametrize("shape", [(4,), (3, 7, 4), (1, 1, 4)])
def test_batch_shapes(problem, shape):
    rng = np.random.default_rng(0)
    poses = rng.uniform([-1.0, -1.0, 0.0, -np.pi], [1.0, 1.0, 0.3, np.pi], size=shape)
    got = evo.evaluate(problem, poses)
    flat = evo.evaluate(problem, poses.reshape(-1, 4))
    assert got.fitness.shape == shape[:-1]
    np.testing.assert_allclose(np.asarray(got.fitness).ravel(), np.asarray(flat.fitness), atol=FIT_ATOL)


@pytest.mark.slow
def test_traced_fitness_equals_eager(problem, random_poses):
    """The jitted path used by the optimisers (one more compile of the IK graph)."""
    poses = np.concatenate([np.array(FEASIBLE + INFEASIBLE), random_poses])
    jitted = jax.jit(lambda p, x: p.fitness(x))(problem, poses)
    np.testing.assert_allclose(np.asarray(jitted), np.asarray(evo.evaluate(problem, poses).fitness), atol=FIT_ATOL)


def test_bad_input_is_rejected(problem, scene):
    with pytest.raises(ValueError, match="shape"):
        evo.evaluate(problem, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="NaN"):
        evo.evaluate(problem, np.array([np.nan, 0.0, 0.1, 0.0]))
    with pytest.raises(ValueError, match="yaw_mode"):
        evo.make_docking_problem(**{**scene, "yaw_mode": "sideways"})
    with pytest.raises(ValueError, match="fit"):
        evo.make_docking_problem(**{**scene, "task_size": 2.5})


def test_fixed_tool_yaw_mode(problem, scene):
    fixed = evo.make_docking_problem(**{**scene, "yaw_mode": "fixed", "tool_yaw": 0.3})
    pose = np.array([-0.45, 0.0, 0.2, 0.3])
    # With ψ = tool_yaw both modes demand the same tool orientation.
    np.testing.assert_allclose(float(evo.evaluate(fixed, pose).fitness), float(evo.evaluate(problem, pose).fitness), atol=FIT_ATOL)
