"""Metrics, time parameterisation, interpolation, task graph, metric tensor and settings."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from uvms_jax import kin, sched
from uvms_jax.plan import (
    EdgeMetrics,
    EdgeResult,
    IkSettings,
    PlanJsonSettings,
    PlanResult,
    PlanSettings,
    build_scene,
    densify,
    edge_endpoints,
    goal_node,
    metric_tensor,
    task_edges,
    time_parameterize,
    trajectory_metrics,
)
from uvms_jax.settings import SettingsError, from_mapping
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

CONFIGS = Path(__file__).parents[2] / "configs"
SCENARIO = CONFIGS / "scenario" / "thesis_cage.yaml"
ATOL = 1e-9  # float64 throughout; hand formulas vs code differ only by round-off
WEIGHTLESS = {"gravity_base": np.zeros(3), "water_density": 0.0}  # only the held object's force


@pytest.fixture(scope="module")
def scene():
    return build_scene(BRAVO7, yaml.safe_load(SCENARIO.read_text()))


def test_two_point_metrics_by_hand(scene):
    """Rotate joint G alone by Δ: Σ|Δq| = Δ; the tool moves on a circle about G's axis, so
    the two-point distance is the chord 2 r sin(Δ/2); a vertical force f (along G's axis)
    gives τ_G = 0 and τ_i = ((p − o_i) × f) · ω_i on the other joints."""
    chain = BRAVO7.chain
    q0 = np.asarray(scene.start_q)
    delta = 0.3
    q1 = q0 + np.array([delta, 0, 0, 0, 0, 0])
    f = np.array([0.0, 0.0, -1.2])  # base frame: along G's axis (z)
    jm, ee, tau = trajectory_metrics(BRAVO7, np.stack([q0, q1]), f, **WEIGHTLESS)
    assert jm == pytest.approx(delta, abs=ATOL)
    k0 = kin.kinematics(chain, q0)  # one compiled FK pass gives the joint frames and the tool
    frames, p = np.asarray(k0.T_base_joint), np.asarray(k0.T_base_tool)[:3, 3]
    o_g, w_g = frames[0, :3, 3], frames[0, :3, 2]  # joint G's axis is ∓z of its frame
    r = np.linalg.norm(np.cross(p - o_g, w_g))
    assert ee == pytest.approx(2 * r * np.sin(delta / 2), abs=ATOL)
    axes = [np.array(j.axis) for j in kin.BRAVO7_JOINTS]

    def torques(q):
        k = kin.kinematics(chain, q)
        fr, pt = np.asarray(k.T_base_joint), np.asarray(k.T_base_tool)[:3, 3]
        return np.array([np.dot(np.cross(pt - fr[i, :3, 3], f), fr[i, :3, :3] @ axes[i]) for i in range(6)])

    t0, t1 = torques(q0), torques(q1)
    assert abs(t0[0]) < ATOL
    assert tau == pytest.approx(max(np.abs(t0).max(), np.abs(t1).max()), abs=ATOL)
    # Nothing held and a weightless arm: no torque (tests/plan/test_plan_torque.py weighs the arm).
    assert trajectory_metrics(BRAVO7, np.stack([q0, q1]), **WEIGHTLESS)[2] == 0.0


def test_metrics_reject_bad_input():
    with pytest.raises(ValueError, match="finite"):
        trajectory_metrics(BRAVO7, np.full((2, 6), np.nan), **WEIGHTLESS)


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


def _edge(src, dst, values, success=True):
    path = np.zeros((2, 6))
    metrics = EdgeMetrics(*values) if success else None
    return EdgeResult("RRTConnect", src, dst, PlanResult(success, path, values[0], 1), None, metrics, {})


def test_metric_tensor_feeds_sched(scene):
    """Rows land at (src, dst) in sched.METRICS order; failed and forbidden moves are NaN, and
    sched's normalisation inverts security (larger clearance costs less)."""
    n = goal_node(scene) + 1
    results = [_edge(0, 1, (1.0, 2.0, 3.0, 0.1, 5.0)), _edge(1, 5, (3.0, 4.0, 5.0, 0.3, 7.0)),
               _edge(5, 9, (9.0,) * 5, success=False)]
    m = metric_tensor(scene, results)
    assert m.shape == (len(sched.METRICS), n, n)
    np.testing.assert_array_equal(m[:, 0, 1], [1.0, 2.0, 3.0, 0.1, 5.0])
    assert np.isnan(m[:, 5, 9]).all() and np.isnan(m[:, 2, 2]).all()
    assert EdgeMetrics._fields == sched.METRICS
    z = sched.normalise_metrics(m)
    security = sched.METRICS.index("security")
    assert z[security, 0, 1] == 1.0 and z[security, 1, 5] == 0.0
    assert z[0, 0, 1] == 0.0 and z[0, 1, 5] == 1.0


def test_settings_mirror_the_config():
    """configs/plan/default.yaml gives exactly the dataclass defaults; bad values are named."""
    raw = yaml.safe_load((CONFIGS / "plan" / "default.yaml").read_text())
    settings = from_mapping(PlanSettings, raw)
    assert settings == PlanSettings()
    assert settings.weight_vector() == tuple(raw["weights"][m] for m in sched.METRICS)
    assert PlanSettings(weights={"security": 1.0}).weight_vector() == (0.0, 0.0, 0.0, 1.0, 0.0)
    with pytest.raises(ValueError, match="unknown metrics"):
        PlanSettings(weights={"speed": 1.0})
    with pytest.raises(ValueError, match="unknown planners"):
        PlanSettings(planners=("RRT*",))
    with pytest.raises(ValueError, match="budget_s"):
        PlanSettings(budget_s=0.0)
    with pytest.raises(ValueError, match="n_seeds"):
        IkSettings(n_seeds=0)
    with pytest.raises(ValueError, match="sequence"):
        PlanJsonSettings(sequence=(0,))
    with pytest.raises(SettingsError, match="ik"):
        from_mapping(PlanSettings, {"ik": {"seeds": 3}})


def test_plan_does_not_import_hw():
    """Layers: planning reaches the hardware only through the plan.json format."""
    code = "import sys, uvms_jax.plan; print([m for m in sys.modules if m.startswith('uvms_jax.hw')])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
