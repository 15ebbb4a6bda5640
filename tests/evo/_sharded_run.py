"""Run in a fresh process with 4 fake CPU devices: sharded vs single-device results.

Prints one JSON line; used by test_evo_shard.py (XLA_FLAGS must be set before jax starts).
"""

import json
import sys

import jax
import numpy as np
from omegaconf import OmegaConf

from uvms_jax import evo

scene = dict(OmegaConf.to_container(OmegaConf.load(sys.argv[1])))
problem = evo.make_docking_problem(**scene)
sharded = evo.shard_over_devices(problem)
low, high = problem.pose_low, problem.pose_high
counts, periodic = (12, 12, 4, 8), (False, False, False, True)
single = evo.grid_search(problem, low, high, counts, periodic, chunk_size=512)
multi = evo.grid_search(sharded, low, high, counts, periodic, chunk_size=512)

codec = evo.make_codec(low, high, [8, 8, 6, 6], gray=True)
ga = evo.BinaryGA(population_size=20, n_bits=codec.n_bits, max_generations=15)
keys = jax.random.split(jax.random.key(3), 4)
ga_single = evo.run_ga_batch(keys, problem, codec, ga)
ga_multi = evo.run_ga_batch(keys, sharded, codec, ga)
print(
    json.dumps(
        {
            "devices": len(jax.devices()),
            "mesh": int(sharded.mesh.devices.size),
            "grid_x": [np.asarray(single.x).tolist(), np.asarray(multi.x).tolist()],
            "grid_f": [float(single.fitness), float(multi.fitness)],
            "ga_f": [np.asarray(ga_single.best_fitness).tolist(), np.asarray(ga_multi.best_fitness).tolist()],
            "ga_x": [np.asarray(ga_single.best_x).tolist(), np.asarray(ga_multi.best_x).tolist()],
        }
    )
)
