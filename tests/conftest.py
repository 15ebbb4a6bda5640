"""Test-wide settings: float64 available (oracle comparisons), CPU only, reproducible properties.

Hypothesis draws its examples from a fixed seed unless ``HYPOTHESIS_PROFILE=explore`` is set, so a
CI run is repeatable; use the explore profile to search new examples locally.
"""

import os

os.environ.setdefault("JAX_PLATFORMS", "cpu")
# The tests run small batches, so compiling dominates their time, and most of a compile is
# generating and optimising machine code the tests then run for milliseconds. LLVM level 0
# without its expensive passes, and XLA's older elemental emitters (which lower a large
# elementwise fusion in about half the time of the MLIR fusion emitters), keep XLA's own graph
# optimisations (fusion, simplification) and make each compile several times cheaper.
# Subprocesses the tests start inherit these flags.
TEST_XLA_FLAGS = (
    "--xla_backend_optimization_level=0",
    "--xla_llvm_disable_expensive_passes=true",
    "--xla_cpu_use_fusion_emitters=false",
)
# The flags as they were, for a subprocess whose run, not its compile, takes the time.
os.environ.setdefault("XLA_FLAGS_OUTSIDE_TESTS", os.environ.get("XLA_FLAGS", ""))
os.environ["XLA_FLAGS"] = " ".join(filter(None, [os.environ.get("XLA_FLAGS"), *TEST_XLA_FLAGS]))

import jax  # noqa: E402
from hypothesis import settings  # noqa: E402

jax.config.update("jax_enable_x64", True)

settings.register_profile("repeatable", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))
