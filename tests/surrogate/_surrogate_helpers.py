"""Shared data of the surrogate tests: small synthetic regression sets shaped like D2."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from uvms_jax.surrogate import INDEX_INPUTS, Dataset, Sampling


def synthetic_dataset(key, n: int, dtype=jnp.float64) -> Dataset:
    """A D2-shaped dataset (7 inputs of a 12-joint q) with a smooth target far from 0.

    ``y = 5 + sin(2 θ5) cos(2 θ6) + 0.5 θ7``: one tanh unit cannot fit the product term, a few can.
    """
    q = jax.random.uniform(key, (n, 12), dtype, -1.0, 1.0)
    inputs = INDEX_INPUTS["w"]
    x = q[:, list(inputs)]
    y = 5.0 + jnp.sin(2.0 * x[:, 0]) * jnp.cos(2.0 * x[:, 1]) + 0.5 * x[:, 2]
    return Dataset(q=q, x=x, y=y, index="w", inputs=inputs, sampling=Sampling())
