"""Binary GA (paper Table 2): coding, determinism, monotone best fitness, batch = single runs."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import evo

LOW, HIGH = np.array([-1.0, -1.0, 0.0, -np.pi]), np.array([1.0, 1.0, 0.3, np.pi])
BITS = (8, 8, 5, 6)
STALL = 15

# The codec's maps, each compiled once per shape instead of primitive by primitive.
_encode = jax.jit(lambda codec, x: codec.encode(x))
_decode = jax.jit(lambda codec, bits: codec.decode(bits))


@pytest.fixture(scope="module")
def setup():
    codec = evo.make_codec(LOW, HIGH, BITS)
    ga = evo.BinaryGA(population_size=24, n_bits=codec.n_bits, max_generations=120)
    params = ga.default_params.replace(stall_generations=STALL)
    keys = jax.random.split(jax.random.key(1), 4)
    return codec, ga, params, keys


@pytest.fixture(scope="module")
def batch(setup, sphere):
    codec, ga, params, keys = setup
    return evo.run_ga_batch(keys, sphere, codec, ga, params)


def test_codec_roundtrip(setup):
    codec = setup[0]
    bits = jax.random.bernoulli(jax.random.key(0), 0.5, (50, codec.n_bits))
    np.testing.assert_array_equal(np.asarray(_encode(codec, _decode(codec, bits))), np.asarray(bits))
    x = np.random.default_rng(0).uniform(LOW, HIGH, (50, 4))
    err = np.abs(np.asarray(_decode(codec, _encode(codec, x))) - x)
    assert np.all(err <= np.asarray(codec.resolution) / 2 + 1e-12)
    np.testing.assert_allclose(np.asarray(_decode(codec, jnp.zeros(codec.n_bits, bool))), LOW)
    np.testing.assert_allclose(np.asarray(_decode(codec, _encode(codec, HIGH))), HIGH)
    plain = evo.make_codec(LOW, HIGH, BITS, gray=False)
    np.testing.assert_allclose(np.asarray(_decode(plain, jnp.ones(plain.n_bits, bool))), HIGH)


def test_gray_code_mirror_is_one_bit():
    """In reflected Gray code, v and 2^n − 1 − v (x and −x on the block) differ in one bit."""
    codec = evo.make_codec(LOW, HIGH, BITS)
    x = np.random.default_rng(1).uniform(LOW, HIGH, (50, 4))  # the batch shape of the roundtrip test
    mirrored = x.copy()
    mirrored[:, 0] = -x[:, 0]
    a, b = np.asarray(_encode(codec, x)), np.asarray(_encode(codec, mirrored))
    flips = np.nonzero(a != b)
    assert np.all(flips[1] == 0)  # only the first bit of the x field
    # and neighbouring codes differ in exactly one bit
    step = x.copy()
    step[:, 1] = x[:, 1] + np.asarray(codec.resolution)[1]
    inside = step[:, 1] <= HIGH[1]
    d = np.sum(a != np.asarray(_encode(codec, step)), axis=-1)
    assert np.all(d[inside] == 1)


def test_same_seed_same_result(setup, batch, sphere):
    codec, ga, params, keys = setup
    again = evo.run_ga_batch(keys, sphere, codec, ga, params)
    for a, b in zip(jax.tree_util.tree_leaves(batch), jax.tree_util.tree_leaves(again)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    other = evo.run_ga_batch(jax.random.split(jax.random.key(9), 4), sphere, codec, ga, params)
    assert not np.array_equal(np.asarray(batch.state.population), np.asarray(other.state.population))


def test_best_fitness_never_decreases_and_stop_rule(setup, batch, sphere):
    codec, ga, params, keys = setup
    # NumPy once (indexing device arrays in the loop dispatches an op per element); the oracle
    # fitness of every run's best_x in one call.
    generations, history, best_fitness = (np.asarray(a) for a in (batch.generations, batch.history,
                                                                   batch.best_fitness))
    oracle = np.asarray(sphere.fitness(batch.best_x))
    for r in range(keys.shape[0]):
        g = int(generations[r])
        h = history[r]
        assert 1 <= g <= ga.max_generations
        assert np.all(np.isfinite(h[:g])) and np.all(np.isnan(h[g:]))
        assert np.all(np.diff(h[:g]) >= 0.0)
        assert h[g - 1] == float(best_fitness[r])
        if g < ga.max_generations:  # stopped by the stall rule: the last generations are flat
            assert np.all(h[g - STALL - 1 : g] == h[g - 1])
        # The reported best is the decoded best chromosome, and it is near the optimum.
        assert float(oracle[r]) == pytest.approx(float(best_fitness[r]))
        assert float(best_fitness[r]) > -0.01


def test_batch_equals_single_run(setup, batch, sphere):
    codec, ga, params, keys = setup
    single = evo.run_ga(keys[2], sphere, codec, ga, params)
    np.testing.assert_array_equal(np.asarray(batch.best_x[2]), np.asarray(single.best_x))
    np.testing.assert_array_equal(np.asarray(batch.history[2]), np.asarray(single.history))
    assert int(batch.generations[2]) == int(single.generations)


@pytest.mark.parametrize("chunk", [7])
def test_fitness_cache_gives_identical_runs(setup, batch, sphere, chunk):
    codec, ga, params, keys = setup
    cached = evo.run_ga_batch(keys, sphere, codec, dataclasses.replace(ga, eval_chunk=chunk), params)
    np.testing.assert_array_equal(np.asarray(cached.history), np.asarray(batch.history))
    np.testing.assert_array_equal(np.asarray(cached.best_x), np.asarray(batch.best_x))
    full = np.asarray(batch.generations) * ga.population_size
    np.testing.assert_array_equal(np.asarray(batch.evaluations), full)
    assert np.all(np.asarray(cached.evaluations) < full)  # elites alone are never re-evaluated


def test_host_loop_gives_identical_runs(setup, sphere):
    """Generations driven from Python with the shared compiled fitness: the same runs as the
    jitted loop with the same fitness cache (the sphere's fitness rounds alike in both)."""
    codec, ga, params, keys = setup
    looped = evo.run_ga_batch(keys, sphere, codec, dataclasses.replace(ga, eval_chunk=7), params)
    host = evo.run_ga_batch(keys, sphere, codec, dataclasses.replace(ga, eval_chunk=7, host_loop=True), params)
    for field in ("history", "best_x", "best_fitness", "generations", "evaluations"):
        np.testing.assert_array_equal(np.asarray(getattr(host, field)), np.asarray(getattr(looped, field)),
                                      err_msg=field)
    with pytest.raises(ValueError, match="host_loop needs an eval_chunk"):
        dataclasses.replace(ga, host_loop=True)


def test_elitism_and_rate_decay(setup, sphere):
    codec, ga, params, _ = setup
    ask, tell = jax.jit(ga.ask), jax.jit(ga.tell)
    fitness = jax.jit(lambda pop: sphere.fitness(codec.decode(pop)))
    state = ga.init(jax.random.key(3), params)
    key = jax.random.key(4)
    prev_best = -np.inf
    for g in range(4):
        key, k = jax.random.split(key)
        pop, state = ask(k, state, params)
        if g > 0:  # the best of the last generation is carried over unchanged
            best_prev = np.asarray(state.population)[int(np.argmax(np.asarray(state.fitness)))]
            assert any(np.array_equal(best_prev, row) for row in np.asarray(pop[: ga.n_elites]))
        state = tell(pop, fitness(pop), state, params)
        assert float(state.best_fitness) >= prev_best
        prev_best = float(state.best_fitness)
    assert float(state.mutation_rate) < params.mutation_rate
    assert float(state.crossover_rate) < params.crossover_rate


def test_bad_configuration_is_rejected(sphere):
    with pytest.raises(ValueError, match="n_elites"):
        evo.BinaryGA(population_size=4, n_bits=10, n_elites=4)
    with pytest.raises(ValueError, match="bits"):
        evo.make_codec(LOW, HIGH, (8, 8, 0, 6))
    with pytest.raises(ValueError, match="empty"):
        evo.make_codec(HIGH, LOW, BITS)
    codec = evo.make_codec(LOW, HIGH, BITS)
    with pytest.raises(ValueError, match="bits"):
        evo.run_ga(jax.random.key(0), sphere, codec, evo.BinaryGA(population_size=4, n_bits=5))
