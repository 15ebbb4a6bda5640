"""A fast collision checker for whole motions: the arm as spheres, the scene as convex
polytopes, compiled with Numba; MuJoCo confirms what it rejects.

The planner spends its time checking motions: a straight joint-space segment sampled every
``resolution`` [rad] on every joint. MuJoCo checks one configuration per call (kinematics, then
broad and narrow phase of capsule–mesh pairs: 5–30 µs in this scene, plus Python per state);
here a whole segment is one compiled call that checks its samples coarse to fine and stops at
the first collision, as in VAMP (Thomason et al., "Motions in Microseconds via Vectorized
Sampling-Based Planning", ICRA 2024), whose robots are sphere sets against primitive scenes.

Everything is read from the scene's MuJoCo model, so both checkers see the same world:

* arm: each capsule of a moving body becomes spheres along its axis, ``s`` apart with radius
  ``sqrt(r² + (s/2)²)`` (together they contain the capsule); each mesh of a moving body (jaw
  fingers, the held object) becomes the circumscribed spheres of a grid of cells over its
  bounding box, kept where they reach the mesh's convex hull;
* scene: planes are half-spaces and meshes their convex hulls (face equations); capsules and
  spheres of fixed bodies (the base link) become spheres as above;
* pairs: exactly the geom pairs MuJoCo tests in the current :class:`Context` (the reference
  checker's ``contype``/``conaffinity`` bits, welded bodies, the parent–child filter,
  ``<exclude>``), less those beyond the arm's reach; each is first tested with the bounding
  spheres of both geoms. Two capsules of the arm are tested exactly (segment distance), a
  sphere against a box exactly, against any other polytope by its largest face distance.

Conservative: the spheres contain the arm's geoms and the distance of a point to a convex
polytope is at least its largest signed face distance, so a configuration this checker
accepts with margin ``m`` has every MuJoCo pair farther apart than ``m``. It may reject a
configuration MuJoCo accepts (sphere bumps, polytope corners): MuJoCo, the reference, checks
every sample it rejects — a collision ends the motion's check, a false alarm resumes it. The
samples of a motion are those of :func:`~uvms_jax.plan.densify` at the same resolution, so a
path made of accepted motions passes the MuJoCo re-check there.

The same spheres bound the clearance from below (:meth:`SphereChecker.clearance_lower_bounds`),
so that the smallest clearance along a path needs MuJoCo at a few samples only
(:meth:`SphereChecker.min_clearance`, the same value as MuJoCo at every sample).
"""

from __future__ import annotations

import functools

import mujoco
import numba
import numpy as np
from scipy.spatial import ConvexHull

from uvms_jax import frames
from uvms_jax.plan._collision import CollisionChecker
from uvms_jax.plan._scene import Context

__all__ = ["SphereChecker", "coarse_to_fine"]

_FACE_ATOL = 1e-9  # coplanar triangles of a hull give one face equation up to round-off


def _capsule_spheres(pos, R, radius: float, half_length: float, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Spheres containing a capsule (centre ``pos``, axis ``R[:, 2]``): centres ``(n, 3)``, radii ``(n,)``."""
    n = max(2, int(np.ceil(2 * half_length / spacing)) + 1)
    step = 2 * half_length / (n - 1)
    centres = pos + np.linspace(-half_length, half_length, n)[:, None] * R[:, 2]
    return centres, np.full(n, np.hypot(radius, step / 2))


def _hull_faces(vertices: np.ndarray) -> np.ndarray:
    """Face equations ``(f, 4)`` of the convex hull of ``vertices (v, 3)``: ``n·x + d ≤ 0``
    inside, ``|n| = 1``."""
    keep: list[np.ndarray] = []
    for e in ConvexHull(vertices).equations:
        if not any(np.all(np.abs(e - k) < _FACE_ATOL * 1e3) for k in keep):
            keep.append(e)
    return np.array(keep)


def _box_of(faces: np.ndarray) -> np.ndarray | None:
    """``(4, 3)`` box (rows: centre, then the three half-extent vectors) of a hull with three
    pairs of opposite, mutually orthogonal faces; None for any other polytope."""
    if len(faces) != 6:
        return None
    axes, used = [], set()
    for i in range(6):
        if i in used:
            continue
        j = next((j for j in range(6) if j not in used and j != i and np.allclose(faces[j, :3], -faces[i, :3], atol=1e-9)), None)
        if j is None:
            return None
        used |= {i, j}
        u = faces[i, :3]
        axes.append((u, (faces[j, 3] - faces[i, 3]) / 2, (-faces[i, 3] - faces[j, 3]) / 2))
    U = np.array([a[0] for a in axes])
    if not np.allclose(U @ U.T, np.eye(3), atol=1e-9):
        return None
    centre = np.linalg.solve(U, np.array([a[1] for a in axes]))
    return np.vstack([centre, U * np.array([a[2] for a in axes])[:, None]])


def _mesh_spheres(vertices: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Spheres covering the convex hull of ``vertices (v, 3)``: the circumscribed spheres of
    the cells (edges ≤ ``cell``) of its bounding box that reach the hull."""
    lo, hi = vertices.min(0), vertices.max(0)
    n = np.maximum(1, np.ceil((hi - lo) / cell - 1e-9).astype(int))
    h = (hi - lo) / n
    axes = [lo[i] + (np.arange(n[i]) + 0.5) * h[i] for i in range(3)]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    r = float(np.linalg.norm(h) / 2)
    faces = _hull_faces(vertices)
    reach = np.max(centres @ faces[:, :3].T + faces[:, 3], axis=1) <= r
    return centres[reach], np.full(int(reach.sum()), r)


@functools.lru_cache(maxsize=4096)
def coarse_to_fine(n: int) -> np.ndarray:
    """The sample indices ``1 … n`` of a motion, coarse to fine (the end first, then halves,
    quarters, …), so that a collision is usually met after a few samples: ``(n,)`` int."""
    i = np.arange(1, n + 1)
    out = i[np.argsort(-(i & -i) - (i == n) * (n + 1), kind="stable")]
    out.flags.writeable = False  # shared by every motion of n samples
    return out


@numba.njit(cache=True)
def _box_distance(x, box) -> float:
    """Signed distance of point ``x (3,)`` to a box ``(5, 3)``: flag row, centre, then the three
    half-extent vectors (axis times half edge) [m]."""
    out, inside = 0.0, -np.inf
    for a in range(3):
        h2 = box[2 + a, 0] ** 2 + box[2 + a, 1] ** 2 + box[2 + a, 2] ** 2
        h = np.sqrt(h2)
        u = ((x[0] - box[1, 0]) * box[2 + a, 0] + (x[1] - box[1, 1]) * box[2 + a, 1] + (x[2] - box[1, 2]) * box[2 + a, 2]) / h
        e = abs(u) - h
        inside = max(inside, e)
        if e > 0:
            out += e * e
    return np.sqrt(out) if out > 0 else inside


@numba.njit(cache=True)
def _dot(u, v) -> float:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@numba.njit(cache=True)
def _segment_distance(p1, q1, p2, q2) -> float:
    """Distance between segments ``p1 q1`` and ``p2 q2`` (each end ``(3,)``) [m]: the closest
    points by clamping the line parameters (Ericson, Real-Time Collision Detection, 5.1.9)."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f = _dot(d1, d1), _dot(d2, d2), _dot(d2, r)
    eps = 1e-15
    if a <= eps and e <= eps:
        return np.sqrt(_dot(r, r))
    if a <= eps:
        s, t = 0.0, min(max(f / e, 0.0), 1.0)
    else:
        c = _dot(d1, r)
        if e <= eps:
            s, t = min(max(-c / a, 0.0), 1.0), 0.0
        else:
            b = _dot(d1, d2)
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > eps else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                s, t = min(max(-c / a, 0.0), 1.0), 0.0
            elif t > 1.0:
                s, t = min(max((b - c) / a, 0.0), 1.0), 1.0
    w = (p1 + d1 * s) - (p2 + d2 * t)
    return np.sqrt(_dot(w, w))


@numba.njit(cache=True)
def _place(g, placed, X, p, R, g_body, g_start, g_end, sph_local) -> None:
    """World centres of geom ``g``'s spheres into ``X``, once per configuration."""
    if placed[g]:
        return
    b = g_body[g] + 1
    for k in range(g_start[g], g_end[g]):
        for r in range(3):
            X[k, r] = p[b, r] + R[b, r, 0] * sph_local[k, 0] + R[b, r, 1] * sph_local[k, 1] + R[b, r, 2] * sph_local[k, 2]
    placed[g] = True


@numba.njit(cache=True, nogil=True)
def _forward(q, R, p, Rj, M, parent, R_fixed, p_fixed, axis, qadr) -> None:
    """Forward kinematics into ``R (B + 1, 3, 3)``, ``p (B + 1, 3)`` (slot 0: the root, set by
    the caller; body b in slot b + 1): R_b = R_parent R_fixed Rot(axis, q), p_b = p_parent +
    R_parent p_fixed. ``Rj``, ``M``: ``(3, 3)`` scratch."""
    n_body = parent.shape[0]
    for b in range(n_body):
        a0, a1, a2 = axis[b, 0], axis[b, 1], axis[b, 2]
        s, c = np.sin(q[qadr[b]]), np.cos(q[qadr[b]])
        v = 1.0 - c
        Rj[0, 0] = c + a0 * a0 * v
        Rj[0, 1] = a0 * a1 * v - a2 * s
        Rj[0, 2] = a0 * a2 * v + a1 * s
        Rj[1, 0] = a1 * a0 * v + a2 * s
        Rj[1, 1] = c + a1 * a1 * v
        Rj[1, 2] = a1 * a2 * v - a0 * s
        Rj[2, 0] = a2 * a0 * v - a1 * s
        Rj[2, 1] = a2 * a1 * v + a0 * s
        Rj[2, 2] = c + a2 * a2 * v
        j = parent[b] + 1
        for r in range(3):
            p[b + 1, r] = p[j, r] + R[j, r, 0] * p_fixed[b, 0] + R[j, r, 1] * p_fixed[b, 1] + R[j, r, 2] * p_fixed[b, 2]
            for cc in range(3):
                M[r, cc] = R[j, r, 0] * R_fixed[b, 0, cc] + R[j, r, 1] * R_fixed[b, 1, cc] + R[j, r, 2] * R_fixed[b, 2, cc]
        for r in range(3):
            for cc in range(3):
                R[b + 1, r, cc] = M[r, 0] * Rj[0, cc] + M[r, 1] * Rj[1, cc] + M[r, 2] * Rj[2, cc]


@numba.njit(cache=True)
def _poly_distance(x, o, faces, poly_start, poly_end, boxes) -> float:
    """Lower bound of the signed distance of point ``x (3,)`` to polytope ``o`` [m]: exact for a
    box, else the largest signed face distance (both 1-Lipschitz in ``x``)."""
    if boxes[o, 0, 0] > 0.0:
        return _box_distance(x, boxes[o])
    lb = -np.inf
    for f in range(poly_start[o], poly_end[o]):
        lb = max(lb, faces[f, 0] * x[0] + faces[f, 1] * x[1] + faces[f, 2] * x[2] + faces[f, 3])
    return lb


@numba.njit(cache=True, nogil=True)
def _clearance_bounds(Q, cap, R_root, p_root, parent, R_fixed, p_fixed, axis, qadr, sph_local, sph_r, g_start,
                      g_end, g_body, g_centre, g_radius, faces, poly_start, poly_end, boxes, cp_geom, cp_poly,
                      cs_geom, cs_c, cs_r):
    """``(k,)`` lower bounds of the clearance at the rows of ``Q (k, n)``, capped at ``cap``
    [m] (see :meth:`SphereChecker.clearance_lower_bounds`)."""
    n_body = parent.shape[0]
    R = np.empty((n_body + 1, 3, 3))
    p = np.empty((n_body + 1, 3))
    R[0] = R_root
    p[0] = p_root
    Rj = np.empty((3, 3))
    M = np.empty((3, 3))
    C = np.empty((g_start.shape[0], 3))
    x = np.empty(3)
    n_poly = cp_geom.shape[0]
    n_pair = n_poly + cs_geom.shape[0]
    geom = np.concatenate((cp_geom, cs_geom))
    coarse = np.empty(n_pair)
    out = np.empty(Q.shape[0])
    for i in range(Q.shape[0]):
        _forward(Q[i], R, p, Rj, M, parent, R_fixed, p_fixed, axis, qadr)
        for g in range(g_start.shape[0]):
            b = g_body[g] + 1
            for r in range(3):
                C[g, r] = p[b, r] + R[b, r, 0] * g_centre[g, 0] + R[b, r, 1] * g_centre[g, 1] + R[b, r, 2] * g_centre[g, 2]
        # Each pair's bound through the geom's bounding sphere (its spheres lie inside it);
        # the pairs are then refined nearest first, so that the rest are mostly skipped.
        for j in range(n_pair):
            g = geom[j]
            if j < n_poly:
                coarse[j] = _poly_distance(C[g], cp_poly[j], faces, poly_start, poly_end, boxes) - g_radius[g]
            else:
                s0 = j - n_poly
                coarse[j] = np.sqrt((C[g, 0] - cs_c[s0, 0]) ** 2 + (C[g, 1] - cs_c[s0, 1]) ** 2
                                    + (C[g, 2] - cs_c[s0, 2]) ** 2) - g_radius[g] - cs_r[s0]
        best = cap
        for j in np.argsort(coarse):
            if coarse[j] >= best:
                break
            g = geom[j]
            b = g_body[g] + 1
            for k in range(g_start[g], g_end[g]):
                for r in range(3):
                    x[r] = p[b, r] + R[b, r, 0] * sph_local[k, 0] + R[b, r, 1] * sph_local[k, 1] + R[b, r, 2] * sph_local[k, 2]
                if j < n_poly:
                    d = _poly_distance(x, cp_poly[j], faces, poly_start, poly_end, boxes) - sph_r[k]
                else:
                    s0 = j - n_poly
                    d = np.sqrt((x[0] - cs_c[s0, 0]) ** 2 + (x[1] - cs_c[s0, 1]) ** 2 + (x[2] - cs_c[s0, 2]) ** 2) \
                        - sph_r[k] - cs_r[s0]
                best = min(best, d)
        out[i] = best
    return out


@numba.njit(cache=True, nogil=True)
def _first_collision(q0, q1, steps, order, start, active, R_root, p_root, parent, R_fixed, p_fixed, axis, qadr,
                     sph_body, sph_local, sph_r, g_start, g_end, g_body, g_centre, g_radius, g_seg, g_cap,
                     faces, poly_start, poly_end, poly_c, poly_r, boxes, pp_geom, pp_poly, ss_a, ss_b, st_geom, st_c, st_r,
                     margin):
    """Index into ``order`` (from ``start`` on) of the first sample ``q0 + (i/steps)(q1 − q0)``,
    ``i = order[t]``, that the spheres reject, or −1 (see :class:`SphereChecker`)."""
    n_body = parent.shape[0]
    # Slot 0 holds the root (the body the arm hangs from), body b sits in slot b + 1.
    R = np.empty((n_body + 1, 3, 3))
    p = np.empty((n_body + 1, 3))
    R[0] = R_root
    p[0] = p_root
    X = np.empty((sph_r.shape[0], 3))
    C = np.empty((g_start.shape[0], 3))
    Rj = np.empty((3, 3))
    M = np.empty((3, 3))
    S = np.empty((g_start.shape[0], 2, 3))
    placed = np.zeros(g_start.shape[0], dtype=np.bool_)
    q = np.empty(q0.shape[0])
    for t in range(start, order.shape[0]):
        u = order[t] / steps
        for i in range(q0.shape[0]):
            q[i] = q0[i] + u * (q1[i] - q0[i])
        _forward(q, R, p, Rj, M, parent, R_fixed, p_fixed, axis, qadr)
        for g in range(g_start.shape[0]):
            if not active[g]:
                continue  # e.g. the in-hand copies of the objects not held
            b = g_body[g] + 1
            for r in range(3):
                C[g, r] = p[b, r] + R[b, r, 0] * g_centre[g, 0] + R[b, r, 1] * g_centre[g, 1] + R[b, r, 2] * g_centre[g, 2]
            if g_cap[g] > 0.0:
                for e in range(2):
                    for r in range(3):
                        S[g, e, r] = (p[b, r] + R[b, r, 0] * g_seg[g, e, 0] + R[b, r, 1] * g_seg[g, e, 1]
                                      + R[b, r, 2] * g_seg[g, e, 2])
            placed[g] = False  # its spheres are placed when a pair needs them
        # Arm geom vs polytope (half-spaces included): bounding sphere first, then its spheres.
        for i in range(pp_geom.shape[0]):
            g, o = pp_geom[i], pp_poly[i]
            dx, dy, dz = C[g, 0] - poly_c[o, 0], C[g, 1] - poly_c[o, 1], C[g, 2] - poly_c[o, 2]
            reach = g_radius[g] + poly_r[o] + margin
            if dx * dx + dy * dy + dz * dz > reach * reach:
                continue  # bounding spheres apart
            if boxes[o, 0, 0] > 0.0:  # a box: exact distance (boxes[o, 1:] = centre, axes)
                if _box_distance(C[g], boxes[o]) > g_radius[g] + margin:
                    continue
                _place(g, placed, X, p, R, g_body, g_start, g_end, sph_local)
                for k in range(g_start[g], g_end[g]):
                    if _box_distance(X[k], boxes[o]) <= sph_r[k] + margin:
                        return t
                continue
            lb = -np.inf
            for f in range(poly_start[o], poly_end[o]):
                lb = max(lb, faces[f, 0] * C[g, 0] + faces[f, 1] * C[g, 1] + faces[f, 2] * C[g, 2] + faces[f, 3])
            if lb > g_radius[g] + margin:
                continue
            _place(g, placed, X, p, R, g_body, g_start, g_end, sph_local)
            for k in range(g_start[g], g_end[g]):
                lb = -np.inf
                for f in range(poly_start[o], poly_end[o]):
                    lb = max(lb, faces[f, 0] * X[k, 0] + faces[f, 1] * X[k, 1] + faces[f, 2] * X[k, 2] + faces[f, 3])
                if lb <= sph_r[k] + margin:
                    return t
        # Arm geom vs arm geom.
        for i in range(ss_a.shape[0]):
            ga, gb = ss_a[i], ss_b[i]
            dx, dy, dz = C[ga, 0] - C[gb, 0], C[ga, 1] - C[gb, 1], C[ga, 2] - C[gb, 2]
            if np.sqrt(dx * dx + dy * dy + dz * dz) > g_radius[ga] + g_radius[gb] + margin:
                continue
            if g_cap[ga] > 0.0 and g_cap[gb] > 0.0:  # two capsules: exact
                if _segment_distance(S[ga, 0], S[ga, 1], S[gb, 0], S[gb, 1]) <= g_cap[ga] + g_cap[gb] + margin:
                    return t
                continue
            _place(ga, placed, X, p, R, g_body, g_start, g_end, sph_local)
            _place(gb, placed, X, p, R, g_body, g_start, g_end, sph_local)
            for ka in range(g_start[ga], g_end[ga]):
                for kb in range(g_start[gb], g_end[gb]):
                    dx, dy, dz = X[ka, 0] - X[kb, 0], X[ka, 1] - X[kb, 1], X[ka, 2] - X[kb, 2]
                    if np.sqrt(dx * dx + dy * dy + dz * dz) <= sph_r[ka] + sph_r[kb] + margin:
                        return t
        # Arm geom vs spheres of fixed geoms (the base link).
        for i in range(st_geom.shape[0]):
            g, s0 = st_geom[i], i
            dx, dy, dz = C[g, 0] - st_c[s0, 0], C[g, 1] - st_c[s0, 1], C[g, 2] - st_c[s0, 2]
            reach = g_radius[g] + st_r[s0] + margin
            if dx * dx + dy * dy + dz * dz > reach * reach:
                continue
            _place(g, placed, X, p, R, g_body, g_start, g_end, sph_local)
            for k in range(g_start[g], g_end[g]):
                dx, dy, dz = X[k, 0] - st_c[s0, 0], X[k, 1] - st_c[s0, 1], X[k, 2] - st_c[s0, 2]
                if np.sqrt(dx * dx + dy * dy + dz * dz) <= sph_r[k] + st_r[s0] + margin:
                    return t
    return -1


def _pair_filter(m: mujoco.MjModel):
    """``collides(g1, g2) -> bool``: whether MuJoCo tests geoms ``g1``, ``g2`` of model ``m`` as
    a pair (its ``contype``/``conaffinity`` bits, welded bodies, the parent–child filter,
    ``<exclude>``)."""
    excluded = {int(s) for s in m.exclude_signature[: m.nexclude]}
    weld = m.body_weldid

    def collides(g1: int, g2: int) -> bool:
        b1, b2 = m.geom_bodyid[g1], m.geom_bodyid[g2]
        w1, w2 = weld[b1], weld[b2]
        if w1 == w2:
            return False
        if w1 and w2 and (w1 == weld[m.body_parentid[w2]] or w2 == weld[m.body_parentid[w1]]):
            return False
        if ((int(min(b1, b2)) << 16) + int(max(b1, b2))) in excluded:
            return False
        return bool((m.geom_contype[g1] & m.geom_conaffinity[g2]) or (m.geom_contype[g2] & m.geom_conaffinity[g1]))

    return collides


class SphereChecker:
    """Validity of configurations and motions: compiled sphere checks, MuJoCo on a rejection.

    Args:
      reference: the MuJoCo checker of the scene (its margin is used); its model's collision
        bits define the pairs of a context. :meth:`set_context` switches both.
      spacing: sphere spacing along the capsules [m].
      cell: largest cell edge of the sphere grid over meshes [m].

    Attributes:
      n_motions, n_states: motions checked and samples visited by the compiled kernel.
      n_confirmed: rejections that went to MuJoCo.

    Not thread-safe (the context is the reference checker's).
    """

    def __init__(self, reference: CollisionChecker, spacing: float = 0.03, cell: float = 0.03):
        if spacing <= 0 or cell <= 0:
            raise ValueError(f"spacing and cell must be > 0 [m], got {spacing}, {cell}")
        self.reference = reference
        self.margin = reference.margin
        self.lower, self.upper = reference.lower, reference.upper
        m = reference.scene.model
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        bodies = [b for b in range(1, m.nbody) if m.body_weldid[b] == b]
        for b in bodies:
            if m.body_jntnum[b] != 1 or m.jnt_type[m.body_jntadr[b]] != mujoco.mjtJoint.mjJNT_HINGE \
                    or np.any(m.jnt_pos[m.body_jntadr[b]] != 0):
                raise ValueError(f"body {b} of the arm must have one hinge at its origin")
        slot = {b: i for i, b in enumerate(bodies)}
        root = m.body_parentid[bodies[0]]
        self._origin = d.xpos[bodies[0]].copy()  # fixed: the first joint turns about it
        self._chain = (d.xmat[root].reshape(3, 3).copy(), d.xpos[root].copy(),
                       np.array([slot.get(m.body_parentid[b], -1) for b in bodies]),
                       np.stack([frames.quat_matrix(m.body_quat[b]) for b in bodies]),
                       np.stack([m.body_pos[b] for b in bodies]).astype(float),
                       np.stack([m.jnt_axis[m.body_jntadr[b]] for b in bodies]).astype(float),
                       np.array([m.jnt_qposadr[m.body_jntadr[b]] for b in bodies]))
        centres, radii, sph_body = [], [], []
        self._moving: list[int] = []  # geom ids of moving geoms, in kernel order
        g_start, g_end, g_body, g_centre, g_radius, g_seg, g_cap = [], [], [], [], [], [], []
        self._static: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # fixed capsules/spheres
        faces, self._poly_range, self._poly_ball = [], {}, {}
        for g in range(m.ngeom):
            b = m.geom_bodyid[g]
            moving = m.body_weldid[b] != 0
            pos, R = ((m.geom_pos[g].astype(float), frames.quat_matrix(m.geom_quat[g])) if moving else
                      (d.geom_xpos[g].copy(), d.geom_xmat[g].reshape(3, 3).copy()))
            t = m.geom_type[g]
            seg, cap = np.zeros((2, 3)), 0.0
            if t == mujoco.mjtGeom.mjGEOM_CAPSULE:
                c, r = _capsule_spheres(pos, R, m.geom_size[g, 0], m.geom_size[g, 1], spacing)
                seg, cap = pos + np.outer([-1.0, 1.0], R[:, 2] * m.geom_size[g, 1]), float(m.geom_size[g, 0])
            elif t == mujoco.mjtGeom.mjGEOM_SPHERE:
                c, r = pos[None], m.geom_size[g, :1].astype(float)
            elif t == mujoco.mjtGeom.mjGEOM_MESH:
                k = m.geom_dataid[g]
                v = pos + m.mesh_vert[m.mesh_vertadr[k]: m.mesh_vertadr[k] + m.mesh_vertnum[k]].astype(float) @ R.T
                if not moving:
                    eq = _hull_faces(v)
                    self._poly_range[g] = (len(faces), len(faces) + len(eq))
                    mid = (v.min(0) + v.max(0)) / 2
                    self._poly_ball[g] = (mid, float(np.max(np.linalg.norm(v - mid, axis=1))))
                    faces += list(eq)
                    continue
                c, r = _mesh_spheres(v, cell)
            elif t == mujoco.mjtGeom.mjGEOM_PLANE and not moving:
                n = R[:, 2]  # solid behind the plane: signed distance n·(x − p0)
                self._poly_range[g] = (len(faces), len(faces) + 1)
                self._poly_ball[g] = (pos, np.inf)
                faces.append(np.r_[n, -n @ pos])
                continue
            else:
                raise ValueError(f"geom {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)!r}: type {int(t)} "
                                 "is not supported by the sphere checker")
            if not moving:
                self._static[g] = (c, r)
                continue
            self._moving.append(g)
            g_start.append(len(radii))
            g_end.append(len(radii) + len(r))
            g_body.append(slot[b])
            mid = (c.min(0) + c.max(0)) / 2
            g_centre.append(mid)
            g_radius.append(float(np.max(np.linalg.norm(c - mid, axis=1) + r)))
            g_seg.append(seg)
            g_cap.append(cap)
            centres += list(c)
            radii += list(r)
            sph_body += [slot[b]] * len(r)
        self.radii = np.array(radii)
        self._spheres = (np.array(sph_body), np.array(centres), self.radii, np.array(g_start), np.array(g_end),
                         np.array(g_body), np.array(g_centre), np.array(g_radius), np.array(g_seg), np.array(g_cap))
        self._faces = np.array(faces).reshape(-1, 4)
        self._cache: dict[Context, tuple] = {}
        self._clearance_cache: dict[Context, tuple] = {}
        self.n_motions = self.n_states = self.n_confirmed = 0
        # Compile (or load Numba's on-disk cache) now, not inside a planner's time budget.
        self.spheres_free(np.zeros((1, m.nq)))
        self.n_motions = self.n_states = self.n_confirmed = 0

    # -- pairs of a context ----------------------------------------------------------------
    def _scene_pairs(self, collides, reach) -> tuple[list, list, list, list, list]:
        """Moving geoms against the scene, as the filter ``collides`` allows: ``(geom, polytope)``
        pairs of polytopes within each geom's ``reach (G,)`` [m] (by polytope distance), and
        ``(geom, sphere centre, sphere radius)`` rows of the fixed geoms' spheres."""
        polys, *_, poly_dist = self._polytopes
        p_geom, p_poly, s_geom, s_c, s_r = [], [], [], [], []
        for i, g1 in enumerate(self._moving):
            for k, g2 in enumerate(polys):
                if poly_dist[k] <= reach[i] and collides(g1, g2):
                    p_geom.append(i)
                    p_poly.append(k)
            for g2, (c, r) in self._static.items():
                if collides(g1, g2):
                    s_geom += [i] * len(r)
                    s_c += list(c)
                    s_r += list(r)
        return p_geom, p_poly, s_geom, s_c, s_r

    def _pairs(self, context: Context) -> tuple:
        """Kernel arrays of the pairs MuJoCo tests in ``context`` (its filters, in its order)."""
        if context in self._cache:
            return self._cache[context]
        self.reference.set_context(context)
        collides = _pair_filter(self.reference._m)

        polys, starts, ends, ball_c, ball_r, boxes, poly_dist = self._polytopes
        reach = self._reach() + self.margin
        pp_geom, pp_poly, st_geom, st_c, st_r = self._scene_pairs(collides, reach)
        ss_a, ss_b = [], []
        for i, g1 in enumerate(self._moving):
            for j in range(i + 1, len(self._moving)):
                if collides(g1, self._moving[j]):
                    ss_a.append(i)
                    ss_b.append(j)
        # Half-spaces first: the ceiling and the floor are met most often.
        order = sorted(range(len(pp_poly)), key=lambda k: self._poly_range[polys[pp_poly[k]]][1]
                       - self._poly_range[polys[pp_poly[k]]][0] > 1)
        ints = lambda x: np.array(x, dtype=np.int64)  # noqa: E731
        active = np.zeros(len(self._moving), dtype=np.bool_)
        active[np.array(pp_geom + ss_a + ss_b + st_geom, dtype=np.int64)] = True
        pairs = (active, self._faces, starts, ends, ball_c, ball_r, boxes, ints(pp_geom)[order], ints(pp_poly)[order],
                 ints(ss_a), ints(ss_b),
                 ints(st_geom), np.array(st_c, dtype=float).reshape(-1, 3), np.array(st_r, dtype=float))
        self._cache[context] = pairs
        return pairs

    def _reach(self) -> np.ndarray:
        """``(G,)`` the farthest any point of each moving geom's bounding sphere can be from the
        origin of the first moving body (which only turns about itself) [m]: its bounding
        radius plus the link lengths up the chain."""
        _, _, parent, _, p_fixed, _, _ = self._chain
        _, _, _, _, _, g_body, g_centre, g_radius, _, _ = self._spheres
        out = np.linalg.norm(g_centre, axis=1) + g_radius
        for i, b in enumerate(g_body):
            while parent[b] >= 0:
                out[i] += np.linalg.norm(p_fixed[b])
                b = parent[b]
        return out

    @functools.cached_property
    def _polytopes(self) -> tuple:
        """The fixed polytopes, the same in every context: their geom ids ``(P,)`` (sorted),
        face ranges ``(P,)`` ×2 into the face equations, bounding balls (centres ``(P, 3)``,
        radii ``(P,)`` [m]), boxes ``(P, 5, 3)`` (flag row 1 for a box, see
        :func:`_box_distance`; zeros otherwise) and a lower bound of each one's distance from
        the first moving body's origin ``(P,)`` [m] (a box's exact signed distance, else the
        largest signed face distance). Built once: every context selects pairs from it."""
        polys = sorted(self._poly_range)
        starts = np.array([self._poly_range[g][0] for g in polys], dtype=np.int64)
        ends = np.array([self._poly_range[g][1] for g in polys], dtype=np.int64)
        ball_c = np.array([self._poly_ball[g][0] for g in polys], dtype=float).reshape(-1, 3)
        ball_r = np.array([self._poly_ball[g][1] for g in polys], dtype=float)
        boxes = np.zeros((max(len(polys), 1), 5, 3))
        dist = np.empty(len(polys))
        for k, g in enumerate(polys):
            eq = self._faces[starts[k]:ends[k]]
            box = _box_of(eq)
            if box is not None:
                boxes[k, 0, 0], boxes[k, 1:] = 1.0, box
                dist[k] = _box_distance(self._origin, boxes[k])
            else:
                dist[k] = float(np.max(eq[:, :3] @ self._origin + eq[:, 3]))
        return polys, starts, ends, ball_c, ball_r, boxes, dist

    def set_context(self, context: Context) -> None:
        """Switch this checker and the reference checker to ``context``."""
        self._pairs(context)
        self.reference.set_context(context)

    @property
    def context(self) -> Context:
        return self.reference.context

    # -- queries -------------------------------------------------------------------------
    def _first(self, q0: np.ndarray, q1: np.ndarray, steps: int, order: np.ndarray, start: int = 0) -> int:
        active, *pairs = self._pairs(self.context)
        t = _first_collision(q0, q1, steps, order, start, active, *self._chain, *self._spheres, *pairs, self.margin)
        self.n_states += (len(order) if t < 0 else t + 1) - start
        return int(t)

    def spheres_free(self, Q) -> np.ndarray:
        """``(k,)`` bool: the compiled sphere test alone (no limits, no MuJoCo) at every row
        of ``Q (k, n)`` [rad]; True guarantees no MuJoCo pair nearer than the margin."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        one = coarse_to_fine(1)
        return np.array([self._first(q, q, 1, one) < 0 for q in Q], dtype=bool)

    def motion_is_valid(self, q0, q1, resolution: float) -> bool:
        """Whether the straight segment ``q0 → q1`` (each ``(n,)`` [rad]; ``q0`` assumed valid, as
        OMPL does) is valid at the samples of :func:`densify` at ``resolution`` [rad].

        The compiled test visits the samples coarse to fine; MuJoCo checks each sample it
        rejects: a collision there ends the check, a false alarm of the spheres resumes it."""
        self.n_motions += 1
        q0, q1 = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
        if not np.all((q1 >= self.lower) & (q1 <= self.upper)):
            return False  # the limits are a box: both ends inside, so is the segment
        steps = max(1, int(np.ceil(np.max(np.abs(q1 - q0)) / resolution - 1e-12)))
        order = coarse_to_fine(steps)
        t = self._first(q0, q1, steps, order)
        while t >= 0:
            self.n_confirmed += 1
            if not self.reference.is_valid(q0 + (order[t] / steps) * (q1 - q0)):
                return False
            t = self._first(q0, q1, steps, order, t + 1)
        return True

    # -- clearance -----------------------------------------------------------------------
    def _clearance_pairs(self, context: Context) -> tuple:
        """Kernel arrays of the pairs of the reference checker's clearance model in
        ``context`` (arm geoms against polytopes, then against spheres of fixed geoms), less
        polytopes farther than ``clearance_max`` from anything the arm reaches."""
        if context in self._clearance_cache:
            return self._clearance_cache[context]
        self.reference.set_context(context)
        collides = _pair_filter(self.reference._mc)
        cp_geom, cp_poly, cs_geom, cs_c, cs_r = self._scene_pairs(collides, self._reach() + self.reference.clearance_max)
        ints = lambda x: np.array(x, dtype=np.int64)  # noqa: E731
        pairs = (ints(cp_geom), ints(cp_poly), ints(cs_geom), np.array(cs_c, dtype=float).reshape(-1, 3),
                 np.array(cs_r, dtype=float))
        self._clearance_cache[context] = pairs
        return pairs

    def clearance_lower_bounds(self, Q) -> np.ndarray:
        """``(k,)`` lower bounds [m] of the reference checker's :meth:`~CollisionChecker.clearance`
        at the rows of ``Q (k, n)`` [rad], in the current context, in one compiled call.

        Each is the smallest distance of an arm sphere to a scene polytope (its largest face
        distance, a box's exact distance) or a fixed sphere, capped at ``clearance_max``: the
        spheres contain the arm's geoms, so no pair MuJoCo measures is nearer (up to MuJoCo's
        own tolerance)."""
        Q = self.reference._check_batch(Q)
        _, sph_local, sph_r, g_start, g_end, g_body, g_centre, g_radius, _, _ = self._spheres
        _, faces, starts, ends, _, _, boxes, *_ = self._pairs(self.context)
        return _clearance_bounds(Q, self.reference.clearance_max, *self._chain, sph_local, sph_r, g_start, g_end,
                                 g_body, g_centre, g_radius, faces, starts, ends, boxes,
                                 *self._clearance_pairs(self.context))

    def min_clearance(self, Q) -> float:
        """The reference checker's :meth:`~CollisionChecker.min_clearance` of ``Q (k, n)``
        [rad] (the same value), with MuJoCo run only where :meth:`clearance_lower_bounds`
        leaves the minimum open."""
        return self.reference.min_clearance(Q, self.clearance_lower_bounds(Q))
