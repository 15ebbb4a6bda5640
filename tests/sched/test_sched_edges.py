"""Schedules as lists of moves."""

import pytest

from uvms_jax import sched


def test_edges_of_the_thesis_greedy_schedule():
    p = sched.thesis_problem()
    edges = sched.schedule_edges(p, sched.THESIS_EQ41_GREEDY_PATH)
    assert [(e.src, e.dst) for e in edges] == list(
        zip(sched.THESIS_EQ41_GREEDY_PATH[:-1], sched.THESIS_EQ41_GREEDY_PATH[1:])
    )
    assert [e.action for e in edges[:5]] == ["pick", "place", "pick", "place", "return"]
    assert edges[-1].action == "finish"
    assert edges[1].obj == 2 and edges[0].obj is None


def test_invalid_schedule_raises():
    p = sched.thesis_problem()
    with pytest.raises(ValueError, match="BASE_REUSED"):
        sched.schedule_edges(p, (0, 2, 5, 4, 8, 0, 1, 5, 3, 7, 9))
    with pytest.raises(ValueError, match="at least two nodes"):
        sched.schedule_edges(p, (0,))
