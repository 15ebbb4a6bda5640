"""Levenberg–Marquardt least-squares training in JAX (dexterity paper eq. 20; Hagan & Menhaj 1994).

``W ← W − (JᵀJ + μ I)⁻¹ Jᵀ e`` with ``e = S − T`` the residuals of all training samples and
``J = ∂e/∂W`` their Jacobian (per-sample gradients, one ``vmap``). After a step that lowers the
mean squared error μ shrinks (``μ·mu_dec``, towards Gauss–Newton); after a step that does not,
the step is discarded and μ grows (``μ·mu_inc``, towards short gradient steps) — Matlab's
``trainlm`` rule. Training stops at ``max_epochs``, at ``mse ≤ target_mse`` or when μ exceeds
``mu_max``.

The model is any ``apply_fn(params, x) → scalar`` for one sample ``x: (d,)``; params is any
pytree (flattened internally with ``ravel_pytree``).
"""

from __future__ import annotations

from functools import partial
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
from jax import Array
from jax.flatten_util import ravel_pytree

Params = Any
ApplyFn = Callable[[Params, Array], Array]


class LMHyperParams(NamedTuple):
    """Damping schedule (Matlab ``trainlm`` defaults)."""

    mu_init: float = 1e-3
    mu_dec: float = 0.1
    mu_inc: float = 10.0
    mu_max: float = 1e10


class LMState(NamedTuple):
    """Optimiser state between epochs.

    Attributes:
      mu: ``()`` current damping μ.
      mse: ``()`` mean squared residual at the current parameters.
      epoch: ``()`` int, accepted + attempted epochs so far.
    """

    mu: Array
    mse: Array
    epoch: Array


class LevenbergMarquardt(NamedTuple):
    """Pure ``init(params, x, y) → state`` and ``update(params, state, x, y) → (params, state)``."""

    init: Callable[[Params, Array, Array], LMState]
    update: Callable[[Params, LMState, Array, Array], tuple[Params, LMState]]


def _residuals(apply_fn: ApplyFn, unravel, flat: Array, x: Array, y: Array) -> Array:
    return jax.vmap(lambda xi: apply_fn(unravel(flat), xi))(x) - y


def _mse(e: Array) -> Array:
    return jnp.mean(e * e)


def _lm_epoch(apply_fn: ApplyFn, hp: LMHyperParams, params: Params, state: LMState, x: Array, y: Array):
    flat, unravel = ravel_pytree(params)
    e = _residuals(apply_fn, unravel, flat, x, y)
    J = jax.vmap(jax.grad(lambda p, xi: apply_fn(unravel(p), xi)), in_axes=(None, 0))(flat, x)  # (N, P)
    JtJ, g = J.T @ J, J.T @ e
    mse = _mse(e)
    eye = jnp.eye(flat.shape[0], dtype=flat.dtype)

    def try_step(carry):
        mu, _, best, best_mse = carry
        delta = jnp.linalg.solve(JtJ + mu * eye, g)
        cand = flat - delta
        cand_mse = _mse(_residuals(apply_fn, unravel, cand, x, y))
        ok = cand_mse < mse  # False for NaN (a failed solve counts as a rejected step)
        return (
            jnp.where(ok, mu * hp.mu_dec, mu * hp.mu_inc),
            ok,
            jnp.where(ok, cand, best),
            jnp.where(ok, cand_mse, best_mse),
        )

    def keep_trying(carry):
        mu, accepted, _, _ = carry
        return (~accepted) & (mu <= hp.mu_max)

    mu, _, new, new_mse = jax.lax.while_loop(keep_trying, try_step, (state.mu, jnp.array(False), flat, mse))
    return unravel(new), LMState(mu=mu, mse=new_mse, epoch=state.epoch + 1)


def levenberg_marquardt(apply_fn: ApplyFn, hyper: LMHyperParams = LMHyperParams()) -> LevenbergMarquardt:
    """Levenberg–Marquardt as an ``init``/``update`` pair (both jitted).

    Args:
      apply_fn: ``apply_fn(params, x) → ()`` model output for one sample ``x: (d,)``.
      hyper: damping schedule.

    Returns:
      ``init(params, x, y)`` → :class:`LMState`; ``update(params, state, x, y)`` → one epoch:
      (new params, new state). ``x: (N, d)``, ``y: (N,)``; μ is adapted inside one update
      (rejected steps are retried with a larger μ until one lowers the mse or μ > mu_max).

    Example:
      >>> lm = levenberg_marquardt(apply_fn)
      >>> state = lm.init(params, x, y)
      >>> params, state = lm.update(params, state, x, y)
    """

    @jax.jit
    def init(params, x, y):
        flat, unravel = ravel_pytree(params)
        mse = _mse(_residuals(apply_fn, unravel, flat, x, y))
        return LMState(mu=jnp.asarray(hyper.mu_init, flat.dtype), mse=mse, epoch=jnp.array(0, jnp.int32))

    update = jax.jit(partial(_lm_epoch, apply_fn, hyper))
    return LevenbergMarquardt(init=init, update=update)


@partial(jax.jit, static_argnames=("apply_fn", "max_epochs", "hyper"))
def _fit(apply_fn, hyper, params, x, y, target_mse, max_epochs):
    flat, unravel = ravel_pytree(params)
    state = LMState(
        mu=jnp.asarray(hyper.mu_init, flat.dtype),
        mse=_mse(_residuals(apply_fn, unravel, flat, x, y)),
        epoch=jnp.array(0, jnp.int32),
    )
    history = jnp.full((max_epochs + 1,), jnp.nan, flat.dtype).at[0].set(state.mse)

    def cond(carry):
        _, s, _ = carry
        return (s.epoch < max_epochs) & (s.mse > target_mse) & (s.mu <= hyper.mu_max)

    def body(carry):
        p, s, h = carry
        p, s = _lm_epoch(apply_fn, hyper, p, s, x, y)
        return p, s, h.at[s.epoch].set(s.mse)

    return jax.lax.while_loop(cond, body, (params, state, history))


def fit_lm(
    apply_fn: ApplyFn,
    params: Params,
    x: Array,
    y: Array,
    *,
    max_epochs: int = 100,
    target_mse: float = 0.0,
    hyper: LMHyperParams = LMHyperParams(),
) -> tuple[Params, LMState, Array]:
    """Train with Levenberg–Marquardt until ``mse ≤ target_mse``, ``max_epochs`` or μ > mu_max.

    The whole run is one jitted ``lax.while_loop`` (compiled once per model shape).

    Args:
      apply_fn: one-sample model ``apply_fn(params, x: (d,)) → ()``; must be hashable and
        stable (a module-level function), it is a static argument.
      params: initial parameters (pytree).
      x: ``(N, d)`` inputs; y: ``(N,)`` targets (same units as the model output).
      max_epochs: epoch limit (paper: L_epochs = 100).
      target_mse: training goal E_mse, in squared output units.
      hyper: damping schedule.

    Returns:
      (params, final state, history ``(max_epochs + 1,)`` of the mse after each epoch; entry 0
      is the initial mse, entries after the last epoch are NaN).
    """
    x, y = jnp.asarray(x), jnp.asarray(y)
    if x.ndim != 2 or y.shape != x.shape[:1]:
        raise ValueError(f"expected x: (N, d) and y: (N,), got {x.shape} and {y.shape}")
    if max_epochs < 1:
        raise ValueError(f"max_epochs must be >= 1, got {max_epochs}")
    return _fit(apply_fn, hyper, params, x, y, jnp.asarray(target_mse, y.dtype), int(max_epochs))
