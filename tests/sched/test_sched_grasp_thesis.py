"""The thesis's GRASP local search (Algorithm 4) against a plain-Python reading of it."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import sched

from _sched_bruteforce import all_schedules

COST_RTOL = 1e-5  # float32 sums in the kernel, float64 here

# The local search over a batch of schedules, built once: a jit made per test would be a new
# function to JAX, compiled again for every instance of the same sizes.
LOCAL_SEARCH_BATCH = jax.jit(jax.vmap(sched.thesis_local_search, in_axes=(None, 0, 0)))


def _algorithm_4(path, cost_of, neighbourhood=3):
    """Thesis Algorithm 4 on a node list: each position after the start swapped with each of
    the next ``neighbourhood``; a swap is kept if the result is feasible and cheaper."""
    path, best = list(path), cost_of(path)
    for i in range(1, len(path)):
        for j in range(i + 1, min(i + neighbourhood, len(path) - 1) + 1):
            cand = list(path)
            cand[i], cand[j] = cand[j], cand[i]
            c = cost_of(cand)
            if c < best:
                path, best = cand, c
    return path, best


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_thesis_local_search_matches_algorithm_4(seed):
    p = sched.random_problem(jax.random.key(seed), 4, 4, compat=sched.THESIS_COMPAT) if seed else sched.thesis_problem()
    feasible = dict(all_schedules(p.cost.tolist(), p.compat, p.start, p.goal))
    n, L = p.n_nodes, p.max_path_len

    def cost_of(padded):  # a padded node list → its cost, inf if not a feasible schedule
        nodes = tuple(padded)
        while nodes and nodes[-1] == n:
            nodes = nodes[:-1]
        return feasible.get(nodes, math.inf)

    rng = np.random.default_rng(seed)
    every = list(feasible)
    starts = [list(every[i]) + [n] * (L - len(every[i])) for i in rng.permutation(len(every))[:40]]
    got_paths, got_costs = LOCAL_SEARCH_BATCH(p, jnp.asarray(starts, jnp.int32),
                                              jnp.asarray([cost_of(s) for s in starts], jnp.float32))
    improved = 0
    for s, gp, gc in zip(starts, np.asarray(got_paths), np.asarray(got_costs)):
        want_path, want_cost = _algorithm_4(s, cost_of)
        assert list(gp) == want_path
        np.testing.assert_allclose(gc, want_cost, rtol=COST_RTOL)
        improved += want_cost < cost_of(s)
    assert improved > 0  # the test exercises accepted swaps, not only rejected ones


def test_grasp_with_the_thesis_local_search_returns_valid_schedules():
    p = sched.thesis_problem()
    batch = sched.grasp_batch(jax.random.key(0), p, 64, local_search="thesis")
    paths = np.where(np.asarray(batch.paths) >= p.n_nodes, sched.PAD_NODE, np.asarray(batch.paths))
    scores = sched.score(p, paths)
    assert bool(jnp.all(scores.reason == sched.Reason.OK))
    np.testing.assert_allclose(np.asarray(scores.cost), np.asarray(batch.costs), rtol=COST_RTOL)
    assert bool(jnp.all(batch.costs <= batch.construction_costs))
    best = sched.grasp(jax.random.key(0), p, 64, local_search="thesis")
    assert best.info["local_search"] == "thesis" and best.cost == pytest.approx(float(batch.costs.min()), rel=COST_RTOL)


def test_unknown_local_search_is_named():
    with pytest.raises(ValueError, match="local search"):
        sched.grasp(jax.random.key(0), sched.thesis_problem(), 10, local_search="2-opt")
