"""First-order alternative to Levenberg–Marquardt: full-batch optax Adam on the mean squared error."""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import optax
from jax import Array

from uvms_jax.surrogate._lm import ApplyFn, Params


@partial(jax.jit, static_argnames=("apply_fn", "steps"))
def _fit(apply_fn, params, x, y, learning_rate, steps):
    opt = optax.adam(learning_rate)

    def loss(p):
        e = jax.vmap(lambda xi: apply_fn(p, xi))(x) - y
        return jnp.mean(e * e)

    def step(carry, _):
        p, s = carry
        value, grads = jax.value_and_grad(loss)(p)
        updates, s = opt.update(grads, s, p)
        return (optax.apply_updates(p, updates), s), value

    (params, _), history = jax.lax.scan(step, (params, opt.init(params)), None, length=steps)
    return params, jnp.append(history, loss(params))


def fit_adam(
    apply_fn: ApplyFn,
    params: Params,
    x: Array,
    y: Array,
    *,
    steps: int = 2000,
    learning_rate: float = 1e-2,
) -> tuple[Params, Array]:
    """Full-batch Adam on ``mean((apply_fn(params, x_i) − y_i)²)``; one jitted ``lax.scan``.

    Args:
      apply_fn: one-sample model ``(params, x: (d,)) → ()`` (static, hashable).
      params: initial parameters (pytree).
      x: ``(N, d)`` inputs; y: ``(N,)`` targets.
      steps: number of Adam steps.
      learning_rate: Adam step size.

    Returns:
      (params, history ``(steps + 1,)`` of the mse before each step and after the last).
    """
    x, y = jnp.asarray(x), jnp.asarray(y)
    if x.ndim != 2 or y.shape != x.shape[:1]:
        raise ValueError(f"expected x: (N, d) and y: (N,), got {x.shape} and {y.shape}")
    if steps < 1 or not learning_rate > 0:
        raise ValueError(f"need steps >= 1 and learning_rate > 0, got {steps}, {learning_rate}")
    return _fit(apply_fn, params, x, y, jnp.asarray(learning_rate, y.dtype), int(steps))
