"""What FFBN and RBFN share: a network of a few joints standing in for an index of all of them."""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array


class JointInputs:
    """Mixin for surrogate networks with ``inputs`` (joint indices), ``n_joints`` and ``predict``."""

    inputs: tuple[int, ...]
    n_joints: int

    @property
    def n_inputs(self) -> int:
        """Network inputs d (joints the index depends on)."""
        return len(self.inputs)

    def index_fn(self, q: Array) -> Array:
        """Stand-in for the analytic index: ``q: (..., n_joints)`` [m, rad] → ``(...)``.

        Raises:
          ValueError: ``q``'s last axis is not ``n_joints`` long.
        """
        q = jnp.asarray(q)
        if q.ndim == 0 or q.shape[-1] != self.n_joints:
            raise ValueError(f"q must have shape (..., {self.n_joints}), got {q.shape}")
        if not jnp.issubdtype(q.dtype, jnp.floating):
            q = q.astype(jnp.float32)
        return self._from_joints(q)

    def _checked_inputs(self, x) -> Array:
        """``x`` as an array of network inputs ``(..., d)``.

        Raises:
          ValueError: ``x``'s last axis is not ``d`` long.
        """
        x = jnp.asarray(x)
        if x.ndim == 0 or x.shape[-1] != self.n_inputs:
            raise ValueError(f"x must have shape (..., {self.n_inputs}), got {x.shape}")
        return x

    def _from_joints(self, q: Array) -> Array:
        """The network at its inputs taken from ``q: (..., n_joints)``; a network may read the
        columns of ``q`` directly instead of this gathered copy."""
        return self.predict(q[..., list(self.inputs)])
