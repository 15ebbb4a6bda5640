"""Test-wide settings: float64 available (oracle comparisons), CPU only, reproducible properties.

Hypothesis draws its examples from a fixed seed unless ``HYPOTHESIS_PROFILE=explore`` is set, so a
CI run is repeatable; use the explore profile to search new examples locally.
"""

import os

os.environ.setdefault("JAX_PLATFORMS", "cpu")
# The tests run small batches, so compiling dominates their time, and most of a compile is
# LLVM optimising machine code the tests then run for milliseconds. Level 0 keeps XLA's own
# graph optimisations (fusion, simplification) and takes a fifth off a cold-cache run.
# Subprocesses the tests start inherit it.
os.environ["XLA_FLAGS"] = " ".join(filter(None, [os.environ.get("XLA_FLAGS"), "--xla_backend_optimization_level=0"]))

import jax  # noqa: E402
from hypothesis import settings  # noqa: E402

jax.config.update("jax_enable_x64", True)

settings.register_profile("repeatable", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))
