"""Levenberg–Marquardt and Adam trainers on small regressions."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax.surrogate import MLP, fit_adam, fit_lm, levenberg_marquardt, mlp_apply

from _surrogate_helpers import synthetic_dataset

# The loss of the same parameters summed twice (the trainer's and a mean here) over 200 samples:
# in float32 they differ by at most n·eps ≈ 2.4e-5 of the loss (a worst case; pairwise sums much
# less), in float64 by ~4e-14.
MSE_RTOL = 1e-4
# One Gauss–Newton step on a linear least-squares problem (50 points on [-1, 1], float64) is its
# exact solution up to the normal equations' rounding (cond ≈ 3 · eps) and μ = 1e-12.
LINEAR_ATOL = 1e-8


def _mse(params, x, y):
    return float(jnp.mean((jax.vmap(lambda xi: mlp_apply(params, xi))(x) - y) ** 2))


@pytest.fixture(scope="module")
def problem():
    ds = synthetic_dataset(jax.random.key(0), 200)
    params = MLP(4).init(jax.random.key(1), ds.x[:1])["params"]
    return params, ds.x, ds.y


@pytest.mark.parametrize("dtype", [jnp.float32, jnp.float64])
def test_one_lm_step_lowers_the_loss(problem, dtype):
    params, x, y = jax.tree_util.tree_map(lambda a: a.astype(dtype), problem)
    lm = levenberg_marquardt(mlp_apply)
    state = lm.init(params, x, y)
    new_params, new_state = lm.update(params, state, x, y)
    before, after = _mse(params, x, y), _mse(new_params, x, y)
    assert after < before
    np.testing.assert_allclose(float(new_state.mse), after, rtol=MSE_RTOL)
    np.testing.assert_allclose(float(state.mse), before, rtol=MSE_RTOL)
    assert int(new_state.epoch) == 1
    # μ was adapted: rejected tries multiply it by 10, the accepted one divides by 10.
    ratio = float(new_state.mu) / float(state.mu)
    assert np.isclose(np.log10(ratio), np.round(np.log10(ratio)), atol=1e-3) and ratio <= 1e9


def test_lm_solves_a_linear_least_squares_problem_in_one_epoch():
    # For a model linear in its parameters, one Gauss–Newton step (μ → 0) is the exact solution.
    x = jnp.linspace(-1.0, 1.0, 50)[:, None]
    y = 3.0 * x[:, 0] - 2.0

    def line(p, xi):
        return p["a"] * xi[0] + p["b"]

    params = {"a": jnp.array(0.0), "b": jnp.array(0.0)}
    fitted, state, history = fit_lm(line, params, x, y, max_epochs=5, target_mse=1e-12,
                                    hyper=fit_lm.__kwdefaults__["hyper"]._replace(mu_init=1e-12))
    np.testing.assert_allclose([float(fitted["a"]), float(fitted["b"])], [3.0, -2.0], atol=LINEAR_ATOL)
    assert int(state.epoch) == 1


def test_fit_lm_history_is_monotone_and_stops_at_max_epochs(problem):
    params, x, y = problem
    _, state, history = fit_lm(mlp_apply, params, x, y, max_epochs=20)
    h = np.asarray(history)
    done = h[np.isfinite(h)]
    assert int(state.epoch) == 20 and len(done) == 21
    assert np.all(np.diff(done) <= 0)
    assert done[-1] < 0.1 * done[0]


def test_fit_adam_lowers_the_loss(problem):
    params, x, y = problem
    fitted, history = fit_adam(mlp_apply, params, x, y, steps=200, learning_rate=1e-2)
    assert history.shape == (201,)
    assert _mse(fitted, x, y) < 0.5 * _mse(params, x, y)


def test_trainers_reject_bad_shapes(problem):
    params, x, y = problem
    with pytest.raises(ValueError, match="expected x"):
        fit_lm(mlp_apply, params, x, y[:-1])
    with pytest.raises(ValueError, match="expected x"):
        fit_adam(mlp_apply, params, x[:, 0], y)
    with pytest.raises(ValueError, match="max_epochs"):
        fit_lm(mlp_apply, params, x, y, max_epochs=0)
