"""SE(3) helpers: the rotation log and its gradient at and near the identity and near π."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax.kin._lie import exp_twist, rotation_log

LOG_ATOL = 1e-12  # float64 round trip log(exp(w)) = w
FD_STEP = 1e-6
FD_ATOL = 1e-8  # central differences in float64: O(h²) truncation + round-off
AXIS = np.array([0.48, -0.6, 0.64])  # unit vector


def rotation(w):
    """``exp(ŵ)`` of an axis-angle vector ``w (3,)``, as ``(3, 3)``, differentiable at 0."""
    x, y, z = w
    W = jnp.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    # Series of the exponential: exact to round-off for |w| ≤ 1e-3 with 12 terms.
    R, term = jnp.eye(3), jnp.eye(3)
    for k in range(1, 12):
        term = term @ W / k
        R = R + term
    return R


def _log_of_series(w):
    return rotation_log(rotation(w))


def _log_of_exp_twist(w):
    return rotation_log(exp_twist(jnp.concatenate([jnp.zeros(3), w / jnp.linalg.norm(w)]), jnp.linalg.norm(w))[0])


# Compiled once at module scope and shared by the tests (a fresh lambda per test would
# compile again).
_log = jax.jit(rotation_log)
_jacrev_log = jax.jit(jax.jacrev(rotation_log))
_log_series, _log_exp_twist = jax.jit(_log_of_series), jax.jit(_log_of_exp_twist)
_jacfwd_series, _jacrev_series = jax.jit(jax.jacfwd(_log_of_series)), jax.jit(jax.jacrev(_log_of_series))
_jacfwd_exp_twist = jax.jit(jax.jacfwd(_log_of_exp_twist))


@pytest.mark.parametrize("theta", [0.0, 1e-9, 1e-6, 1e-3, 0.5, 2.0, 3.0, np.pi - 1e-4])
def test_log_inverts_exp(theta):
    R, _ = exp_twist(jnp.concatenate([jnp.zeros(3), AXIS]), jnp.float64(theta))
    np.testing.assert_allclose(_log(R), theta * AXIS, atol=LOG_ATOL)


@pytest.mark.parametrize("theta", [0.0, 1e-9, 1e-7, 1e-4])
def test_gradient_of_log_is_finite_and_exact_at_and_near_identity(theta):
    """Regression: grad through the rotation log was NaN at θ = 0 (the norm of a zero vee).

    ``d log(exp(ŵ)) / dw`` is the inverse left Jacobian of SO(3), ``I + O(θ)``; at θ = 0 exactly I.
    """
    w0 = jnp.asarray(theta * AXIS)
    J = np.asarray(_jacfwd_series(w0))
    assert np.isfinite(J).all()
    Jr = np.asarray(_jacrev_series(w0))
    np.testing.assert_allclose(J, Jr, atol=1e-12)
    np.testing.assert_allclose(J, np.eye(3), atol=2 * theta + 1e-12)


def test_gradient_of_log_at_identity_is_half_the_vee():
    """At R = I, log(R) ≈ vee(R − Rᵀ)/2, so ∂log_x/∂R₂₁ = ½ and ∂log_x/∂R₁₂ = −½."""
    G = np.asarray(_jacrev_log(jnp.eye(3)))  # (3, 3, 3)
    assert np.isfinite(G).all()
    expected = np.zeros((3, 3, 3))
    for k, (i, j) in enumerate(((2, 1), (0, 2), (1, 0))):
        expected[k, i, j], expected[k, j, i] = 0.5, -0.5
    np.testing.assert_allclose(G, expected, atol=1e-12)


@pytest.mark.parametrize("theta", [1e-3, 0.7, 3.0])
def test_gradient_of_log_matches_finite_differences(theta):
    f, jac = (_log_series, _jacfwd_series) if theta < 0.1 else (_log_exp_twist, _jacfwd_exp_twist)
    w0 = jnp.asarray(theta * AXIS)
    J = np.asarray(jac(w0))
    fd = np.stack([(f(w0 + FD_STEP * e) - f(w0 - FD_STEP * e)) / (2 * FD_STEP) for e in np.eye(3)], axis=-1)
    np.testing.assert_allclose(J, fd, atol=FD_ATOL * max(1.0, 1.0 / (np.pi - theta)))


def test_gradient_of_log_is_finite_at_pi():
    R = jnp.diag(jnp.array([1.0, -1.0, -1.0]))
    np.testing.assert_allclose(_log(R), [np.pi, 0.0, 0.0], atol=LOG_ATOL)
    assert np.isfinite(np.asarray(_jacrev_log(R))).all()
