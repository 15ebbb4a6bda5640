"""The planner's collision world as data, and the arithmetic of its tests.

:class:`SphereWorld` (the arm's spheres per target, :class:`WorldRows`, and the scene's
obstacles) and the distance tests on points given as 3 components (arrays that broadcast
together, or a GPU kernel's per-lane vectors). The XLA path (:mod:`uvms_jax.evo._world`) and
the GPU kernel (:mod:`uvms_jax.evo._world_gpu`) both build on this module; frames and units
are in :mod:`uvms_jax.evo._world`'s docstring.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array

# float32 round-off of a sphere placed through six joints and of a distance computed in the
# base frame stays below 1e-5 m for arms under 2 m; a ten times wider slack makes the JAX test
# call a pair the planner's float64 kernel rejects by a hair a collision too (the safe side).
SLACK = 1e-4  # [m]


@struct.dataclass
class WorldRows:
    """What each docking target tests: its spheres and pairs (``r`` rows, one per target).

    Attributes:
      body: ``(r, N)`` frame slot of each sphere (0: the base, ``b + 1``: body ``b``).
      centre: ``(r, N, 3)`` sphere centres in their body's frame [m].
      radius: ``(r, N)`` radii [m].
      box_on, face_on, ball_on: ``(r, N, B)``, ``(r, N, P)``, ``(r, N, M)`` the sphere–box,
        sphere–polytope and sphere–fixed-sphere pairs tested (padding spheres: none).
      pair_a, pair_b: ``(r, A)``, ``(r, A')`` indices (into the row's spheres) of the first and
        the second spheres of pairs; pair_on ``(r, A, A')`` the pairs tested among them.
      cap_body: ``(r, C, 2)`` frame slots of capsule pairs; cap_ends ``(r, C, 2, 2, 3)`` their
        axes' end points in those frames [m]; cap_reach ``(r, C)`` the sum of their radii [m];
        cap_on ``(r, C)``.
    """

    body: Array
    centre: Array
    radius: Array
    box_on: Array
    face_on: Array
    ball_on: Array
    pair_a: Array
    pair_b: Array
    pair_on: Array
    cap_body: Array
    cap_ends: Array
    cap_reach: Array
    cap_on: Array


@struct.dataclass
class SphereWorld:
    """The arm's spheres and the scene's obstacles of a docking problem (module docstring).

    Attributes:
      rows: :class:`WorldRows`, one row per target (the problem's ``group`` indexes it).
      box_c, box_R, box_half: ``(B, 3)``, ``(B, 3, 3)`` (columns: the box's axes), ``(B, 3)``
        boxes: the first ``n_base_boxes`` in B, the rest in W [m].
      box_vehicle: ``(B,)`` True for the vehicle's own boxes (not the mount).
      faces: ``(P, F, 4)`` convex polytopes ``n·x + d ≤ 0`` inside, ``|n| = 1`` (padded by
        repeating a face), the first ``n_base_faces`` in B, the rest in W (half-spaces: one
        face).
      balls: ``(M, 4)`` fixed spheres in W: centre [m], radius [m].
      margin: the planner's safety distance [m]: a pair nearer than it is a collision.
      n_base_boxes, n_base_faces: obstacles fixed to the vehicle (static).
      n_faces: ``(P,)`` the faces of each polytope before its padding (static): the test reads
        only those (a mesh's hull of 200 faces beside a box's 6 would otherwise cost 200 each).
    """

    rows: WorldRows
    box_c: Array
    box_R: Array
    box_half: Array
    box_vehicle: Array
    faces: Array
    balls: Array
    margin: Array
    n_base_boxes: int = struct.field(pytree_node=False)
    n_base_faces: int = struct.field(pytree_node=False)
    n_faces: tuple[int, ...] = struct.field(pytree_node=False)

    def without_scene(self) -> "SphereWorld":
        """The world with the scene's obstacles switched off (the vehicle, its mount and the
        arm itself remain)."""
        r = self.rows
        return self.replace(rows=r.replace(box_on=r.box_on.at[..., self.n_base_boxes:].set(False),
                                           face_on=r.face_on.at[..., self.n_base_faces:].set(False),
                                           ball_on=jnp.zeros_like(r.ball_on)))

    def without_vehicle(self) -> "SphereWorld":
        """The world without the vehicle's boxes (the arm on its mount alone)."""
        return self.replace(rows=self.rows.replace(box_on=self.rows.box_on & ~self.box_vehicle))


def make_sphere_world(rows: dict, boxes: dict, faces: np.ndarray, balls: np.ndarray, margin: float,
                      n_base_boxes: int, n_base_faces: int, dtype=None, n_faces=None) -> SphereWorld:
    """A :class:`SphereWorld` from NumPy arrays (the fields' shapes; see its docstring).

    Args:
      rows: the :class:`WorldRows` fields by name.
      boxes: ``c``, ``R``, ``half``, ``vehicle``: the box fields.
      faces, balls: polytopes ``(P, F, 4)`` and fixed spheres ``(M, 4)``.
      margin: safety distance [m], ≥ 0.
      n_base_boxes, n_base_faces: how many boxes and polytopes lead the lists in the base frame.
      dtype: float dtype (default: JAX's default float).
      n_faces: ``(P,)`` faces of each polytope before its padding (default: all ``F``).

    Raises:
      ValueError: on inconsistent shapes or a negative margin.
    """
    dtype = dtype or jnp.zeros(()).dtype
    f = lambda x: jnp.asarray(np.asarray(x, dtype=np.float64), dtype=dtype)  # noqa: E731
    n_rows, n_sph = np.shape(rows["radius"])
    B, P, M = len(boxes["half"]), len(faces), len(balls)
    want = {"box_on": (n_rows, n_sph, B), "face_on": (n_rows, n_sph, P), "ball_on": (n_rows, n_sph, M),
            "centre": (n_rows, n_sph, 3), "body": (n_rows, n_sph)}
    for name, shape in want.items():
        if np.shape(rows[name]) != shape:
            raise ValueError(f"world rows: {name} must have shape {shape}, got {np.shape(rows[name])}")
    n_faces = tuple(int(n) for n in (np.full(P, np.shape(faces)[1]) if n_faces is None else n_faces))
    if len(n_faces) != P or any(not 1 <= n <= np.shape(faces)[1] for n in n_faces):
        raise ValueError(f"n_faces must give 1 to {np.shape(faces)[1]} faces for each of {P} polytopes, got {n_faces}")
    if margin < 0 or not 0 <= n_base_boxes <= B or not 0 <= n_base_faces <= P:
        raise ValueError(f"need margin >= 0 and base obstacle counts within the lists, got {margin}, "
                         f"{n_base_boxes} of {B} boxes, {n_base_faces} of {P} polytopes")
    ints = lambda x: jnp.asarray(x, dtype=jnp.int32)  # noqa: E731
    bools = lambda x: jnp.asarray(x, dtype=bool)  # noqa: E731
    return SphereWorld(
        rows=WorldRows(body=ints(rows["body"]), centre=f(rows["centre"]), radius=f(rows["radius"]),
                       box_on=bools(rows["box_on"]), face_on=bools(rows["face_on"]), ball_on=bools(rows["ball_on"]),
                       pair_a=ints(rows["pair_a"]), pair_b=ints(rows["pair_b"]), pair_on=bools(rows["pair_on"]), cap_body=ints(rows["cap_body"]),
                       cap_ends=f(rows["cap_ends"]), cap_reach=f(rows["cap_reach"]), cap_on=bools(rows["cap_on"])),
        box_c=f(np.reshape(boxes["c"], (B, 3))), box_R=f(np.reshape(boxes["R"], (B, 3, 3))),
        box_half=f(np.reshape(boxes["half"], (B, 3))), box_vehicle=bools(np.reshape(boxes["vehicle"], (B,))),
        faces=f(faces), balls=f(np.reshape(balls, (M, 4))), margin=f(margin),
        n_base_boxes=int(n_base_boxes), n_base_faces=int(n_base_faces), n_faces=n_faces)


# The tests' arithmetic, on points given as 3 components (arrays that broadcast together, or
# a kernel's per-lane vectors): the XLA path and the GPU kernel share it.

def dot(u, v) -> Array:
    """``u · v`` of vectors given as 3 components."""
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def box_gap2(x, c, R, half) -> Array:
    """Squared distance of point ``x`` from a box (0 inside): centre ``c``, axes ``R[j][i]``
    (component ``j`` of axis ``i``), half extents ``half``, all as components [m²]."""
    local = [sum((x[j] - c[j]) * R[j][i] for j in range(3)) for i in range(3)]  # Rᵀ (x − c)
    out = [jnp.maximum(jnp.abs(local[i]) - half[i], 0.0) for i in range(3)]
    return dot(out, out)


def plane(x, face) -> Array:
    """Signed distance ``n·x + d`` of point ``x`` from the face ``(n, d)`` (4 components) [m]."""
    return x[0] * face[0] + x[1] * face[1] + x[2] * face[2] + face[3]


def segment_distance(p1, q1, p2, q2) -> Array:
    """Distance between segments ``p1 q1`` and ``p2 q2`` (points as 3 components) [m]: the
    closest points by clamping the line parameters (Ericson, Real-Time Collision Detection,
    5.1.9), the divisions guarded for points and parallel segments."""
    d1, d2, r = ([u[i] - v[i] for i in range(3)] for u, v in ((q1, p1), (q2, p2), (p1, p2)))
    a, e, f = dot(d1, d1), dot(d2, d2), dot(d2, r)
    c, b = dot(d1, r), dot(d1, d2)
    tiny = 1e-12
    safe = lambda x: jnp.where(x > tiny, x, 1.0)  # noqa: E731
    on_2 = lambda: jnp.clip(-c / safe(a), 0.0, 1.0)  # noqa: E731  the point of segment 1 nearest p2
    denom = a * e - b * b
    s = jnp.where(denom > tiny * jnp.maximum(a * e, 1.0), jnp.clip((b * f - c * e) / safe(denom), 0.0, 1.0), 0.0)
    s = jnp.where(a > tiny, jnp.where(e > tiny, s, on_2()), 0.0)
    t = jnp.where(e > tiny, (b * s + f) / safe(e), 0.0)
    s = jnp.where(t < 0.0, on_2(), jnp.where(t > 1.0, jnp.clip((b - c) / safe(a), 0.0, 1.0), s))
    s = jnp.where(a > tiny, s, 0.0)
    t = jnp.clip(t, 0.0, 1.0)
    w = [(p1[i] + d1[i] * s) - (p2[i] + d2[i] * t) for i in range(3)]
    return jnp.sqrt(dot(w, w))
