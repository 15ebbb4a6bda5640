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


@pytest.mark.parametrize("chunk_size", [7, 1000])
def test_grid_keeps_the_best_points_of_a_shifted_lattice(sphere, chunk_size):
    """``keep`` best points of a lattice moved by ``shift`` cells, against NumPy brute force."""
    shift = np.array([0.25, 0.5, 0.0, 0.9])
    res = evo.grid_search(sphere, LOW, HIGH, COUNTS, PERIODIC, chunk_size=chunk_size, keep=5, shift=shift)
    axes = [lo + (np.arange(n) + s) * (hi - lo) / n for lo, hi, n, s in zip(LOW, HIGH, COUNTS, shift)]
    cands = np.array(list(itertools.product(*axes)))
    f = np.asarray(sphere.fitness(cands))
    order = np.argsort(-f, kind="stable")[:5]
    np.testing.assert_allclose(np.asarray(res.top_x), cands[order], atol=1e-12)
    np.testing.assert_allclose(np.asarray(res.top_fitness), f[order], rtol=1e-12)
    assert np.all((cands >= LOW) & (cands < HIGH))


def test_grid_rejects_a_shift_outside_one_cell(sphere):
    with pytest.raises(ValueError, match="shift"):
        evo.grid_search(sphere, LOW, HIGH, COUNTS, PERIODIC, shift=[0.0, 0.0, 1.0, 0.0])


def _brute_zoom(fitness, start, f0, counts, stages, shrink, periodic):
    """One start's zoom stages, written out: every box's points, best kept when it improves."""
    x, f = np.array(start, float), f0
    for s in range(stages):
        half = (HIGH - LOW) * shrink ** (s + 1) / 2
        lo = np.where(periodic, x - half, np.maximum(LOW, x - half))
        hi = np.where(periodic, x + half, np.minimum(HIGH, x + half))
        pts = np.array(list(itertools.product(*[np.linspace(a, b, c) for a, b, c in zip(lo, hi, counts)])))
        pts = np.where(periodic, LOW + np.mod(pts - LOW, HIGH - LOW), pts)
        fp = fitness(pts)
        if fp.max() > f:
            x, f = pts[np.argmax(fp)], fp.max()
    return x, f


def test_zoom_from_several_starts_equals_each_start_alone(sphere):
    """K starts at once (chunked) give what each start's zoom gives alone; ψ wraps across ±π."""
    starts = np.array([[0.9, 0.9, 0.25, 3.0], [-0.8, 0.2, 0.05, -3.0], [0.3, -0.4, 0.1, 0.7]])
    f0 = np.asarray(sphere.fitness(starts))
    periodic = np.array(PERIODIC)
    zoom = evo.zoom_from(sphere, starts, f0, LOW, HIGH, (3, 3, 3, 3), stages=6, shrink=0.5, periodic=periodic,
                         chunk_size=50)
    fitness = lambda p: np.asarray(sphere.fitness(p))
    for k in range(len(starts)):
        x, f = _brute_zoom(fitness, starts[k], f0[k], (3, 3, 3, 3), 6, 0.5, periodic)
        np.testing.assert_allclose(zoom.x[k], x, atol=1e-12)
        assert zoom.fitness[k] == pytest.approx(f)
    assert zoom.fitness_history.shape == (6, 3) and np.all(np.diff(zoom.fitness_history, axis=0) >= 0)
    assert np.all(zoom.fitness >= f0)


def test_distinct_best_keeps_one_point_per_basin():
    x = np.array([[0.0, 0.0], [0.05, 0.0], [1.0, 1.0], [0.0, 0.5], [1.02, 1.0]])
    f = np.array([5.0, 4.9, 4.0, 3.0, np.nan])
    assert evo.distinct_best(x, f, 3, np.array([0.1, 0.1])).tolist() == [0, 2, 3]
    assert evo.distinct_best(x, f, 1, np.array([0.1, 0.1])).tolist() == [0]
