"""The GA's generations driven from Python (``BinaryGA.host_loop``): the operators of all runs
are two compiled steps (ask, tell) that do not hold the fitness, and the new individuals are
evaluated ``eval_chunk`` at a time by the one compiled evaluation of a problem that the grid
search and the zoom stages call too (:func:`uvms_jax.evo._grid._fitness_of`). A costly fitness
(numerical IK of every demanded tool pose) is then compiled once for a docking run, not once
inside the GA's loop and again for each search; the steps compile in a fraction of that and
serve every problem of the same GA sizes.

Same operators, same random draws, same fitness cache as the jitted loop
(:func:`uvms_jax.evo._ga._run_pooled`): the result is the same up to the fitness's round-off
in the two compiled programs; the cost is a few host round trips per generation.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from uvms_jax.evo._binary import BinaryCodec
from uvms_jax.evo._ga import _pool, _result_jit
from uvms_jax.evo._grid import _fitness_of

_split = jax.vmap(jax.random.split)


@partial(jax.jit, static_argnames=("ga",))
def _start(keys: Array, ga, params):
    """Initial states of the runs ``keys (R,)`` and the keys their loop draws from."""
    k_init, k_loop = jnp.moveaxis(_split(keys), 1, 0)
    return k_loop, jax.vmap(ga.init, in_axes=(0, None))(k_init, params)


@partial(jax.jit, static_argnames=("ga",))
def _ask(keys: Array, state, codec: BinaryCodec, ga, params):
    """One generation's populations ``(R, P, n_bits)`` and the values of its new individuals,
    new ones first, ``(n_slots, m)``, with the fitness cache (:func:`uvms_jax.evo._ga._pool`)."""
    keys, k_ask = jnp.moveaxis(_split(keys), 1, 0)
    population, asked = jax.vmap(ga.ask, in_axes=(0, 0, None))(k_ask, state, params)
    fitness, order, n_new, evaluated = _pool(population, state, state.done, ga.eval_chunk)
    R, P, L = population.shape
    values = codec.decode(population.reshape(R * P, L)[jnp.minimum(order, R * P - 1)])
    return keys, population, asked, fitness, order, n_new, evaluated, values


@partial(jax.jit, static_argnames=("ga",))
def _tell(population, fitness: Array, asked, state, n_evals: Array, evaluated: Array, ga, params):
    """Record the generation's fitness ``(R, P)``; a stopped run keeps its final state."""
    told = jax.vmap(ga.tell, in_axes=(0, 0, 0, None))(population, fitness, asked, params)
    keep = lambda new, old: jnp.where(state.done.reshape(state.done.shape + (1,) * (new.ndim - 1)), old, new)
    return jax.tree_util.tree_map(keep, told, state), n_evals + evaluated


def run_host_loop(keys: Array, problem: Any, codec: BinaryCodec, ga, params):
    """R independent runs (``keys (R,)``), one generation per Python iteration (module
    docstring). Returns ``(final states, evaluations (R,))``."""
    keys, state = _start(keys, ga, params)
    n_evals = np.zeros(keys.shape[:1], dtype=np.int32)
    chunk = ga.eval_chunk
    while not np.all(np.asarray(state.done)):
        keys, population, asked, fitness, order, n_new, evaluated, values = _ask(keys, state, codec, ga, params)
        fitness, order, values, n_new = np.array(fitness), np.asarray(order), np.asarray(values), int(n_new)
        for i in range(0, n_new, chunk):
            f = np.asarray(_fitness_of(problem, jnp.asarray(values[i:i + chunk])))
            idx = order[i:i + chunk]
            inside = idx < fitness.shape[0]  # padding slots point past the end
            fitness[idx[inside]] = f[inside]
        fitness = fitness.reshape(population.shape[:2])
        state, n_evals = _tell(population, fitness, asked, state, n_evals, evaluated, ga, params)
    return state, n_evals


def compile_steps(keys: Array, codec: BinaryCodec, ga, params) -> None:
    """Compile the steps (not the fitness) for these runs' shapes: one generation on a zero fitness."""
    k, state = _start(keys, ga, params)
    k, population, asked, fitness, order, n_new, evaluated, values = _ask(k, state, codec, ga, params)
    fitness = np.zeros(population.shape[:2], np.dtype(fitness.dtype))
    state, n_evals = _tell(population, fitness, asked, state, np.zeros(keys.shape[:1], np.int32), evaluated, ga, params)
    jax.block_until_ready(_result_jit(codec, state, n_evals))
