"""The collision test of :mod:`uvms_jax.evo._world` as one Pallas (Triton) program on a GPU.

XLA runs :func:`uvms_jax.evo.world_collides` as a loop over configurations × spheres ×
obstacles per test, reading each configuration's frames and the obstacles moved into its base
frame from GPU memory for every pair. Here one thread tests one configuration: it places a
sphere from its body frame, tests it against every obstacle, and moves on, with every
intermediate in registers.

A program holds configurations of one demanded tool pose (one row of the world), so the row's
spheres, pairs and masks are the same in all its threads; the obstacles stay where the world
holds them (the vehicle's in the arm's base frame B, the scene's in W) and each sphere is
moved into W by its configuration's base pose instead, so they are the same in every thread
of every program. Both are read as scalars; only the frames differ from thread to thread. The
tests' arithmetic is the XLA path's (the helpers of :mod:`uvms_jax.evo._geometry`); a scene
obstacle is met in W instead of B, which changes distances by float32 round-off (≪
:data:`uvms_jax.evo.SLACK`).
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.evo._geometry import SLACK, SphereWorld, box_gap2, dot, plane, segment_distance

#: Configurations per program instance, and warps per instance: one configuration per thread.
BLOCK = 128
NUM_WARPS = 4


def applies(T_base_joint: Array) -> bool:
    """Whether the kernel serves frames ``T_base_joint``: a GPU backend and float32."""
    return jax.default_backend() == "gpu" and T_base_joint.dtype == jnp.float32


def _pow2(n: int) -> int:
    return 1 << max(n - 1, 0).bit_length()


class _Layout:
    """Offsets of a row's numbers in its table (one table per demanded tool pose), from the
    world's static sizes: spheres N, boxes B, polytopes Q, fixed spheres M, pair lists A and
    A', capsule pairs C."""

    def __init__(self, N: int, B: int, Q: int, M: int, A: int, A2: int, C: int):
        sizes = {"frame_row": N, "centre": 3 * N, "reach": N, "radius": N, "box_on": N * B, "face_on": N * Q,
                 "ball_on": N * M, "pair_a": A, "pair_b": A2, "pair_on": A * A2, "cap_row": 2 * C,
                 "cap_ends": 12 * C, "cap_reach": C, "cap_on": C}
        self.offset, at = {}, 0
        for name, size in sizes.items():
            self.offset[name] = at
            at += size
        self.size = at


def _row_tables(world: SphereWorld, group: Array, margin: Array, layout: _Layout) -> Array:
    """``(k, L)`` float32: each demanded tool pose's row as one table (:class:`_Layout`;
    indices and masks as exact small floats; a frame slot ``s`` as the first of its 12 rows in
    the frames, ``12 (s + 1)``)."""
    r = jax.tree_util.tree_map(lambda a: a[group], world.rows)
    k = group.shape[0]
    f = lambda x: jnp.reshape(x, (k, -1)).astype(jnp.float32)  # noqa: E731
    parts = {"frame_row": 12 * (r.body + 1), "centre": r.centre, "reach": r.radius + margin, "radius": r.radius,
             "box_on": r.box_on, "face_on": r.face_on, "ball_on": r.ball_on, "pair_a": r.pair_a, "pair_b": r.pair_b,
             "pair_on": r.pair_on, "cap_row": 12 * (r.cap_body + 1), "cap_ends": r.cap_ends,
             "cap_reach": r.cap_reach + margin, "cap_on": r.cap_on}
    table = jnp.concatenate([f(parts[name]) for name in layout.offset], axis=1)
    return jnp.pad(table, ((0, 0), (0, _pow2(layout.size) - layout.size)))


def _obstacle_table(world: SphereWorld) -> Array:
    """``(1, L)`` float32: box centres, axes and half extents, the polytopes' own faces, the
    fixed spheres, as the world holds them (each in its frame)."""
    faces = [world.faces[p, :n] for p, n in enumerate(world.n_faces)]
    parts = [world.box_c, world.box_R, world.box_half, *faces, world.balls]
    table = jnp.concatenate([jnp.ravel(x).astype(jnp.float32) for x in parts])
    return jnp.pad(table, (0, _pow2(table.shape[0]) - table.shape[0]))[None]


@functools.lru_cache(maxsize=32)
def _build(sizes: tuple[int, ...], n_faces: tuple[int, ...], n_base_boxes: int, n_base_faces: int,
           n_frame_rows: int, interpret: bool):
    """``(rows (k, L), obstacles (1, L'), frames (k, R, lanes)) → (k, lanes)`` int32, one
    program per tool pose and block of configurations.

    Over 80 lines as one function: the kernel's helpers (``place``, ``sphere_hits``,
    ``pair_hits``, ``capsule_hits``) close over one program's refs and the table's offsets;
    outside it each would take them all as arguments."""
    from jax.experimental import pallas as pl
    from jax.experimental.pallas import triton as plt

    N, B, Q, M, A, A2, C = sizes
    at = _Layout(*sizes).offset
    face_at = [3 * B + 9 * B + 3 * B + 4 * sum(n_faces[:p]) for p in range(Q)]
    ball_at = 15 * B + 4 * sum(n_faces)

    def kernel(row_ref, obs_ref, frame_ref, out_ref):
        t = lambda i: row_ref[0, i]  # noqa: E731  the row's numbers (the same in every thread)
        o = lambda i: obs_ref[0, i]  # noqa: E731
        index = lambda i: t(i).astype(jnp.int32)  # noqa: E731
        frame = lambda r: [frame_ref[0, r + e, :] for e in range(12)]  # noqa: E731  a 3 × 4 frame, row by row

        def apply(F, c):
            """Point ``c`` (3 components) moved by the frame ``F`` (12 numbers, row by row)."""
            return [F[4 * a + 3] + F[4 * a] * c[0] + F[4 * a + 1] * c[1] + F[4 * a + 2] * c[2] for a in range(3)]

        T_world_base = frame(0)

        def place(i):
            """Sphere ``i``'s centre in B."""
            return apply(frame(index(at["frame_row"] + i)), [t(at["centre"] + 3 * i + j) for j in range(3)])

        def sphere_hits(i, hit):
            x = place(i)
            x_world = apply(T_world_base, x)
            reach = t(at["reach"] + i)
            for b in range(B):
                c = [o(3 * b + j) for j in range(3)]
                R = [[o(3 * B + 9 * b + 3 * j + a) for a in range(3)] for j in range(3)]
                half = [o(12 * B + 3 * b + j) for j in range(3)]
                gap2 = box_gap2(x if b < n_base_boxes else x_world, c, R, half)
                hit |= (gap2 <= reach * reach) & (t(at["box_on"] + i * B + b) > 0.5)
            for p in range(Q):
                at_p = x if p < n_base_faces else x_world
                dist = functools.reduce(jnp.maximum, (plane(at_p, [o(face_at[p] + 4 * f + j) for j in range(4)])
                                                      for f in range(n_faces[p])))
                hit |= (dist <= reach) & (t(at["face_on"] + i * Q + p) > 0.5)
            for m in range(M):
                gap = [x_world[j] - o(ball_at + 4 * m + j) for j in range(3)]
                both = reach + o(ball_at + 4 * m + 3)
                hit |= (dot(gap, gap) <= both * both) & (t(at["ball_on"] + i * M + m) > 0.5)
            return hit

        hit = jax.lax.fori_loop(0, N, sphere_hits, jnp.zeros((BLOCK,), bool))
        # Sphere pairs: the second list's spheres placed once, the first's one by one.
        second = [index(at["pair_b"] + j) for j in range(A2)]
        x_second = [place(i) for i in second]
        r_second = [t(at["radius"] + i) for i in second]

        def pair_hits(a, hit):
            i = index(at["pair_a"] + a)
            x, reach = place(i), t(at["reach"] + i)
            for j in range(A2):
                d = [x[e] - x_second[j][e] for e in range(3)]
                both = reach + r_second[j]
                hit |= (dot(d, d) <= both * both) & (t(at["pair_on"] + a * A2 + j) > 0.5)
            return hit

        hit = jax.lax.fori_loop(0, A, pair_hits, hit)

        def capsule_hits(c, hit):
            ends = [[apply(frame(index(at["cap_row"] + 2 * c + g)),
                           [t(at["cap_ends"] + 12 * c + 6 * g + 3 * e + j) for j in range(3)]) for e in range(2)]
                    for g in range(2)]
            dist = segment_distance(ends[0][0], ends[0][1], ends[1][0], ends[1][1])
            return hit | ((dist <= t(at["cap_reach"] + c)) & (t(at["cap_on"] + c) > 0.5))

        hit = jax.lax.fori_loop(0, C, capsule_hits, hit)
        out_ref[0, :] = hit.astype(jnp.int32)

    def run(rows, obstacles, frames):
        k, lanes = frames.shape[0], frames.shape[2]
        return pl.pallas_call(
            kernel,
            out_shape=jax.ShapeDtypeStruct((k, lanes), jnp.int32),
            grid=(k, lanes // BLOCK),
            in_specs=[pl.BlockSpec((1, rows.shape[1]), lambda g, i: (g, 0)),
                      pl.BlockSpec((1, obstacles.shape[1]), lambda g, i: (0, 0)),
                      pl.BlockSpec((1, _pow2(n_frame_rows), BLOCK), lambda g, i: (g, 0, i))],
            out_specs=pl.BlockSpec((1, BLOCK), lambda g, i: (g, i)),
            compiler_params=plt.CompilerParams(num_warps=NUM_WARPS, num_stages=1),
            interpret=interpret,
        )(rows, obstacles, frames)

    return run


def world_collides_kernel(world: SphereWorld, group: Array, T_world_base: Array, T_base_joint: Array,
                          interpret: bool = False) -> Array:
    """:func:`uvms_jax.evo.world_collides` through the kernel (the same arguments and result);
    ``interpret`` runs the same program emulated (tests on a CPU)."""
    batch = T_world_base.shape[:-2]
    k, S, n = T_base_joint.shape[-5:-2]
    r = world.rows
    sizes = (r.radius.shape[-1], world.box_half.shape[0], len(world.n_faces), world.balls.shape[0],
             r.pair_a.shape[-1], r.pair_b.shape[-1], r.cap_on.shape[-1])
    layout = _Layout(*sizes)
    # Each configuration's frames as rows, the configurations along the lanes: its base pose in
    # W, then slot 0 (the base, the identity) and the n bodies, 12 numbers each.
    P = math.prod(batch)
    top = lambda T: T[..., :3, :].reshape(T.shape[:-2] + (12,))  # noqa: E731
    T_wb = jnp.broadcast_to(top(T_world_base.reshape(P, 1, 1, 1, 4, 4)), (P, k, S, 1, 12))
    eye = jnp.broadcast_to(top(jnp.eye(4, dtype=jnp.float32)), (P, k, S, 1, 12))
    frames = jnp.concatenate([T_wb, eye, top(T_base_joint.reshape(P, k, S, n, 4, 4))], axis=3)  # (P, k, S, n + 2, 12)
    frames = jnp.moveaxis(frames, (0, 2), (-2, -1)).reshape(k, 12 * (n + 2), P * S)
    lanes = -(-(P * S) // BLOCK) * BLOCK
    frames = jnp.pad(frames, ((0, 0), (0, 0), (0, lanes - P * S)))
    run = _build(sizes, world.n_faces, world.n_base_boxes, world.n_base_faces, 12 * (n + 2), interpret)
    hits = run(_row_tables(world, group, world.margin + SLACK, layout), _obstacle_table(world), frames)
    return jnp.moveaxis(hits[:, :P * S].reshape(k, P, S), 0, 1).reshape(batch + (k, S)) > 0
