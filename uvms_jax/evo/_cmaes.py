"""CMA-ES (evosax) as a second optimiser of the docking problem.

CMA-ES searches the unit cube; a sample ``u`` maps to ``low + clip(u, 0, 1)·(high − low)``
(so every candidate lies in the search box and its fitness is eq. 15 as for the GA).
evosax minimises, so it is told ``−fitness``. A whole run is one jitted ``lax.scan``;
several runs are one ``vmap`` over keys.
"""

from __future__ import annotations

from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from evosax.algorithms import CMA_ES
from jax import Array


class CMAESResult(NamedTuple):
    """Outcome of :func:`run_cmaes` (leading axis = run for a batch of keys).

    Attributes:
      best_x: ``(m,)`` best candidate seen.
      best_fitness: ``()`` its fitness (maximised).
      history: ``(generations,)`` best fitness after each generation.
    """

    best_x: Array
    best_fitness: Array
    history: Array


def _run(key: Array, problem: Any, low: Array, high: Array, std_init: Array, population_size: int, generations: int):
    m = low.shape[0]
    es = CMA_ES(population_size=population_size, solution=jnp.zeros(m, dtype=low.dtype))
    params = es.default_params.replace(std_init=std_init)
    k_mean, k_init, k_loop = jax.random.split(key, 3)
    to_x = lambda u: low + jnp.clip(u, 0.0, 1.0) * (high - low)
    state = es.init(k_init, jax.random.uniform(k_mean, (m,), dtype=low.dtype), params)

    def step(carry, k):
        state, best_u, best_f = carry
        k_ask, k_tell = jax.random.split(k)
        u, state = es.ask(k_ask, state, params)
        u = u.astype(low.dtype)  # evosax draws in JAX's default float (float64 under x64)
        f = problem.fitness(to_x(u))
        f = jnp.where(jnp.isnan(f), -jnp.inf, f)
        state, _ = es.tell(k_tell, u, -f, state, params)
        i = jnp.argmax(f)
        better = f[i] > best_f
        best_u, best_f = jnp.where(better, u[i], best_u), jnp.where(better, f[i], best_f)
        # Keep the carry in the problem's dtype whatever evosax computes in.
        new = (state, best_u, best_f)
        return jax.tree_util.tree_map(lambda x, ref: x.astype(ref.dtype), new, carry), best_f.astype(low.dtype)

    init = (state, jnp.full((m,), 0.5, dtype=low.dtype), jnp.asarray(-jnp.inf, dtype=low.dtype))
    (state, best_u, best_f), history = jax.lax.scan(step, init, jax.random.split(k_loop, generations))
    return CMAESResult(best_x=to_x(best_u), best_fitness=best_f, history=history)


@partial(jax.jit, static_argnames=("population_size", "generations"))
def _run_batch(keys, problem, low, high, std_init, population_size, generations):
    return jax.vmap(_run, in_axes=(0, None, None, None, None, None, None))(
        keys, problem, low, high, std_init, population_size, generations
    )


def run_cmaes(
    keys: Array,
    problem: Any,
    low,
    high,
    population_size: int = 16,
    generations: int = 200,
    std_init: float = 0.3,
) -> CMAESResult:
    """Independent CMA-ES runs (one per key in ``keys (R,)``) in one jitted call.

    Args:
      keys: ``(R,)`` PRNG keys; each run starts from a uniform random mean in the box.
      problem: pytree with ``fitness((n, m)) -> (n,)`` to maximise.
      low, high: ``(m,)`` search box.
      population_size: λ.
      generations: fixed number of generations (no early stop: static shapes).
      std_init: initial step size in units of the box size.

    Returns:
      :class:`CMAESResult` with a leading run axis.
    """
    low = jnp.asarray(low)
    high = jnp.asarray(high, dtype=low.dtype)
    if low.shape != high.shape or low.ndim != 1 or not bool(jnp.all(low < high)):
        raise ValueError(f"need low < high of equal shape (m,), got {low} and {high}")
    if population_size < 2 or generations < 1 or std_init <= 0:
        raise ValueError(
            f"need population_size >= 2, generations >= 1, std_init > 0; got "
            f"{population_size}, {generations}, {std_init}"
        )
    return _run_batch(keys, problem, low, high, jnp.asarray(std_init, dtype=low.dtype), population_size, generations)
