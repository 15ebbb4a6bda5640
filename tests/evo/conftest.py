"""Shared fixtures of the evo tests."""

import jax.numpy as jnp
import pytest
from flax import struct


@struct.dataclass
class Sphere:
    """A cheap stand-in problem for optimiser mechanics: maximise ``−|x − target|²``."""

    target: jnp.ndarray

    def fitness(self, x):
        return -jnp.sum((x - self.target) ** 2, axis=-1)


@pytest.fixture(scope="session")
def sphere():
    return Sphere(target=jnp.asarray([0.3, -0.45, 0.1, 0.8]))
