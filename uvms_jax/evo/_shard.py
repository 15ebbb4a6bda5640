"""Scale-out: evaluate grids and GA populations sharded over all local devices.

A :class:`ShardedProblem` wraps any problem with a ``fitness((n, m)) -> (n,)`` method and
constrains the candidate batch to be split along a one-axis device mesh; XLA's SPMD
partitioner then runs each device's share of the IK × control-point × candidate work and
reduces the results. Grid search, the GA and CMA-ES take it unchanged, because they only
ever call ``problem.fitness``. Batch sizes (grid ``chunk_size``, population × runs) should be
multiples of the device count.
"""

from __future__ import annotations

from typing import Any, Sequence

import jax
import numpy as np
from flax import struct
from jax.sharding import Mesh, NamedSharding, PartitionSpec

BATCH_AXIS = "batch"


def device_mesh(devices: Sequence[jax.Device] | None = None) -> Mesh:
    """A one-axis mesh (``"batch"``) over ``devices`` (default: all local devices)."""
    devices = jax.local_devices() if devices is None else list(devices)
    if not devices:
        raise ValueError("device_mesh needs at least one device")
    return Mesh(np.asarray(devices), (BATCH_AXIS,))


@struct.dataclass
class ShardedProblem:
    """``problem`` whose fitness batches are split across the devices of ``mesh``."""

    problem: Any
    mesh: Mesh = struct.field(pytree_node=False)

    @property
    def pose_low(self) -> jax.Array:
        """The wrapped problem's ``(4,)`` lower corner of the candidate box."""
        return self.problem.pose_low

    @property
    def pose_high(self) -> jax.Array:
        """The wrapped problem's ``(4,)`` upper corner of the candidate box."""
        return self.problem.pose_high

    def fitness(self, x: jax.Array) -> jax.Array:
        """``problem.fitness`` of ``x (n, m)``, with ``n`` sharded over the mesh."""
        spec = PartitionSpec(BATCH_AXIS, *([None] * (x.ndim - 1)))
        x = jax.lax.with_sharding_constraint(x, NamedSharding(self.mesh, spec))
        return self.problem.fitness(x)


def shard_over_devices(problem: Any, mesh: Mesh | None = None) -> ShardedProblem:
    """Wrap ``problem`` so that every fitness batch is sharded over ``mesh`` (default: all
    local devices). The result is a drop-in replacement for ``problem``."""
    return ShardedProblem(problem=problem, mesh=device_mesh() if mesh is None else mesh)
