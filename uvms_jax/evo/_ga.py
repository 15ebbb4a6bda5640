"""Binary genetic algorithm of the docking paper (§III.B, Table 2), evosax-style.

``ga = BinaryGA(population_size=60, n_bits=…)`` holds the static sizes; :class:`GAParams`
the hyperparameters (Table 2 defaults); :class:`GAState` everything that evolves. The pure
functions ``ga.init(key, params)``, ``ga.ask(key, state, params)`` and
``ga.tell(population, fitness, state, params)`` make one generation; :func:`run_ga` runs a
whole optimisation as one jitted ``lax.while_loop`` and :func:`run_ga_batch` runs several
independent ones in one call (operators ``vmap``-ed over keys, fitness of all runs pooled).

Operators (each written per individual and batched with ``vmap``):

- selection: tournaments (fitness of eq. 15 may be negative, so no roulette);
- crossover: one-point, applied to a parent pair with probability
  ``p_c,i = p_c · (1 − β + 2β r_i)`` averaged over both parents, where ``r_i ∈ [0, 1]`` is the
  parent's fitness rank (1 = fittest) — the paper's "modified crossover probability …
  assigned in each individual in order to favour the fittest ones";
- mutation: independent bit flips with probability ``p_m``;
- elitism: the ``n_elites`` best individuals are copied unchanged;
- decaying rates: every generation ``p ← p · rate_decay``, and additionally
  ``p ← p · improvement_decay`` when the best fitness improves ("the mutation and the
  crossover probability are being reduced as better solutions are achieved and the number
  of generations grows"), floored at ``*_min``;
- stop: ``max_generations`` evaluated generations or ``stall_generations`` generations
  without an improvement of the best fitness larger than ``improvement_tol``.
"""

from __future__ import annotations

from collections.abc import Callable

import dataclasses
from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from flax import struct
from jax import Array

from uvms_jax.evo._binary import BinaryCodec, Bits


@struct.dataclass
class GAParams:
    """Hyperparameters (traced, so they can be swept with ``vmap``). Defaults: paper Table 2."""

    crossover_rate: float = 0.20
    mutation_rate: float = 0.08  # per bit
    crossover_bias: float = 1.0  # β ∈ [0, 1]: 0 = same p_c for all, 1 = p_c ∈ [0, 2 p_c] by rank
    rate_decay: float = 0.99  # per generation
    improvement_decay: float = 0.95  # per improvement of the best fitness
    crossover_rate_min: float = 0.05
    mutation_rate_min: float = 0.005
    stall_generations: int = 50
    improvement_tol: float = 0.0  # relative to max(1, |best fitness|)


@struct.dataclass
class GAState:
    """Evolving state of one run.

    Attributes:
      population: ``(P, n_bits)`` chromosomes of the current generation.
      fitness: ``(P,)`` their fitness (−inf before the first evaluation).
      best_bits, best_fitness: best individual seen so far.
      crossover_rate, mutation_rate: current (decayed) rates.
      generation: generations evaluated so far.
      stall: generations since the last improvement.
      history: ``(max_generations,)`` best fitness after each generation (NaN after the stop).
      done: stop criterion met.
    """

    population: Bits
    fitness: Array
    best_bits: Bits
    best_fitness: Array
    crossover_rate: Array
    mutation_rate: Array
    generation: Array
    stall: Array
    history: Array
    done: Array


# Random draws in fixed dtypes: a run draws the same numbers whether or not the process has
# enabled jax_enable_x64 (the pipeline does, for IK and training), so its results do not depend on it.
_DRAW = jnp.float32

def _tournament(key: Array, fitness: Array, size: int) -> Array:
    """Index of the fittest of ``size`` individuals drawn with replacement."""
    idx = jax.random.randint(key, (size,), 0, fitness.shape[0], dtype=jnp.int32)
    return idx[jnp.argmax(fitness[idx])]


def _one_point_crossover(key: Array, a: Bits, b: Bits, p: Array) -> tuple[Bits, Bits]:
    """With probability ``p`` swap the tails of ``a`` and ``b`` after a random cut."""
    k_do, k_cut = jax.random.split(key)
    cut = jax.random.randint(k_cut, (), 1, a.shape[-1], dtype=jnp.int32)
    head = (jnp.arange(a.shape[-1]) < cut) | ~(jax.random.uniform(k_do, dtype=_DRAW) < p)
    return jnp.where(head, a, b), jnp.where(head, b, a)


def _mutate(key: Array, bits: Bits, p: Array) -> Bits:
    """Flip each bit independently with probability ``p``."""
    return bits ^ (jax.random.uniform(key, bits.shape, dtype=_DRAW) < p)


@dataclasses.dataclass(frozen=True)
class BinaryGA:
    """Static configuration of the binary GA (hashable: a static argument of ``jit``).

    Attributes:
      population_size: P (Table 2: 60).
      n_bits: chromosome length.
      max_generations: Table 2: 500.
      n_elites: individuals copied unchanged into the next generation.
      tournament_size: individuals per selection tournament.
      eval_chunk: fitness cache. ``None``: every individual of every running run is
        evaluated each generation, in one call (best for a GPU and large populations). An
        integer c: individuals whose chromosome was in their run's previous generation
        (elites, unchanged copies, repeated crossovers) take that fitness, and the new ones of
        all runs are pooled and evaluated c at a time, in as many calls as needed. Results
        are identical; on a CPU a converging run then costs ~40 % fewer evaluations.
      host_loop: False: a whole optimisation is one jitted ``while_loop`` with the fitness
        inside it. True (needs ``eval_chunk``): generations are driven from Python and the
        fitness is the compiled evaluation that :func:`~uvms_jax.evo.grid_search` and
        :func:`~uvms_jax.evo.zoom_from` call with ``chunk_size = eval_chunk``
        (:mod:`uvms_jax.evo._ga_host`): one compilation of a costly fitness serves the GA and
        the searches, for a few host round trips per generation.
    """

    population_size: int
    n_bits: int
    max_generations: int = 500
    n_elites: int = 2
    tournament_size: int = 2
    eval_chunk: int | None = None
    host_loop: bool = False

    def __post_init__(self):
        if self.population_size < 2 or not 0 <= self.n_elites < self.population_size:
            raise ValueError(
                f"need population_size >= 2 and 0 <= n_elites < population_size, "
                f"got {self.population_size} and {self.n_elites}"
            )
        if self.eval_chunk is not None and self.eval_chunk < 1:
            raise ValueError(f"eval_chunk must be None or >= 1, got {self.eval_chunk}")
        if self.host_loop and self.eval_chunk is None:
            raise ValueError("host_loop needs an eval_chunk (the chunk of the shared compiled fitness), got None")
        if self.n_bits < 2 or self.max_generations < 1 or self.tournament_size < 1:
            raise ValueError(
                f"need n_bits >= 2, max_generations >= 1, tournament_size >= 1, got "
                f"{self.n_bits}, {self.max_generations}, {self.tournament_size}"
            )

    @property
    def default_params(self) -> GAParams:
        return GAParams()

    def init(self, key: Array, params: GAParams) -> GAState:
        """Random initial population (uniform bits); nothing evaluated yet."""
        population = jax.random.bernoulli(key, jnp.asarray(0.5, _DRAW), (self.population_size, self.n_bits))
        dtype = jnp.asarray(params.crossover_rate, dtype=float).dtype
        return GAState(
            population=population,
            fitness=jnp.full((self.population_size,), -jnp.inf, dtype=dtype),
            best_bits=population[0],
            best_fitness=jnp.asarray(-jnp.inf, dtype=dtype),
            crossover_rate=jnp.asarray(params.crossover_rate, dtype=dtype),
            mutation_rate=jnp.asarray(params.mutation_rate, dtype=dtype),
            generation=jnp.asarray(0, dtype=jnp.int32),
            stall=jnp.asarray(0, dtype=jnp.int32),
            history=jnp.full((self.max_generations,), jnp.nan, dtype=dtype),
            done=jnp.asarray(False),
        )

    def ask(self, key: Array, state: GAState, params: GAParams) -> tuple[Bits, GAState]:
        """Next population ``(P, n_bits)``: the initial one at generation 0, else offspring."""
        P = self.population_size
        n_pairs = (P + 1) // 2
        k_sel, k_cross, k_mut = jax.random.split(key, 3)
        fitness = state.fitness
        # Fitness-favouring crossover probability per individual (rank 1 = fittest).
        rank = jnp.argsort(jnp.argsort(fitness)) / (P - 1)
        beta = params.crossover_bias
        p_cross = jnp.clip(state.crossover_rate * (1.0 - beta + 2.0 * beta * rank), 0.0, 1.0)

        sel = jax.vmap(_tournament, in_axes=(0, None, None))(
            jax.random.split(k_sel, 2 * n_pairs), fitness, self.tournament_size
        )
        pa, pb = sel[:n_pairs], sel[n_pairs:]
        ca, cb = jax.vmap(_one_point_crossover)(
            jax.random.split(k_cross, n_pairs),
            state.population[pa],
            state.population[pb],
            0.5 * (p_cross[pa] + p_cross[pb]),
        )
        children = jnp.concatenate([ca, cb], axis=0)[:P]
        children = jax.vmap(_mutate, in_axes=(0, 0, None))(jax.random.split(k_mut, P), children, state.mutation_rate)
        if self.n_elites:
            elites = jnp.argsort(-fitness)[: self.n_elites]
            children = children.at[: self.n_elites].set(state.population[elites])
        population = jnp.where(state.generation == 0, state.population, children)
        return population, state

    def tell(self, population: Bits, fitness: Array, state: GAState, params: GAParams) -> GAState:
        """Record a generation's fitness; update best, rates, history and the stop flag."""
        fitness = jnp.where(jnp.isnan(fitness), -jnp.inf, fitness).astype(state.fitness.dtype)
        i = jnp.argmax(fitness)
        better = fitness[i] > state.best_fitness
        scale = jnp.maximum(1.0, jnp.abs(jnp.where(jnp.isfinite(state.best_fitness), state.best_fitness, 0.0)))
        improved = better & ((fitness[i] - state.best_fitness) > params.improvement_tol * scale)
        best_fitness = jnp.where(better, fitness[i], state.best_fitness)
        best_bits = jnp.where(better, population[i], state.best_bits)
        decay = params.rate_decay * jnp.where(improved, params.improvement_decay, 1.0)
        generation = state.generation + 1
        stall = jnp.where(improved, 0, state.stall + 1)
        return state.replace(
            population=population,
            fitness=fitness,
            best_bits=best_bits,
            best_fitness=best_fitness,
            crossover_rate=jnp.maximum(params.crossover_rate_min, state.crossover_rate * decay),
            mutation_rate=jnp.maximum(params.mutation_rate_min, state.mutation_rate * decay),
            generation=generation,
            stall=stall,
            history=state.history.at[state.generation].set(best_fitness),
            done=(generation >= self.max_generations) | (stall >= params.stall_generations),
        )


class GAResult(NamedTuple):
    """Outcome of :func:`run_ga` (leading axis = run for :func:`run_ga_batch`).

    Attributes:
      best_x: ``(m,)`` decoded best solution (a docking pose ``[x, y, z, ψ]``).
      best_fitness: ``()`` its fitness.
      generations: ``()`` generations evaluated.
      evaluations: ``()`` fitness evaluations made (fewer than generations × P with a cache).
      history: ``(max_generations,)`` best fitness per generation (NaN after the stop).
      state: final :class:`GAState`.
    """

    best_x: Array
    best_fitness: Array
    generations: Array
    evaluations: Array
    history: Array
    state: GAState


def _pool(population: Bits, state: GAState, skip: Array, chunk: int):
    """The fitness cache of :func:`_pooled_fitness`: ``(fitness (R·P,)`` known fitness, −inf for
    the new individuals; ``order (n_slots,)`` flat indices of the new individuals first, then
    ``R·P`` (padding, past the end); ``n_new ()``; ``evaluated (R,))``."""
    R, P, L = population.shape
    same = jnp.all(population[:, :, None, :] == state.population[:, None, :, :], axis=-1)  # (R, P, P)
    same = same & jnp.isfinite(state.fitness)[:, None, :]  # nothing is known before generation 1
    known = jnp.any(same, axis=-1) | skip[:, None]
    prev = jnp.take_along_axis(state.fitness, jnp.argmax(same, axis=-1), axis=-1)
    fitness = jnp.where(known, prev, -jnp.inf).reshape(R * P)
    n_new = R * P - jnp.sum(known)
    n_slots = -(-(R * P) // chunk) * chunk
    # Pool indices of the new individuals first; padding slots point past the end (dropped).
    order = jnp.argsort(known.reshape(R * P), stable=True)
    order = jnp.concatenate([order, jnp.full((n_slots - R * P,), R * P, order.dtype)])
    order = jnp.where(jnp.arange(n_slots) < n_new, order, R * P)
    return fitness, order, n_new, (P - jnp.sum(known, axis=-1)).astype(jnp.int32)


def _pooled_fitness(problem: Any, codec: BinaryCodec, population: Bits, state: GAState, skip: Array, chunk):
    """Fitness of the populations ``(R, P, n_bits)`` of R runs.

    With ``chunk = None`` every individual is evaluated in one call. Otherwise an individual
    whose chromosome was in its run's previous generation takes that fitness (fitness is
    deterministic), runs flagged in ``skip (R,)`` (already stopped) are not evaluated, and the
    remaining individuals of all runs are pooled and evaluated ``chunk`` at a time — one
    call per chunk, however the new individuals are spread over the runs.

    Returns ``(fitness (R, P), evaluated (R,))``.
    """
    R, P, L = population.shape
    if chunk is None:
        fitness = problem.fitness(codec.decode(population.reshape(R * P, L))).reshape(R, P)
        return fitness, jnp.where(skip, 0, P).astype(jnp.int32)
    fitness, order, n_new, evaluated = _pool(population, state, skip, chunk)
    flat = population.reshape(R * P, L)

    def body(carry):
        i, fitness = carry
        idx = jax.lax.dynamic_slice(order, (i * chunk,), (chunk,))
        f = problem.fitness(codec.decode(flat[jnp.minimum(idx, R * P - 1)]))
        return i + 1, fitness.at[idx].set(f.astype(fitness.dtype), mode="drop")

    _, fitness = jax.lax.while_loop(lambda c: c[0] * chunk < n_new, body, (jnp.asarray(0, n_new.dtype), fitness))
    return fitness.reshape(R, P), evaluated


def _run_pooled(keys: Array, problem: Any, codec: BinaryCodec, ga: BinaryGA, params: GAParams) -> GAResult:
    """R independent runs (``keys (R,)``): operators vmapped over runs, fitness pooled."""
    split = jax.vmap(jax.random.split)
    k_init, k_loop = jnp.moveaxis(split(keys), 1, 0)
    state = jax.vmap(ga.init, in_axes=(0, None))(k_init, params)

    def body(carry):
        keys, state, n_evals = carry
        keys, k_ask = jnp.moveaxis(split(keys), 1, 0)
        population, asked = jax.vmap(ga.ask, in_axes=(0, 0, None))(k_ask, state, params)
        fitness, n_new = _pooled_fitness(problem, codec, population, state, state.done, ga.eval_chunk)
        told = jax.vmap(ga.tell, in_axes=(0, 0, 0, None))(population, fitness, asked, params)
        # A run that has stopped keeps its final state while the others go on.
        keep = lambda new, old: jnp.where(state.done.reshape(state.done.shape + (1,) * (new.ndim - 1)), old, new)
        return keys, jax.tree_util.tree_map(keep, told, state), n_evals + n_new

    n0 = jnp.zeros(keys.shape[:1], dtype=jnp.int32)
    _, state, n_evals = jax.lax.while_loop(lambda c: ~jnp.all(c[1].done), body, (k_loop, state, n0))
    return _result(codec, state, n_evals)


def _result(codec: BinaryCodec, state: GAState, n_evals: Array) -> GAResult:
    return GAResult(
        best_x=codec.decode(state.best_bits),
        best_fitness=state.best_fitness,
        generations=state.generation,
        evaluations=n_evals,
        history=state.history,
        state=state,
    )


_result_jit = jax.jit(_result)


def _check(codec: BinaryCodec, ga: BinaryGA) -> None:
    if codec.n_bits != ga.n_bits:
        raise ValueError(f"codec has {codec.n_bits} bits but the GA expects {ga.n_bits}")


@partial(jax.jit, static_argnames=("ga",))
def _run_batch_jit(keys, problem, codec, ga, params):
    return _run_pooled(keys, problem, codec, ga, params)


def run_ga(key: Array, problem: Any, codec: BinaryCodec, ga: BinaryGA, params: GAParams | None = None) -> GAResult:
    """One whole GA run as a single jitted ``while_loop``.

    Args:
      key: PRNG key.
      problem: pytree with a method ``fitness((n, m) values) -> (n,)`` to maximise, e.g. a
        :class:`~uvms_jax.evo.DockingProblem` (eq. 15).
      codec: chromosome ↔ value mapping (field bits, box).
      ga: static sizes.
      params: hyperparameters (default: Table 2).
    """
    out = run_ga_batch(key[None], problem, codec, ga, params)
    return jax.tree_util.tree_map(lambda x: x[0], out)


def run_ga_batch(
    keys: Array, problem: Any, codec: BinaryCodec, ga: BinaryGA, params: GAParams | None = None
) -> GAResult:
    """Independent runs, one per key in ``keys (R,)``, in one jitted ``while_loop``.

    The GA operators are vmapped over runs; the fitness of all runs' new individuals is
    evaluated together (see ``BinaryGA.eval_chunk``). The loop goes on until the last run
    stops; each run's state freezes at its own stop, so every run's result equals that of
    :func:`run_ga` with the same key.
    """
    _check(codec, ga)
    params = params if params is not None else ga.default_params
    if ga.host_loop:
        from uvms_jax.evo._ga_host import run_host_loop  # it uses this module's fitness cache

        return _result_jit(codec, *run_host_loop(keys, problem, codec, ga, params))
    return _run_batch_jit(keys, problem, codec, ga, params)


def ga_batch_compiled(
    keys: Array, problem: Any, codec: BinaryCodec, ga: BinaryGA, params: GAParams | None = None
) -> Callable[[Array, Any, BinaryCodec, GAParams], GAResult]:
    """:func:`run_ga_batch` compiled ahead of time for these arguments' shapes, without running
    it: call the result as ``fn(keys, problem, codec, params)`` (params required). Separates the
    compilation time from the run time without running a costly fitness twice. With
    ``ga.host_loop`` the steps are compiled here and the fitness at its first call, unless a
    search with ``chunk_size = ga.eval_chunk`` has compiled it already."""
    _check(codec, ga)
    params = params if params is not None else ga.default_params
    if ga.host_loop:
        from uvms_jax.evo._ga_host import compile_steps

        compile_steps(keys, codec, ga, params)
        return lambda k, p, c, prm: run_ga_batch(k, p, c, ga, prm)
    compiled = _run_batch_jit.lower(keys, problem, codec, ga, params).compile()
    return lambda k, p, c, prm: compiled(k, p, c, prm)
