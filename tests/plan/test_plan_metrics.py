"""Metrics, time parameterisation, interpolation, task graph and cost matrix."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from uvms_jax import kin
from uvms_jax.plan import (
    METRIC_NAMES,
    build_scene,
    cost_matrix,
    densify,
    edge_endpoints,
    goal_node,
    task_edges,
    time_parameterize,
    trajectory_metrics,
)

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
ATOL = 1e-9  # float64 throughout; hand formulas vs code differ only by round-off


@pytest.fixture(scope="module")
def scene():
    return build_scene(yaml.safe_load(SCENARIO.read_text()))


def test_two_point_metrics_by_hand(scene):
    """Rotate joint G alone by Δ: Σ|Δq| = Δ; the tool moves on a circle about G's axis, so
    the two-point distance is the chord 2 r sin(Δ/2); a vertical force f (along G's axis)
    gives τ_G = 0 and τ_i = ((p − o_i) × f) · ω_i on the other joints."""
    chain = kin.bravo7()
    q0 = np.asarray(scene.spec.start_q)
    delta = 0.3
    q1 = q0 + np.array([delta, 0, 0, 0, 0, 0])
    f = np.array([0.0, 0.0, -1.2])  # base frame: along G's axis (z)
    jm, ee, tau = trajectory_metrics(chain, np.stack([q0, q1]), f)
    assert jm == pytest.approx(delta, abs=ATOL)
    frames = np.asarray(kin.kinematics(chain, q0).T_base_joint)
    p = np.asarray(kin.fk(chain, q0))[:3, 3]
    o_g, w_g = frames[0, :3, 3], frames[0, :3, 2]  # joint G's axis is ∓z of its frame
    r = np.linalg.norm(np.cross(p - o_g, w_g))
    assert ee == pytest.approx(2 * r * np.sin(delta / 2), abs=ATOL)
    axes = [np.array(j.axis) for j in kin.BRAVO7_JOINTS]

    def torques(q):
        fr = np.asarray(kin.kinematics(chain, q).T_base_joint)
        pt = np.asarray(kin.fk(chain, q))[:3, 3]
        return np.array([np.dot(np.cross(pt - fr[i, :3, 3], f), fr[i, :3, :3] @ axes[i]) for i in range(6)])

    t0, t1 = torques(q0), torques(q1)
    assert abs(t0[0]) < ATOL
    assert tau == pytest.approx(max(np.abs(t0).max(), np.abs(t1).max()), abs=ATOL)
    # Nothing held: no torque from a payload.
    assert trajectory_metrics(chain, np.stack([q0, q1]))[2] == 0.0


def test_metrics_reject_bad_input():
    with pytest.raises(ValueError, match="finite"):
        trajectory_metrics(kin.bravo7(), np.full((2, 6), np.nan))


def test_time_parameterisation_synchronised():
    """Δq = (1, 0.5, 0…), v = 0.5, a = 1: r_v = 2, r_a = 1 → trapezoid, T = r_v + r_a/r_v = 2.5 s."""
    path = np.zeros((2, 6))
    path[1, :2] = [1.0, 0.5]
    traj = time_parameterize(path, 0.5, 1.0)
    assert traj.t[-1] == pytest.approx(2.5, rel=1e-6)
    t, q, qd = traj.sample(0.01)
    assert np.all(np.abs(qd) <= 0.5 + 1e-9)
    acc = np.diff(qd, axis=0) / np.diff(t)[:, None]
    assert np.all(np.abs(acc) <= 1.0 + 1e-6)
    # Synchronised: joint 2 is always half of joint 1 (both start and arrive together).
    np.testing.assert_allclose(q[:, 1], 0.5 * q[:, 0], atol=1e-12)
    np.testing.assert_allclose(q[-1], path[-1], atol=1e-12)


def test_densify_keeps_waypoints_and_step():
    path = np.array([[0.0] * 6, [0.5, 0, 0, 0, 0, 0.1], [0.5, 0.3, 0, 0, 0, 0.1]])
    d = densify(path, 0.01)
    assert np.max(np.abs(np.diff(d, axis=0))) <= 0.01 + 1e-12
    for w in path:
        assert np.min(np.max(np.abs(d - w), axis=1)) < 1e-12
    assert len(densify(path[:1], 0.01)) == 1


def test_task_graph_thesis_structure(scene):
    edges = task_edges(scene)
    goal = goal_node(scene)
    assert goal == 9 and len(edges) == 34
    assert {(0, o) for o in (1, 2, 3, 4)} <= set(edges)
    assert {d for s, d in edges if s == 1} == {5, 6} and {d for s, d in edges if s == 3} == {7}
    assert {d for s, d in edges if s == 4} == {8}
    assert all({d for s, d in edges if s == b} == {0, 1, 2, 3, 4, 9} for b in (5, 6, 7, 8))
    assert not any(s == goal for s, _ in edges)
    with pytest.raises(ValueError, match="not in the task graph"):
        edge_endpoints(scene, {}, 1, 7)


def test_cost_matrix_normalisation():
    n = 3
    mats = {k: np.full((n, n), np.nan) for k in METRIC_NAMES}
    for k in METRIC_NAMES:
        mats[k][0, 1], mats[k][1, 2] = 1.0, 3.0
    C = cost_matrix(mats)
    assert np.isnan(C[0, 0]) and np.isnan(C[2, 1])
    # Four metrics: lower is better (0 at the min, 1 at the max); clearance inverted.
    assert C[0, 1] == pytest.approx(1 / 5) and C[1, 2] == pytest.approx(4 / 5)
    with pytest.raises(ValueError, match="unknown metrics"):
        cost_matrix(mats, {"speed": 1.0})
