"""Min–max normalisation of network inputs and outputs to [−1, 1] (Matlab ``mapminmax``)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array


@struct.dataclass
class Scaler:
    """Affine map ``z = (v − offset) · scale`` onto [−1, 1] per feature.

    Attributes:
      offset: ``(d,)`` or ``()`` centre of the training range (units of the feature).
      scale: ``(d,)`` or ``()`` ``2 / (max − min)``; 1 where a feature is constant in the
        training data (such a feature then only shifts, it is not blown up).
    """

    offset: Array
    scale: Array

    def __call__(self, v: Array) -> Array:
        """Normalise ``v: (..., d)`` (or ``(...)`` for a scalar feature)."""
        return (v - self.offset.astype(v.dtype)) * self.scale.astype(v.dtype)

    def inverse(self, z: Array) -> Array:
        """Back to feature units: ``v = z / scale + offset``."""
        return z / self.scale.astype(z.dtype) + self.offset.astype(z.dtype)


def fit_scaler(v, axis: int | None = 0) -> Scaler:
    """Min–max scaler of ``v: (n, d)`` per column (``axis=0``) or of ``v: (n,)`` overall.

    Raises:
      ValueError: if ``v`` is empty or not finite.
    """
    v = np.asarray(v, dtype=np.float64)
    if v.size == 0:
        raise ValueError("cannot fit a scaler to an empty array")
    if not np.all(np.isfinite(v)):
        raise ValueError("cannot fit a scaler to data with NaN or infinite values")
    lo, hi = v.min(axis=axis), v.max(axis=axis)
    span = hi - lo
    scale = np.where(span > 0, 2.0 / np.where(span > 0, span, 1.0), 1.0)
    return Scaler(offset=jnp.asarray((hi + lo) / 2.0), scale=jnp.asarray(scale))
