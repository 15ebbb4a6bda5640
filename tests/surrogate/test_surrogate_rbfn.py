"""Greedy RBF network design."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax.surrogate import RBFN, Scaler, fit_rbfn, fit_scaler

from _surrogate_helpers import synthetic_dataset

# Interpolation with all N training inputs as centres is exact up to the conditioning of the
# Gaussian matrix (well conditioned at a small spread) in float64.
INTERP_ATOL = 1e-8
# The output weights against NumPy's least squares on the same 40 × 11 design matrix (cond 11.7):
# two backward-stable solves agree to ~cond · eps ≈ 3e-15 (measured 2.5e-15 under XLA's default,
# AVX and SSE4.2 ISAs); the tolerances leave room for a worse-conditioned set of centres.
LSQ_RTOL, LSQ_ATOL = 1e-6, 1e-8


@pytest.fixture(scope="module")
def small():
    return synthetic_dataset(jax.random.key(3), 40)


def test_rbfn_reproduces_its_centres_exactly(small):
    n = len(small)
    net, history = fit_rbfn(small, spread=0.5, target_mse=0.0, max_centres=n)
    # Bias + N − 1 Gaussians already span R^N: the last input adds a dependent column, skipped.
    assert net.n_centres == n - 1
    x_n = np.asarray(net.x_norm(small.x))
    centre_rows = [int(np.argmin(np.linalg.norm(x_n - c, axis=1))) for c in np.asarray(net.centres)]
    assert len(set(centre_rows)) == n - 1
    np.testing.assert_allclose(np.asarray(net.centres), x_n[centre_rows], atol=1e-12)
    # The network reproduces the target at every centre (and, being an interpolant, everywhere in the set).
    centre_q = small.q[np.array(centre_rows)]
    np.testing.assert_allclose(np.asarray(net.index_fn(centre_q)), np.asarray(small.y[np.array(centre_rows)]),
                               atol=INTERP_ATOL)
    np.testing.assert_allclose(np.asarray(net.predict(small.x)), np.asarray(small.y), atol=INTERP_ATOL)
    assert history[-1] < 1e-16


def test_first_unit_sits_on_the_worst_fit_input(small):
    net, history = fit_rbfn(small, spread=1.0, target_mse=0.0, max_centres=1)
    worst = int(jnp.argmax(jnp.abs(small.y - jnp.mean(small.y))))
    x_n = net.x_norm(small.x)
    np.testing.assert_allclose(np.asarray(net.centres[0]), np.asarray(x_n[worst]), atol=1e-12)
    assert len(history) == 2 and history[1] < history[0]


def test_output_weights_are_the_least_squares_solution(small):
    net, _ = fit_rbfn(small, spread=1.0, target_mse=0.0, max_centres=10)
    x_n = net.x_norm(small.x)
    b = math.sqrt(math.log(2.0)) / float(net.spread)  # = 0.8326 / spread
    phi = np.exp(-(b * np.linalg.norm(np.asarray(x_n)[:, None] - np.asarray(net.centres)[None], axis=-1)) ** 2)
    A = np.concatenate([phi, np.ones((len(small), 1))], axis=1)
    sol = np.linalg.lstsq(A, np.asarray(fit_scaler(small.y, axis=None)(small.y)), rcond=None)[0]
    np.testing.assert_allclose(np.asarray(net.weights), sol[:-1], rtol=LSQ_RTOL, atol=LSQ_ATOL)
    np.testing.assert_allclose(float(net.bias), sol[-1], rtol=LSQ_RTOL, atol=LSQ_ATOL)


def test_training_mse_never_rises_and_stops_at_target(small):
    target = 1e-3
    net, history = fit_rbfn(small, spread=1.0, target_mse=target, max_centres=len(small))
    assert np.all(np.diff(history) <= 1e-15)
    assert history[-1] <= target and (len(history) < 3 or history[-2] > target)
    assert net.n_centres == len(history) - 1


def test_rbfn_index_fn_and_operation_count(small):
    net, _ = fit_rbfn(small, spread=1.0, max_centres=5)
    np.testing.assert_allclose(np.asarray(net.index_fn(small.q)), np.asarray(net.predict(small.x)), rtol=1e-12)
    assert net.index_fn(small.q.astype(jnp.float32)).dtype == jnp.float32
    assert net.operation_count == 5 * 28


def test_operation_count_follows_the_papers_convention():
    # Paper §4.3–4.4: RBFN-w, 149 units of 7 inputs: 1788 additions + 2384 multiplications.
    # RBFN-KCI: 1704 + 2272 = 3976, which is the same 12 + 16 per unit for 142 units of 11 inputs.
    assert rbfn_like(149, 7).operation_count == 1788 + 2384
    assert rbfn_like(142, 11).operation_count == 1704 + 2272


def rbfn_like(n_centres: int, d: int) -> RBFN:
    """An RBFN with ``n_centres`` units of ``d`` inputs (weights irrelevant to the count)."""
    unit = Scaler(jnp.zeros(()), jnp.ones(()))
    return RBFN(centres=jnp.zeros((n_centres, d)), weights=jnp.zeros(n_centres), bias=jnp.zeros(()),
                spread=jnp.ones(()), x_norm=Scaler(jnp.zeros(d), jnp.ones(d)), y_norm=unit, index="w",
                inputs=tuple(range(12 - d - 1, 11)))


def test_rbfn_rejects_bad_arguments(small):
    with pytest.raises(ValueError, match="spread"):
        fit_rbfn(small, spread=0.0)
    with pytest.raises(ValueError, match="max_centres"):
        fit_rbfn(small, spread=1.0, max_centres=0)
    net, _ = fit_rbfn(small, spread=1.0, max_centres=2)
    with pytest.raises(ValueError, match="shape"):
        net.index_fn(small.x)
