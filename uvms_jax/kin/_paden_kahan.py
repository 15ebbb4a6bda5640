"""Paden–Kahan subproblems (Murray, Li & Sastry §3.2.2), broadcasting over leading axes.

Each returns angles and a ``valid`` flag instead of raising: a subproblem with no real
solution gives ``valid = False`` and finite filler angles.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array


def _dot(a: Array, b: Array) -> Array:
    return jnp.sum(a * b, axis=-1)


def _project(w: Array, u: Array) -> Array:
    """Component of ``u`` orthogonal to unit axis ``w``."""
    return u - _dot(w, u)[..., None] * w


def rotation_to(w: Array, r: Array, p: Array, q: Array) -> Array:
    """Subproblem 1: θ with ``exp(ξθ) p = q`` for a rotation about unit ``w`` through ``r``.

    Shapes ``(..., 3)`` → ``(...)`` [rad].
    """
    u, v = _project(w, p - r), _project(w, q - r)
    return jnp.arctan2(_dot(w, jnp.cross(u, v)), _dot(u, v))


def two_axes(w1: Array, w2: Array, r: Array, p: Array, q: Array) -> tuple[Array, Array, Array]:
    """Subproblem 2: ``exp(ξ1θ1) exp(ξ2θ2) p = q`` for axes ``w1``, ``w2`` meeting at ``r``.

    Returns:
      ``theta1 (..., 2)``, ``theta2 (..., 2)``, ``valid (...)`` — both solutions (± the
      common-normal direction); ``valid`` is False when ``|p − r| ≠ |q − r|`` or the circles
      do not meet.
    """
    u, v = p - r, q - r
    c12 = _dot(w1, w2)
    denom = c12**2 - 1.0
    alpha = (c12 * _dot(w2, u) - _dot(w1, v)) / denom
    beta = (c12 * _dot(w1, v) - _dot(w2, u)) / denom
    n = jnp.cross(w1, w2)
    gamma2 = (_dot(u, u) - alpha**2 - beta**2 - 2.0 * alpha * beta * c12) / _dot(n, n)
    # Equal radii to a tolerance that scales with the lengths involved.
    scale = jnp.maximum(_dot(u, u), 1e-12)
    tol = 1e-6 if u.dtype == jnp.float64 else 1e-4
    valid = (gamma2 >= -tol * scale) & (jnp.abs(_dot(u, u) - _dot(v, v)) <= tol * scale)
    gamma = jnp.sqrt(jnp.clip(gamma2, 0.0, None))
    sign = jnp.array([1.0, -1.0], dtype=u.dtype)
    z = (alpha[..., None] * w1 + beta[..., None] * w2)[..., None, :] + sign[:, None] * gamma[..., None, None] * n[..., None, :]
    c = z + r[..., None, :]
    expand = lambda a: a[..., None, :]
    theta2 = rotation_to(expand(w2), expand(r), expand(p), c)
    theta1 = -rotation_to(expand(w1), expand(r), expand(q), c)
    return theta1, theta2, valid


def distance(w: Array, r: Array, p: Array, q: Array, delta: Array) -> tuple[Array, Array]:
    """Subproblem 3: θ with ``|exp(ξθ) p − q| = δ``, rotation about ``w`` through ``r``.

    Returns ``theta (..., 2)`` (the ± solutions) and ``valid (...)``.
    """
    u, v = p - r, q - r
    up, vp = _project(w, u), _project(w, v)
    theta0 = jnp.arctan2(_dot(w, jnp.cross(up, vp)), _dot(up, vp))
    delta_p2 = delta**2 - _dot(w, p - q) ** 2
    nu, nv = jnp.linalg.norm(up, axis=-1), jnp.linalg.norm(vp, axis=-1)
    cos_phi = (nu**2 + nv**2 - delta_p2) / jnp.maximum(2.0 * nu * nv, 1e-12)
    tol = 1e-9 if u.dtype == jnp.float64 else 1e-5
    valid = (jnp.abs(cos_phi) <= 1.0 + tol) & (delta_p2 >= 0)
    phi = jnp.arccos(jnp.clip(cos_phi, -1.0, 1.0))
    return jnp.stack([theta0 - phi, theta0 + phi], axis=-1), valid
