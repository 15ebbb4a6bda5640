"""Batch scoring against the brute-force enumeration, and reason codes."""

import numpy as np
import pytest

from uvms_jax import sched

from _sched_bruteforce import all_schedules

COST_RTOL = 1e-6  # float32 sums of ≤ 13 costs in [0, 1]
R = sched.Reason


@pytest.fixture(scope="module")
def thesis():
    p = sched.thesis_problem()
    found = list(all_schedules(p.cost.tolist(), p.compat, p.start, p.goal))
    return p, found


def test_every_feasible_schedule_scores_its_cost(thesis):
    p, found = thesis
    paths = sched.as_padded_paths([f[0] for f in found], p.max_path_len)
    s = sched.score(p, paths)
    assert (np.asarray(s.reason) == R.OK).all()
    np.testing.assert_allclose(s.cost, [f[1] for f in found], rtol=COST_RTOL)


def test_random_sequences_are_valid_exactly_when_enumerated(thesis):
    p, found = thesis
    valid = {f[0] for f in found}
    rng = np.random.default_rng(0)
    base = sched.as_padded_paths([f[0] for f in found], p.max_path_len)
    perm = rng.random(base.shape).argsort(axis=1)
    shuffled = np.take_along_axis(base, perm, axis=1)
    shuffled[:, 0] = 0
    s = sched.score(p, shuffled)
    for row, reason, cost in zip(shuffled, np.asarray(s.reason), np.asarray(s.cost)):
        nodes = tuple(int(v) for v in row if v >= 0)
        is_valid = nodes in valid and list(row[: len(nodes)]) == list(nodes)
        assert (reason == R.OK) == is_valid
        assert np.isfinite(cost) == is_valid


@pytest.mark.parametrize(
    "path, reason",
    [
        ((0, 2, 5, 4, 8, 0, 1, 6, 3, 7, 9), R.OK),
        ((0, 2, 5, 4, 8, 0, 1, 6, 3, 7, 9, -1, -1), R.OK),
        ((0, 2, 5, 4, 8, 0, 1, 6, 3, 7, 10), R.UNKNOWN_NODE),
        ((0, 2, 5, 4, 8, 0, 1, 6, 3, 7, -2), R.UNKNOWN_NODE),
        ((1, 2, 5, 4, 8, 0, 0, 6, 3, 7, 9), R.NOT_FROM_START),
        ((0, 2, 5, 4, 8, 0, 1, 6, 3, 7), R.NO_GOAL),
        ((0, 2, 5, 4, 8, 9, 1, 6, 3, 7, 9), R.NO_GOAL),
        ((0, 2, 5, 4, 8, 0, 2, 6, 3, 7, 9), R.OBJECT_NOT_PLACED_ONCE),
        ((0, 2, 5, 4, 8, 3, 7, 9), R.OBJECT_NOT_PLACED_ONCE),
        ((0, 2, 5, 4, 8, 0, 1, 5, 3, 7, 9), R.BASE_REUSED),
        ((0, 2, 7, 4, 8, 0, 1, 6, 3, 5, 9), R.MOVE_RULE),  # cube on the cylinder's base
        ((0, 2, 4, 5, 8, 0, 1, 6, 3, 7, 9), R.MOVE_RULE),  # two objects in the gripper
        ((0, 2, 5, 4, 8, 0, 1, 6, 3, 7, 0, 9), R.MOVE_RULE),  # back to start when all placed
        ((0, 2, 5, -1, 4, 8, 1, 6, 3, 7, 9), R.MOVE_RULE),  # padding inside
    ],
)
def test_reason_codes(path, reason):
    p = sched.thesis_problem()
    s = sched.score(p, sched.as_padded_paths([path]))  # each path's own length: any L is scored
    assert int(np.asarray(s.reason)[0]) == reason
    assert np.isfinite(float(np.asarray(s.cost)[0])) == (reason == R.OK)


def test_nan_move_is_a_forbidden_edge():
    cost = np.array(sched.THESIS_EQ41)
    cost[8, 0] = np.nan
    p = sched.PickPlaceProblem.from_matrix(cost, sched.THESIS_COMPAT)
    s = sched.score(p, sched.as_padded_paths([sched.THESIS_EQ41_GREEDY_PATH]))
    assert int(np.asarray(s.reason)[0]) == R.FORBIDDEN_EDGE


@pytest.mark.parametrize("batch", [(), (7,), (3, 4)])
def test_batch_shapes(thesis, batch):
    p, found = thesis
    paths = sched.as_padded_paths([f[0] for f in found[: int(np.prod(batch, dtype=int))]], 13)
    paths = paths.reshape(*batch, 13)
    s = sched.score(p, paths)
    assert s.cost.shape == batch and s.reason.shape == batch
