"""Test-wide settings: float64 available (oracle comparisons), CPU only, reproducible properties.

Hypothesis draws its examples from a fixed seed unless ``HYPOTHESIS_PROFILE=explore`` is set, so a
CI run is repeatable; use the explore profile to search new examples locally.
"""

import os

os.environ.setdefault("JAX_PLATFORMS", "cpu")

import jax  # noqa: E402
from hypothesis import settings  # noqa: E402

jax.config.update("jax_enable_x64", True)

settings.register_profile("repeatable", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))
