"""Chunked grid search against NumPy brute force; CMA-ES (evosax) determinism."""

import itertools

import jax
import numpy as np
import pytest

from uvms_jax import evo

LOW, HIGH = np.array([-1.0, -1.0, 0.0, -np.pi]), np.array([1.0, 1.0, 0.3, np.pi])
COUNTS = (7, 6, 3, 8)
PERIODIC = (False, False, False, True)


@pytest.mark.parametrize("chunk_size", [5, 1000])  # 5 does not divide 1008: a partial chunk
def test_grid_search_equals_brute_force(sphere, chunk_size):
    res = evo.grid_search(sphere, LOW, HIGH, COUNTS, PERIODIC, chunk_size=chunk_size)
    axes = evo.grid_axes(LOW, HIGH, COUNTS, PERIODIC)
    assert np.isclose(axes[3][-1], np.pi - 2 * np.pi / 8)  # ψ = π is ψ = −π: not sampled twice
    cands = np.array(list(itertools.product(*axes)))
    f = np.asarray(sphere.fitness(cands))
    assert res.n_candidates == len(cands) == np.prod(COUNTS)
    np.testing.assert_allclose(np.asarray(res.x), cands[np.argmax(f)], atol=1e-12)
    assert float(res.fitness) == pytest.approx(f.max())


def test_refinement_improves(sphere):
    res = evo.grid_search(sphere, LOW, HIGH, COUNTS, PERIODIC)
    stages = evo.refine_grid_search(sphere, res, counts=(5, 5, 5, 5), stages=3)
    f = [float(res.fitness)] + [float(s.fitness) for s in stages]
    assert all(b >= a for a, b in zip(f, f[1:]))
    assert f[-1] > -1e-3


def test_cmaes_same_seed_same_result(sphere):
    keys = jax.random.split(jax.random.key(0), 2)
    a = evo.run_cmaes(keys, sphere, LOW, HIGH, population_size=8, generations=60)
    b = evo.run_cmaes(keys, sphere, LOW, HIGH, population_size=8, generations=60)
    np.testing.assert_array_equal(np.asarray(a.best_x), np.asarray(b.best_x))
    assert np.all(np.diff(np.asarray(a.history), axis=-1) >= 0)
    assert np.all(np.asarray(a.best_fitness) > -1e-3)
    assert np.all((np.asarray(a.best_x) >= LOW) & (np.asarray(a.best_x) <= HIGH))
