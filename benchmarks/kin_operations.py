"""Scalar operations per evaluation of the fused index kernels: the primitives of the traced
expression of ``indices.manipulability_of`` / ``indices.kci_of`` for one configuration, counted by
kind (nested programs included); prints one JSON object.

This is the count a roofline needs: the expression the GPU kernel runs, before any compiler
simplifies it (XLA's cost analysis, quoted elsewhere, counts the CPU program after its own
simplification and leaves sin, cos and square roots out).

    python benchmarks/kin_operations.py > benchmarks/results/kin_operations_uvms12.json

Usage: python benchmarks/kin_operations.py [--chain uvms12|bravo7]
"""

from __future__ import annotations

import argparse
import collections
import sys

import jax
import jax.numpy as jnp
from jax.extend import core as jcore

from uvms_jax import indices, kin
from uvms_jax.files import json_text

#: Primitives that are arithmetic on a scalar (the rest move or select data).
ARITHMETIC = ("mul", "add", "sub", "neg", "div", "sqrt", "rsqrt", "sin", "cos", "abs", "max", "min", "exp", "log")


def primitive_counts(fn, *args) -> collections.Counter:
    """How often each primitive occurs in the jaxpr of ``fn(*args)``, nested jaxprs expanded."""
    counts = collections.Counter()

    def walk(jaxpr):
        for eqn in jaxpr.eqns:
            inner = [v for v in eqn.params.values() if isinstance(v, (jcore.Jaxpr, jcore.ClosedJaxpr))]
            for sub in inner:
                walk(sub.jaxpr if isinstance(sub, jcore.ClosedJaxpr) else sub)
            if not inner:
                counts[eqn.primitive.name] += 1

    walk(jax.make_jaxpr(fn)(*args).jaxpr)
    return counts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chain", choices=("uvms12", "bravo7"), default="uvms12")
    args = ap.parse_args()
    chain = getattr(kin, args.chain)()
    q = jnp.zeros((1, chain.n_joints), jnp.float32)
    record = {"benchmark": "kin_operations", "command": " ".join(["python benchmarks/kin_operations.py", *sys.argv[1:]]),
              "chain": args.chain, "n_joints": chain.n_joints, "jax": jax.__version__, "indices": {}}
    for name, fn in (("w", indices.manipulability_of), ("kci", indices.kci_of)):
        counts = primitive_counts(lambda q: fn(chain, q), q)
        record["indices"][name] = {"arithmetic": {k: counts[k] for k in ARITHMETIC if counts[k]},
                                   "other": {k: v for k, v in sorted(counts.items()) if k not in ARITHMETIC}}
    print(json_text(record))


if __name__ == "__main__":
    main()
