"""w_max map over the task area (paper eq. 16) and its consistency with M_a (eq. 1)."""

import numpy as np
import pytest

from uvms_jax import evo, papers

BEST_NEAR = (-0.4755, -0.002, 0.1476, 0.905)
ILL_PLACED = papers.D11_ILL_PLACED_POSE


@pytest.fixture(scope="module")
def problem(scene):
    return evo.make_docking_problem(**scene)


@pytest.mark.parametrize("pose", [BEST_NEAR, ILL_PLACED, (0.0, -0.5, 0.25, 2.0)])
def test_map_corners_and_min_match_area_manipulability(problem, pose, scene):
    m = evo.wmax_map(problem, pose, n_per_side=5)
    assert m.w_max.shape == (5, 5) and np.all(m.w_max >= 0)
    corners = m.w_max[[0, 0, -1, -1], [0, -1, 0, -1]]
    np.testing.assert_allclose(corners.min(), float(evo.evaluate(problem, pose).M_a), atol=1e-12)
    dense = evo.make_docking_problem(**{**scene, "control_points_per_side": 5})
    np.testing.assert_allclose(m.w_max.min(), float(evo.evaluate(dense, pose).M_a), atol=1e-12)


def test_ill_placed_pose_leaves_more_zero_area(problem):
    good = evo.wmax_map(problem, BEST_NEAR, n_per_side=21)
    bad = evo.wmax_map(problem, ILL_PLACED, n_per_side=21)
    assert bad.zero_fraction > good.zero_fraction
    assert 0.0 <= good.zero_fraction <= 1.0 and bad.zero_fraction > 0.1
