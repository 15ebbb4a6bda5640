"""Paden–Kahan subproblems (Murray, Li & Sastry §3.2.2), on scalars.

Points and axes are 3 components each: Python floats, or arrays of one batch shape that
broadcast together (the form of :mod:`uvms_jax.kin._scalar`: every operation elementwise, so
XLA fuses a whole closed-form IK into one loop, and a GPU kernel can run it on registers).
Each returns angles and a ``valid`` flag instead of raising: a subproblem with no real
solution gives ``valid = False`` and finite filler angles.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array

from uvms_jax.kin._lie import cross3, dot3


def sub3(a, b) -> list:
    """``a − b`` of two 3-component vectors."""
    return [a[i] - b[i] for i in range(3)]


def _project(w, u) -> list:
    """Component of ``u`` orthogonal to unit axis ``w``."""
    d = dot3(w, u)
    return [u[i] - d * w[i] for i in range(3)]


def _tolerance(x, float64: float, float32: float) -> float:
    return float64 if jnp.result_type(x) == jnp.float64 else float32


def rotation_to(w, r, p, q) -> Array:
    """Subproblem 1: θ [rad] with ``exp(ξθ) p = q`` for a rotation about unit ``w`` through ``r``."""
    u, v = _project(w, sub3(p, r)), _project(w, sub3(q, r))
    return jnp.arctan2(dot3(w, cross3(u, v)), dot3(u, v))


def two_axes(w1, w2, r, p, q) -> tuple[list, list, Array]:
    """Subproblem 2: ``exp(ξ1θ1) exp(ξ2θ2) p = q`` for axes ``w1``, ``w2`` meeting at ``r``.

    Returns:
      ``theta1``, ``theta2`` (2 scalars each: the ± common-normal solutions) and ``valid``:
      False when ``|p − r| ≠ |q − r|`` or the circles do not meet.
    """
    u, v = sub3(p, r), sub3(q, r)
    c12 = dot3(w1, w2)
    denom = c12 * c12 - 1.0
    alpha = (c12 * dot3(w2, u) - dot3(w1, v)) / denom
    beta = (c12 * dot3(w1, v) - dot3(w2, u)) / denom
    n = cross3(w1, w2)
    uu, vv = dot3(u, u), dot3(v, v)
    gamma2 = (uu - alpha * alpha - beta * beta - 2.0 * alpha * beta * c12) / dot3(n, n)
    # Equal radii to a tolerance that scales with the lengths involved.
    scale = jnp.maximum(uu, 1e-12)
    tol = _tolerance(uu, 1e-6, 1e-4)
    valid = (gamma2 >= -tol * scale) & (jnp.abs(uu - vv) <= tol * scale)
    gamma = jnp.sqrt(jnp.maximum(gamma2, 0.0))
    theta1, theta2 = [], []
    for sign in (1.0, -1.0):
        c = [alpha * w1[i] + beta * w2[i] + sign * gamma * n[i] + r[i] for i in range(3)]
        theta2.append(rotation_to(w2, r, p, c))
        theta1.append(-rotation_to(w1, r, q, c))
    return theta1, theta2, valid


def distance(w, r, p, q, delta) -> tuple[list, Array]:
    """Subproblem 3: θ with ``|exp(ξθ) p − q| = δ``, rotation about ``w`` through ``r``.

    Returns ``theta`` (2 scalars: the ± solutions) and ``valid``.
    """
    up, vp = _project(w, sub3(p, r)), _project(w, sub3(q, r))
    theta0 = jnp.arctan2(dot3(w, cross3(up, vp)), dot3(up, vp))
    along = dot3(w, sub3(p, q))
    delta_p2 = delta * delta - along * along
    nu2, nv2 = dot3(up, up), dot3(vp, vp)
    cos_phi = (nu2 + nv2 - delta_p2) / jnp.maximum(2.0 * jnp.sqrt(nu2 * nv2), 1e-12)
    tol = _tolerance(cos_phi, 1e-9, 1e-5)
    valid = (jnp.abs(cos_phi) <= 1.0 + tol) & (delta_p2 >= 0)
    phi = jnp.arccos(jnp.clip(cos_phi, -1.0, 1.0))
    return [theta0 - phi, theta0 + phi], valid
