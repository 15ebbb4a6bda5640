"""FFBN model: batching, dtype, operation counts, input checks."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax.surrogate import (MLP, init_ffbn, init_ffbns, padded_width, predict_side_by_side, train_ffbn_adam,
                               train_ffbn_lm)

from _surrogate_helpers import synthetic_dataset

# A network zero-padded to a wider layer trains as the unpadded one but through matrices of
# another shape: its sums round differently in the last bits, and training carries that on.
# Measured (float64, XLA's default, AVX and SSE4.2 ISAs on an Intel Xeon): 5 LM epochs differ by
# at most 2.0e-13 (loss history) and 4.0e-14 (predictions) between padded and plain, and by
# 2.9e-13 across the ISAs; 20 Adam steps by 3.7e-16. The tolerances are ~3e4× those spreads,
# room for CPUs whose rounding was not measured.
PAD_LM_RTOL = 1e-8
PAD_ADAM_RTOL = 1e-10
# The same trained network's loss summed twice (the trainer's and a mean here, float64, 300
# samples): their difference is bounded by n·eps ≈ 3e-14 of the loss; the tolerance is loose.
MSE_RTOL = 1e-6


@pytest.fixture(scope="module")
def data():
    return synthetic_dataset(jax.random.key(0), 300)


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_index_fn_reads_the_input_joints_for_any_batch_shape(data, shape):
    net = init_ffbn(jax.random.key(1), 3, data)
    q = jax.random.uniform(jax.random.key(2), shape + (12,), jnp.float64)
    out = net.index_fn(q)
    assert out.shape == shape
    np.testing.assert_allclose(np.asarray(out), np.asarray(net.predict(q[..., list(net.inputs)])), rtol=1e-12)
    # Non-input joints do not matter.
    q2 = q.at[..., 0].add(1.0).at[..., 11].add(1.0)
    np.testing.assert_allclose(np.asarray(net.index_fn(q2)), np.asarray(out), rtol=1e-12)


def test_index_fn_computes_in_the_dtype_of_q(data):
    net = init_ffbn(jax.random.key(1), 3, data)
    q = data.q[:10]
    out32 = net.index_fn(q.astype(jnp.float32))
    assert out32.dtype == jnp.float32
    np.testing.assert_allclose(np.asarray(out32), np.asarray(net.index_fn(q)), rtol=1e-5)
    assert jax.jit(net.index_fn)(q).shape == (10,)


def test_operation_count_matches_paper_table_4(data):
    # Paper Table 4: FFBN-w (7 inputs, 8 neurons) 184 operations; FFBN-KCI (11, 25) 775.
    assert init_ffbn(jax.random.key(0), 8, data).operation_count == 184
    kci_like = data.replace(x=data.q[:, :11], inputs=tuple(range(11)))
    assert init_ffbn(jax.random.key(0), 25, kci_like).operation_count == 775


def test_normalisation_maps_training_ranges_to_unit_interval(data):
    net = init_ffbn(jax.random.key(0), 2, data)
    x_n, y_n = np.asarray(net.x_norm(data.x)), np.asarray(net.y_norm(data.y))
    np.testing.assert_allclose(x_n.min(0), -1.0, atol=1e-12)
    np.testing.assert_allclose(x_n.max(0), 1.0, atol=1e-12)
    assert np.isclose(y_n.min(), -1.0) and np.isclose(y_n.max(), 1.0)


def test_trainers_improve_the_network(data):
    net = init_ffbn(jax.random.key(0), 4, data)
    err0 = float(jnp.mean((net.predict(data.x) - data.y) ** 2))
    lm_net, state, history = train_ffbn_lm(net, data, max_epochs=30)
    assert float(state.mse) < 0.01 * err0
    np.testing.assert_allclose(float(jnp.mean((lm_net.predict(data.x) - data.y) ** 2)), float(state.mse), rtol=MSE_RTOL)
    adam_net, history = train_ffbn_adam(net, data, steps=100)
    assert float(history[-1]) < float(history[0])


def test_zero_padded_training_gives_the_unpadded_network(data):
    net = init_ffbn(jax.random.key(5), 3, data)
    plain, s_plain, h_plain = train_ffbn_lm(net, data, max_epochs=5)
    padded, s_pad, h_pad = train_ffbn_lm(net, data, max_epochs=5, pad_to=8)
    assert padded.hidden == 3
    np.testing.assert_allclose(np.asarray(h_pad), np.asarray(h_plain), rtol=PAD_LM_RTOL)
    np.testing.assert_allclose(np.asarray(padded.predict(data.x)), np.asarray(plain.predict(data.x)), rtol=PAD_LM_RTOL)
    adam_plain, _ = train_ffbn_adam(net, data, steps=20)
    adam_pad, _ = train_ffbn_adam(net, data, steps=20, pad_to=8)
    np.testing.assert_allclose(np.asarray(adam_pad.predict(data.x)), np.asarray(adam_plain.predict(data.x)),
                               rtol=PAD_ADAM_RTOL)
    assert padded_width(1) == 8 and padded_width(9) == 16 and padded_width(64) == 64


def test_networks_of_several_sizes_start_and_predict_as_one_at_a_time(data):
    keys, sizes = list(jax.random.split(jax.random.key(3), 3)), [2, 5, 7]
    nets = init_ffbns(keys, sizes, data)
    for key, size, net in zip(keys, sizes, nets):
        # flax's own initialisation of that size, outside any compiled call
        expected = MLP(size).init(key, net.x_norm(data.x[:1]))["params"]
        for layer in ("hidden", "output"):
            for leaf in ("kernel", "bias"):
                np.testing.assert_array_equal(np.asarray(net.params[layer][leaf]), np.asarray(expected[layer][leaf]))
    trained = [train_ffbn_lm(net, data, max_epochs=3)[0] for net in nets]
    together = predict_side_by_side(trained, data.x)
    assert together.shape == (3, data.x.shape[0])
    for net, row in zip(trained, together):
        np.testing.assert_allclose(np.asarray(row), np.asarray(net.predict(data.x)), rtol=1e-12, atol=1e-14)


def test_bad_input_raises(data):
    with pytest.raises(ValueError, match="hidden"):
        init_ffbn(jax.random.key(0), 0, data)
    with pytest.raises(ValueError, match="one key per size"):
        init_ffbns([jax.random.key(0)], [2, 3], data)
    net = init_ffbn(jax.random.key(0), 2, data)
    with pytest.raises(ValueError, match="shape"):
        net.index_fn(jnp.zeros((3, 7)))
    other = data.replace(inputs=tuple(range(7)))
    with pytest.raises(ValueError, match="inputs"):
        train_ffbn_lm(net, other, max_epochs=1)
