"""What FFBN and RBFN share: a network of a few joints standing in for an index of all of them."""

from __future__ import annotations

import jax.numpy as jnp
from flax import struct
from jax import Array

from uvms_jax.surrogate._scaler import Scaler


@struct.dataclass(kw_only=True)
class JointInputs:
    """Base of the surrogate networks: the fields every network has, and its evaluation on
    whole configurations. A subclass adds its parameters and ``predict``.

    The fields are keyword-only, so that a subclass's parameters (no defaults) may follow
    ``n_joints``'s default; every network is built and loaded (``_io.py``) by keyword.

    Attributes:
      x_norm: input scaler, ``(d,)`` offsets and scales [joint units].
      y_norm: output scaler, scalar offset and scale [index units].
      index: "w" or "kci" (static).
      inputs: joint indices of the inputs in the full configuration (static).
      n_joints: length of the full configuration ``q`` (static).
    """

    x_norm: Scaler
    y_norm: Scaler
    index: str = struct.field(pytree_node=False)
    inputs: tuple[int, ...] = struct.field(pytree_node=False)
    n_joints: int = struct.field(pytree_node=False, default=12)

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
