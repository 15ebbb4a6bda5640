"""Primitive collision tests for docking: link capsules vs boxes, and box vs box.

An arm is modelled as capsules of one radius between consecutive joint origins (the tool
point closes the last one); the vehicle and the scene (task panel, tables, floor) as boxes.
Everything is vectorised JAX and works on any leading batch shape.

Box convention (written once): a box is ``(T_world_box (..., 4, 4), half (..., 3))``, its
centre and axes given by the pose and its half extents along those axes [m].
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import Array

# Golden-section steps of the segment–box distance: the bracket shrinks by 0.618 per step,
# to 0.618^40 ≈ 4e-9 of the segment length (below float32 resolution for links < 1 m).
GOLDEN_STEPS = 40
_INV_PHI = 0.6180339887498949
# Full float32 products on GPUs too: TF32 (their default) moves a rotated point by ~1e-3 of its
# distance, enough to flip a contact decision near a surface.
_EXACT = jax.lax.Precision.HIGHEST


def point_box_distance(p: Array, half: Array) -> Array:
    """Distance from points ``p (..., 3)`` to the axis-aligned box ``[-half, half]`` (0 inside)."""
    return jnp.linalg.norm(p - jnp.clip(p, -half, half), axis=-1)


def segment_box_distance(a: Array, b: Array, T_world_box: Array, half: Array) -> Array:
    """Distance ``(...)`` between segments ``a → b (..., 3)`` and boxes (0 when they meet) [m].

    The distance of a point to a convex box is a convex function of the point, so along the
    segment it is convex in the segment parameter: a fixed number of golden-section steps
    finds its minimum (no branch per Voronoi region of the box).
    """
    R, c = T_world_box[..., :3, :3], T_world_box[..., :3, 3]
    to_box = lambda p: jnp.einsum("...ji,...j->...i", R, p - c, precision=_EXACT)  # Rᵀ (p − c)
    a_b, b_b = to_box(a), to_box(b)
    d = lambda t: point_box_distance(a_b + t[..., None] * (b_b - a_b), half)
    shape = jnp.broadcast_shapes(a_b.shape, b_b.shape, half.shape)[:-1]
    def shrink(_, bracket):
        lo, hi = bracket
        m1, m2 = hi - _INV_PHI * (hi - lo), lo + _INV_PHI * (hi - lo)
        left = d(m1) <= d(m2)
        return jnp.where(left, lo, m1), jnp.where(left, m2, hi)

    lo, hi = jax.lax.fori_loop(0, GOLDEN_STEPS, shrink, (jnp.zeros(shape, a_b.dtype), jnp.ones(shape, a_b.dtype)))
    t = 0.5 * (lo + hi)
    return jnp.minimum(jnp.minimum(d(t), d(jnp.zeros_like(t))), d(jnp.ones_like(t)))


def boxes_overlap(T_a: Array, half_a: Array, T_b: Array, half_b: Array, tol: float = 1e-6) -> Array:
    """``(...)`` True where box a and box b overlap (separating-axis test over 15 axes).

    Touching boxes (gap below ``tol`` [m]) count as overlapping; near-parallel edge pairs,
    whose cross-product axis vanishes, never count as separating.
    """
    batch = jnp.broadcast_shapes(T_a.shape[:-2], half_a.shape[:-1], T_b.shape[:-2], half_b.shape[:-1])
    T_a, T_b = jnp.broadcast_to(T_a, batch + (4, 4)), jnp.broadcast_to(T_b, batch + (4, 4))
    half_a, half_b = jnp.broadcast_to(half_a, batch + (3,)), jnp.broadcast_to(half_b, batch + (3,))
    A, B = T_a[..., :3, :3], T_b[..., :3, :3]  # columns = box axes in the world
    t = T_b[..., :3, 3] - T_a[..., :3, 3]
    cross = jnp.cross(A[..., :, :, None], B[..., :, None, :], axis=-3)  # (..., 3, 3, 3): axis a_i × b_j
    axes = jnp.concatenate([A, B, cross.reshape(cross.shape[:-2] + (9,))], axis=-1)  # (..., 3, 15)
    proj_a = jnp.sum(half_a[..., :, None] * jnp.abs(jnp.einsum("...ki,...kl->...il", A, axes, precision=_EXACT)), axis=-2)
    proj_b = jnp.sum(half_b[..., :, None] * jnp.abs(jnp.einsum("...ki,...kl->...il", B, axes, precision=_EXACT)), axis=-2)
    gap = jnp.abs(jnp.einsum("...k,...kl->...l", t, axes, precision=_EXACT)) - proj_a - proj_b
    norm = jnp.linalg.norm(axes, axis=-2)
    return ~jnp.any(gap > tol * jnp.maximum(norm, 1e-12), axis=-1)


def link_points(T_world_base: Array, T_base_joint: Array, T_base_tool: Array) -> Array:
    """Capsule end points ``(..., n + 2, 3)`` in the world: base origin, joint origins, tool point."""
    tool = T_base_tool[..., None, :3, 3]
    p_base = jnp.concatenate([jnp.zeros_like(tool), T_base_joint[..., :3, 3], tool], axis=-2)  # (..., n + 2, 3)
    R, p = T_world_base[..., None, :3, :3], T_world_base[..., None, :3, 3]
    return jnp.einsum("...ij,...j->...i", R, p_base, precision=_EXACT) + p


def capsules_hit_boxes(points: Array, radius: float, T_world_box: Array, half: Array, skip: Array) -> Array:
    """``(...)`` True where any capsule of a chain of ``points (..., s + 1, 3)`` comes closer
    than ``radius`` to any of the boxes ``(m, 4, 4), (m, 3)``; ``skip (s, m)`` marks
    capsule–box pairs not tested (e.g. the first link, fixed on the vehicle, vs the vehicle)."""
    a, b = points[..., :-1, None, :], points[..., 1:, None, :]  # (..., s, 1, 3)
    dist = segment_box_distance(a, b, T_world_box, half)  # (..., s, m)
    return jnp.any((dist < radius) & ~skip, axis=(-1, -2))
