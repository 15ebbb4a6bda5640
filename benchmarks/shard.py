"""Docking grid search on one device vs sharded over all local devices, one process.

Prints one JSON object: candidates, seconds and candidates/s for the single-device and the
sharded search, whether both found the same optimum, and the device list.

Usage: python benchmarks/shard.py [--counts 64,64,16,64] [--chunk 1048576]
       XLA_FLAGS=--xla_force_host_platform_device_count=2 python benchmarks/shard.py --counts 8,8,4,8   # CPU API check
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import jax
import numpy as np
import yaml

from uvms_jax import evo
from uvms_jax.files import json_text

SCENE = Path(__file__).resolve().parents[1] / "configs" / "docking" / "scene" / "paper.yaml"


def timed(fn):
    fn()  # compile
    t0 = time.perf_counter()
    out = fn()
    jax.block_until_ready(out.fitness)
    return out, time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", default="64,64,16,64")
    parser.add_argument("--chunk", type=int, default=1 << 16)
    args = parser.parse_args()
    counts = tuple(int(c) for c in args.counts.split(","))
    problem = evo.make_docking_problem(**yaml.safe_load(SCENE.read_text()))
    periodic = (False, False, False, True)
    search = lambda p: evo.grid_search(p, problem.pose_low, problem.pose_high, counts, periodic, args.chunk)
    single, t_single = timed(lambda: search(problem))
    sharded_problem = evo.shard_over_devices(problem)
    sharded, t_sharded = timed(lambda: search(sharded_problem))
    n = single.n_candidates
    print(json_text({
        "benchmark": "shard_grid",
        "command": " ".join([*(["XLA_FLAGS=" + os.environ["XLA_FLAGS"]] if "XLA_FLAGS" in os.environ else []),
                             "python benchmarks/shard.py", *sys.argv[1:]]),
        "devices": [str(d) for d in jax.local_devices()],
        "device_kind": jax.local_devices()[0].device_kind, "jax": jax.__version__, "chunk": args.chunk,
        "candidates": n,
        "single_s": t_single, "single_per_s": n / t_single,
        "sharded_s": t_sharded, "sharded_per_s": n / t_sharded,
        "speedup": t_single / t_sharded,
        "same_optimum": bool(np.array_equal(np.asarray(single.x), np.asarray(sharded.x))),
        "fitness": float(single.fitness),
    }))


if __name__ == "__main__":
    main()
