"""The evaluated FFBN (scalers folded into the layers, written out as multiply-adds) equals the
network as trained: flax's MLP on normalised inputs, output mapped back."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax.surrogate import folded_layers, init_ffbn, mlp_apply

from _surrogate_helpers import synthetic_dataset


def _trained_form(net, x):
    """The oracle: flax's Dense layers on min–max normalised inputs, output un-normalised."""
    return net.y_norm.inverse(mlp_apply(net.params, net.x_norm(x)))


@pytest.mark.parametrize("hidden", [1, 3, 8])
def test_evaluation_equals_the_normalised_network(hidden):
    data = synthetic_dataset(jax.random.key(0), 200)
    net = init_ffbn(jax.random.key(hidden), hidden, data)
    # Non-zero biases, so that every folded term is exercised.
    net = net.replace(params=jax.tree_util.tree_map(lambda p: p + 0.3, net.params))
    x = jnp.asarray(data.x)
    np.testing.assert_allclose(np.asarray(net.predict(x)), np.asarray(_trained_form(net, x)), rtol=1e-12)
    np.testing.assert_allclose(np.asarray(net.index_fn(data.q)), np.asarray(_trained_form(net, x)), rtol=1e-12)
    out32 = net.predict(x.astype(jnp.float32))
    assert out32.dtype == jnp.float32
    np.testing.assert_allclose(np.asarray(out32), np.asarray(_trained_form(net, x)), rtol=1e-5)


def test_folded_layers_shapes_and_bad_input():
    data = synthetic_dataset(jax.random.key(0), 50)
    net = init_ffbn(jax.random.key(1), 4, data)
    A, c, v, d = folded_layers(net)
    assert A.shape == (7, 4) and c.shape == (4,) and v.shape == (4,) and d.shape == ()
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 7\)"):
        net.predict(jnp.zeros((3, 12)))
