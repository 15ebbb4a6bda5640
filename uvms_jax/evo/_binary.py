"""Binary chromosome of the docking GA: ``x | y | z | ψ`` bit fields (paper §III.B).

Each field is a fixed-point integer, optionally in reflected Gray code: neighbouring values
then differ in one bit, and mirror values ``v ↔ 2^n − 1 − v`` (here ``x ↔ −x`` on the
symmetric block) differ only in the field's first bit — one mutation apart instead of a
"Hamming cliff" of several bits.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array

Bits = Array  # (..., n_bits) bool, most significant bit first within each field


@struct.dataclass
class BinaryCodec:
    """Fixed-point coding of a box ``[low, high]`` with ``field_bits[i]`` bits per variable.

    Field i holds an unsigned integer ``v ∈ [0, 2^n_i − 1]`` (MSB first) that decodes to
    ``low_i + v / (2^n_i − 1) · (high_i − low_i)``: both box ends are representable and the
    resolution of variable i is ``(high_i − low_i) / (2^n_i − 1)``.

    Attributes:
      low, high: ``(m,)`` box corners.
      field_bits: bits per variable (static).
      gray: fields in reflected Gray code (static); plain binary otherwise.
    """

    low: Array
    high: Array
    field_bits: tuple[int, ...] = struct.field(pytree_node=False)
    gray: bool = struct.field(pytree_node=False, default=True)

    @property
    def n_bits(self) -> int:
        return int(sum(self.field_bits))

    @property
    def resolution(self) -> Array:
        """``(m,)`` step between neighbouring codes of each variable."""
        levels = jnp.asarray([2.0**n - 1.0 for n in self.field_bits], dtype=self.low.dtype)
        return (self.high - self.low) / levels

    def _weights(self) -> np.ndarray:
        """``(n_bits, m)`` place values: bit j of field i weighs ``2^(n_i − 1 − j)`` in field i."""
        W = np.zeros((self.n_bits, len(self.field_bits)))
        start = 0
        for i, n in enumerate(self.field_bits):
            W[start : start + n, i] = 2.0 ** np.arange(n - 1, -1, -1)
            start += n
        return W

    def _fields(self):
        start = 0
        for n in self.field_bits:
            yield start, n
            start += n

    def decode(self, bits: Bits) -> Array:
        """``(..., n_bits)`` chromosomes → ``(..., m)`` values in the box."""
        bits = jnp.asarray(bits)
        if self.gray:  # binary bit i = XOR of Gray bits 0..i of its field
            bits = jnp.concatenate(
                [jnp.cumsum(bits[..., s : s + n].astype(jnp.int32), axis=-1) % 2 for s, n in self._fields()], axis=-1
            )
        levels = jnp.matmul(bits.astype(self.low.dtype), jnp.asarray(self._weights(), dtype=self.low.dtype),
                            precision=jax.lax.Precision.HIGHEST)  # exact integers on GPUs too
        return self.low + levels * self.resolution

    def encode(self, x) -> Bits:
        """``(..., m)`` values → nearest codes ``(..., n_bits)`` (values are clipped to the box)."""
        x = jnp.asarray(x, dtype=self.low.dtype)
        v = jnp.round((jnp.clip(x, self.low, self.high) - self.low) / self.resolution).astype(jnp.int32)
        fields = []
        for i, n in enumerate(self.field_bits):
            vi = v[..., i, None]
            if self.gray:
                vi = vi ^ (vi >> 1)
            shifts = jnp.arange(n - 1, -1, -1, dtype=jnp.int32)
            fields.append(((vi >> shifts) & 1).astype(bool))
        return jnp.concatenate(fields, axis=-1)


def make_codec(low, high, field_bits, gray: bool = True) -> BinaryCodec:
    """Build a :class:`BinaryCodec`; ``field_bits`` positive, at most 30 per field, ``low < high``."""
    field_bits = tuple(int(n) for n in field_bits)
    low, high = jnp.asarray(low), jnp.asarray(high)
    if low.shape != (len(field_bits),) or high.shape != low.shape:
        raise ValueError(f"low/high must have shape ({len(field_bits)},), got {low.shape} and {high.shape}")
    if any(n < 1 or n > 30 for n in field_bits):
        raise ValueError(f"bits per field must be in 1..30, got {field_bits}")
    if not bool(jnp.all(low < high)):
        raise ValueError(f"box is empty: low {low} must be < high {high}")
    return BinaryCodec(low=low, high=high.astype(low.dtype), field_bits=field_bits, gray=bool(gray))
