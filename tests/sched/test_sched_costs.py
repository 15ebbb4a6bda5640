"""Edge metrics → normalised metrics → cost matrix (thesis eqs. 4.15–4.17)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uvms_jax import sched

ATOL = 1e-12  # float64 arithmetic on values in [0, 1]


def _metrics(seed=0, n=10):
    rng = np.random.default_rng(seed)
    m = rng.random((5, n, n)) * np.array([2.0, 6.0, 1.5, 0.3, 9.0])[:, None, None]
    m[:, rng.random((n, n)) < 0.4] = np.nan
    return m


def test_min_max_normalisation_and_security_inverted():
    m = _metrics()
    nm = sched.normalise_metrics(m)
    edge = np.isfinite(m).all(axis=0)
    for k, name in enumerate(sched.METRICS):
        x, z = m[k][edge], nm[k][edge]
        assert z.min() == pytest.approx(0.0) and z.max() == pytest.approx(1.0)
        if name == "security":  # larger clearance, lower cost
            assert z[np.argmax(x)] == 0.0 and z[np.argmin(x)] == 1.0
            np.testing.assert_allclose(z, (x.max() - x) / (x.max() - x.min()), atol=ATOL)
        else:
            np.testing.assert_allclose(z, (x - x.min()) / (x.max() - x.min()), atol=ATOL)
    assert np.isnan(nm[:, ~edge]).all()


def test_constant_metric_normalises_to_zero():
    m = _metrics()
    m[2] = np.where(np.isnan(m[2]), np.nan, 0.7)
    nm = sched.normalise_metrics(m)
    assert np.nanmax(nm[2]) == 0.0


def test_cost_matrix_weights():
    nm = sched.normalise_metrics(_metrics())
    equal = sched.cost_matrix(nm, [0.2] * 5)
    np.testing.assert_allclose(equal, nm.mean(axis=0), atol=ATOL)
    only_security = sched.cost_matrix(nm, [0, 0, 0, 1, 0])
    np.testing.assert_allclose(only_security, nm[3], atol=ATOL)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(0, 1), min_size=5, max_size=5).filter(lambda w: sum(w) > 0), st.integers(0, 99))
def test_costs_lie_between_zero_and_the_weight_sum(weights, seed):
    c = sched.cost_matrix(sched.normalise_metrics(_metrics(seed)), weights)
    finite = c[np.isfinite(c)]
    assert (finite >= -ATOL).all() and (finite <= sum(weights) + ATOL).all()


@pytest.mark.parametrize(
    "weights, match",
    [([0.2] * 4, "need 5 weights"), ([0.2, 0.2, 0.2, 0.2, -0.2], ">= 0"), ([0] * 5, "all weights are zero"),
     ([np.nan, 0, 0, 0, 1], "finite")],
)
def test_bad_weights(weights, match):
    with pytest.raises(ValueError, match=match):
        sched.cost_matrix(sched.normalise_metrics(_metrics()), weights)


def test_bad_metrics():
    with pytest.raises(ValueError, match=r"shape \(5, n, n\)"):
        sched.normalise_metrics(np.zeros((4, 3, 3)))
    m = _metrics()
    m[0, 0, 1] = np.inf
    with pytest.raises(ValueError, match="±inf"):
        sched.normalise_metrics(m)


def test_metric_tensor_from_edge_rows():
    src, dst = np.array([0, 1, 5]), np.array([1, 5, 9])
    vals = np.arange(15, dtype=float).reshape(3, 5)
    m = sched.metric_tensor(src, dst, vals, 10)
    np.testing.assert_array_equal(m[:, 1, 5], vals[1])
    assert np.isnan(m[:, 0, 2]).all()
    with pytest.raises(ValueError, match="more than once"):
        sched.metric_tensor([0, 0], [1, 1], vals[:2], 10)
    with pytest.raises(ValueError, match="unknown dst node 12"):
        sched.metric_tensor([0], [12], vals[:1], 10)
    with pytest.raises(ValueError, match=r"shape \(E, 5\)"):
        sched.metric_tensor([0], [1], vals[:1, :4], 10)


def test_path_metric_sums_and_goal_mirror():
    nm = sched.normalise_metrics(_metrics())
    path = (0, 1, 5, 9)
    expected = nm[:, 0, 1] + nm[:, 1, 5] + nm[:, 5, 9]
    np.testing.assert_allclose(sched.path_metric_sums(nm, path), expected, atol=ATOL)
    m = _metrics()
    m[:, 5, 9] = np.nan
    mirrored = sched.mirror_goal(m, start=0, goal=9)
    np.testing.assert_array_equal(mirrored[:, 5, 9], m[:, 5, 0])


def test_path_totals_sum_and_bound_the_raw_metrics_of_each_move():
    """Along 0 → 2 → 1, written out move by move: the sums, the smallest clearance, the largest torque."""
    m = np.random.default_rng(3).random((5, 3, 3))  # every move allowed
    legs = [(0, 2), (2, 1)]
    k = {name: i for i, name in enumerate(sched.METRICS)}
    totals = sched.path_totals(m, [0, 2, 1])
    assert totals["planning_time_s"] == pytest.approx(m[k["planning_time"], 0, 2] + m[k["planning_time"], 2, 1])
    assert totals["joint_movement_rad"] == pytest.approx(m[k["joint_movement"], 0, 2] + m[k["joint_movement"], 2, 1])
    assert totals["ee_distance_m"] == pytest.approx(m[k["ee_distance"], 0, 2] + m[k["ee_distance"], 2, 1])
    assert totals["min_clearance_m"] == min(m[k["security"], a, b] for a, b in legs)
    assert totals["max_torque_Nm"] == max(m[k["max_torque"], a, b] for a, b in legs)
