"""Synchronised point-to-point moves with velocity and acceleration limits (thesis 4.6).

All joints of a move share one normalised trapezoidal time scaling ``s(τ)``, ``τ = t/T``, so
they start and arrive together; the duration ``T`` is the shortest that keeps every joint
within its velocity and acceleration limits, and never shorter than the plan asks for.

With an acceleration fraction ``f`` (0 < f ≤ ½) of ``T``:
``s = τ²/(2f(1-f))`` for ``τ < f``, ``(τ - f/2)/(1-f)`` in the middle, and
``1 - (1-τ)²/(2f(1-f))`` for ``τ > 1-f``; peak ``ṡ = 1/((1-f)T)``, ``s̈ = 1/(f(1-f)T²)``.
For joint j moving ``D_j``: ``D_j/((1-f)T) ≤ v_j`` and ``D_j/(f(1-f)T²) ≤ a_j``. With
``r_v = max D_j/v_j`` and ``r_a = max D_j/a_j`` the shortest duration is
``T = r_v + r_a/r_v`` when ``r_v² ≥ r_a`` (trapezoid) and ``2√r_a`` otherwise (triangle).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

__all__ = ["Move", "synchronised_move"]

_DURATION_MARGIN = 1e-9  # relative slack so that limits hold despite rounding


@dataclasses.dataclass(frozen=True, eq=False)
class Move:
    """A synchronised move from ``q0`` to ``q1``.

    Attributes:
      q0, q1: (n,) start and end positions [rad or mm].
      duration: T [s].
      accel_fraction: f, fraction of T spent accelerating (and again decelerating).
    """

    q0: np.ndarray
    q1: np.ndarray
    duration: float
    accel_fraction: float

    def scaling(self, t: float) -> tuple[float, float]:
        """``(s, ds/dt)`` at time ``t`` [s], clamped to the move's span."""
        T, f = self.duration, self.accel_fraction
        if T <= 0:
            return 1.0, 0.0
        tau = min(max(t / T, 0.0), 1.0)
        k = 1.0 / (f * (1.0 - f))
        if tau < f:
            s, ds = 0.5 * k * tau * tau, k * tau
        elif tau <= 1.0 - f:
            s, ds = (tau - 0.5 * f) / (1.0 - f), 1.0 / (1.0 - f)
        else:
            r = 1.0 - tau
            s, ds = 1.0 - 0.5 * k * r * r, k * r
        return min(max(s, 0.0), 1.0), ds / T

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Positions (n,) and velocities (n,) at time ``t`` [s] after the start.

        Positions are kept inside the segment between ``q0`` and ``q1`` (this only removes
        floating-point rounding; the maths never leaves it).
        """
        s, ds = self.scaling(t)
        dq = self.q1 - self.q0
        q = np.clip(self.q0 + s * dq, np.minimum(self.q0, self.q1), np.maximum(self.q0, self.q1))
        return q, ds * dq


def synchronised_move(
    q0: np.ndarray,
    q1: np.ndarray,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    min_duration: float = 0.0,
) -> Move:
    """Shortest synchronised move from ``q0`` to ``q1`` not shorter than ``min_duration``.

    Args:
      q0, q1: (n,) start and goal [rad or mm].
      max_velocity: (n,) positive speed limits [per s].
      max_acceleration: (n,) positive acceleration limits [per s²].
      min_duration: duration the plan asks for [s]; the move is stretched, never squeezed.

    Raises:
      ValueError: non-finite input, mismatched shapes or non-positive limits.
    """
    q0 = np.asarray(q0, dtype=float)
    q1 = np.asarray(q1, dtype=float)
    v = np.asarray(max_velocity, dtype=float)
    a = np.asarray(max_acceleration, dtype=float)
    if not (q0.shape == q1.shape == v.shape == a.shape) or q0.ndim != 1:
        raise ValueError(f"shapes differ: q0 {q0.shape}, q1 {q1.shape}, v {v.shape}, a {a.shape}")
    if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(q1)) and math.isfinite(min_duration)):
        raise ValueError("move endpoints and duration must be finite")
    if not (np.all(v > 0) and np.all(a > 0)):
        raise ValueError("velocity and acceleration limits must be positive")
    d = np.abs(q1 - q0)
    r_v = float(np.max(d / v)) if d.size else 0.0
    r_a = float(np.max(d / a)) if d.size else 0.0
    if r_v == 0.0:
        return Move(q0, q1, max(min_duration, 0.0), 0.5)
    t_min = r_v + r_a / r_v if r_v * r_v >= r_a else 2.0 * math.sqrt(r_a)
    T = max(t_min * (1.0 + _DURATION_MARGIN), min_duration)
    f = min(0.5, 1.0 - r_v / T)
    return Move(q0, q1, T, f)
