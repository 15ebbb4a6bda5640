"""Shared fixtures of the evo tests."""

from pathlib import Path

import jax.numpy as jnp
import pytest
from flax import struct
from omegaconf import OmegaConf


@struct.dataclass
class Sphere:
    """A cheap stand-in problem for optimiser mechanics: maximise ``−|x − target|²``."""

    target: jnp.ndarray

    def fitness(self, x):
        return -jnp.sum((x - self.target) ** 2, axis=-1)


@pytest.fixture(scope="session")
def sphere():
    return Sphere(target=jnp.asarray([0.3, -0.45, 0.1, 0.8]))


SCENE_YAML = Path(__file__).resolve().parents[2] / "configs" / "docking" / "scene" / "paper.yaml"


@pytest.fixture(scope="session")
def scene() -> dict:
    """The paper's scene, read from the one place it is written (configs/docking/scene)."""
    return dict(OmegaConf.to_container(OmegaConf.load(SCENE_YAML)))
