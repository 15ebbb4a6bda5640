"""PickPlaceProblem: layout, validation errors, pytree behaviour."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import sched

NAN = np.nan


def _eq41():
    return np.array(sched.THESIS_EQ41)


def test_thesis_layout():
    p = sched.thesis_problem()
    assert p.n_nodes == 10 and p.n_objects == 4 and p.n_bases == 4
    assert p.objects == (1, 2, 3, 4) and p.bases == (5, 6, 7, 8)
    assert p.compat == {1: (5, 6), 2: (5, 6), 3: (7,), 4: (8,)}
    assert (p.start, p.goal) == (0, 9)
    assert p.max_path_len == 13
    assert len(sched.THESIS_NODE_NAMES) == p.n_nodes


def test_moves_outside_the_rules_are_ignored():
    cost = _eq41()
    cost[0, 5] = 0.01  # start → base is never a legal move
    p = sched.PickPlaceProblem.from_matrix(cost, sched.THESIS_COMPAT)
    assert np.isinf(p.move_cost[0, 5])
    assert sched.exact(p).cost == pytest.approx(sched.exact(sched.thesis_problem()).cost)


def test_general_layout_and_default_goal():
    p = sched.random_problem(jax.random.key(0), 3, 5)
    assert p.objects == (1, 2, 3) and p.bases == (4, 5, 6, 7, 8) and p.goal == 9
    assert all(set(bs) <= set(p.bases) for bs in p.compat.values())


@pytest.mark.parametrize(
    "cost, compat, kwargs, match",
    [
        (np.zeros((10, 9)), sched.THESIS_COMPAT, {}, "must be square"),
        (np.zeros(10), sched.THESIS_COMPAT, {}, "must be square"),
        (np.zeros((3, 3)), {1: (2,)}, {}, "at least 4 nodes"),
        ("inf", sched.THESIS_COMPAT, {}, "±inf"),
        ("negative", sched.THESIS_COMPAT, {}, "negative"),
        (None, sched.THESIS_COMPAT, {"start": 10}, "start node 10"),
        (None, sched.THESIS_COMPAT, {"goal": -1}, "goal node -1"),
        (None, sched.THESIS_COMPAT, {"start": 9, "goal": 9}, "must be different"),
        (None, {}, {}, "compat is empty"),
        (None, {1: (5, 6), 12: (7,)}, {}, "unknown object node 12"),
        (None, {1: (5, 6), 2: (5, 16)}, {}, r"unknown base \(of object 2\) node 16"),
        (None, {1: (5, 6), 2: ()}, {}, "object node 2 has no allowed base"),
        (None, {1: (5, 5)}, {}, "lists a base twice"),
        (None, {1: (2,), 2: (5,)}, {}, "lists node 2 as a base"),
        (None, {0: (5,)}, {}, "also the start or goal"),
        (None, {1.5: (5,)}, {}, "not an integer node index"),
    ],
)
def test_bad_input_raises(cost, compat, kwargs, match):
    if cost is None:
        cost = _eq41()
    elif isinstance(cost, str):
        bad = _eq41()
        bad[0, 1] = np.inf if cost == "inf" else -0.5
        cost = bad
    with pytest.raises(ValueError, match=match):
        sched.PickPlaceProblem.from_matrix(cost, compat, **kwargs)


def test_infeasible_cost_matrices_raise():
    c = _eq41()
    c[0, 1:5] = NAN
    with pytest.raises(ValueError, match="every move from the start node 0 is NaN"):
        sched.PickPlaceProblem.from_matrix(c, sched.THESIS_COMPAT)
    c = _eq41()
    c[3, 7] = NAN
    with pytest.raises(ValueError, match="object 3 has a NaN cost to every allowed base"):
        sched.PickPlaceProblem.from_matrix(c, sched.THESIS_COMPAT)
    c = _eq41()
    c[5:9, 9] = NAN
    with pytest.raises(ValueError, match="every move into the goal node 9 is NaN"):
        sched.PickPlaceProblem.from_matrix(c, sched.THESIS_COMPAT)
    # both cubes only fit base 5: no placement of every object exists
    with pytest.raises(ValueError, match="no feasible schedule: the NaN entries"):
        sched.PickPlaceProblem.from_matrix(_eq41(), {1: (5,), 2: (5,), 3: (7,), 4: (8,)})
    # only a cube's base leads to the goal, but the cubes must be placed first... reachable
    # order constraints: goal only from base 8 and base 8 cannot be left towards a cube
    c = _eq41()
    c[5:8, 9] = NAN
    c[8, [0, 1, 2, 3]] = NAN
    p = sched.PickPlaceProblem.from_matrix(c, sched.THESIS_COMPAT)  # hexagon last: feasible
    assert sched.exact(p).path[-3:] == (4, 8, 9)


def test_problem_is_an_immutable_pytree():
    p = sched.thesis_problem()
    leaves, treedef = jax.tree_util.tree_flatten(p)
    assert len(leaves) == 7
    q = jax.tree_util.tree_unflatten(treedef, leaves)
    assert q.objects == p.objects and q.start == p.start
    with pytest.raises(Exception):
        p.start = 3
    with pytest.raises(ValueError):
        p.cost[0, 1] = 1.0  # read-only array


def test_same_layout_shares_compiled_code():
    traces = []

    @jax.jit
    def total(problem):
        traces.append(1)
        return jnp.nansum(problem.cost)

    a = sched.random_problem(jax.random.key(1), 4, 4, bases_per_object=(1, 3))
    b = sched.random_problem(jax.random.key(2), 4, 4, bases_per_object=(1, 3))
    assert a.compat != b.compat
    total(a), total(b)
    assert len(traces) == 1


def test_padded_paths():
    out = sched.as_padded_paths([(0, 1, 2), (0,)], 4)
    np.testing.assert_array_equal(out, [[0, 1, 2, -1], [0, -1, -1, -1]])
    with pytest.raises(ValueError, match="more than the padded length"):
        sched.as_padded_paths([(0, 1, 2)], 2)


def test_random_problem_rejects_too_few_bases():
    with pytest.raises(ValueError, match="at least as many bases"):
        sched.random_problem(jax.random.key(0), 3, 2)
