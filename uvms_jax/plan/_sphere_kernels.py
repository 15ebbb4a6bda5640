"""The sphere checker's geometry and compiled kernels: an arm's capsules and meshes as spheres,
convex polytopes as face equations, and the Numba loops that pose the spheres (forward
kinematics of MuJoCo's body tree) and test whole motions or bound clearances in one call
(:class:`~uvms_jax.plan.SphereChecker` reads a scene's MuJoCo model into these arrays).
"""

from __future__ import annotations

import functools

import numba
import numpy as np
from scipy.spatial import ConvexHull

from uvms_jax.plan import _kernel_cache  # noqa: F401  # the kernels below are cached by content

_FACE_ATOL = 1e-9  # coplanar triangles of a hull give one face equation up to round-off


def _hull_faces(vertices: np.ndarray) -> np.ndarray:
    """Face equations ``(f, 4)`` of the convex hull of ``vertices (v, 3)``: ``n·x + d ≤ 0``
    inside, ``|n| = 1``: the hull's triangles' equations in Qhull's order, each kept unless a
    kept one equals it within the tolerance (each compared with all kept ones in one call)."""
    equations = ConvexHull(vertices).equations
    keep, n = np.empty_like(equations), 0
    for e in equations:
        if not np.any(np.all(np.abs(keep[:n] - e) < _FACE_ATOL * 1e3, axis=1)):
            keep[n], n = e, n + 1
    return keep[:n].copy()


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


_CORNERS = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float)
_CELL_EDGES = np.array([(a, b) for a in range(8) for b in range(a + 1, 8) if np.sum(_CORNERS[a] != _CORNERS[b]) == 1])
_IN_TOL = 1e-9  # [m] a point this close outside the cell or the hull still counts (only enlarges a sphere)
_DEPTHS = 24  # candidate centres along a piece's inward normal


def _hull_edges(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The convex hull's vertices ``(v, 3)`` and the edges of its triangles ``(e, 2)`` (indices
    into them; edges inside a face of several triangles included)."""
    hull = ConvexHull(vertices)
    index = np.full(len(vertices), -1)
    index[hull.vertices] = np.arange(len(hull.vertices))
    tri = index[hull.simplices]
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [0, 2]]]), axis=1)
    return vertices[hull.vertices], np.unique(edges, axis=0)


def _cell_piece(lo: np.ndarray, h: np.ndarray, V: np.ndarray, E: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Points ``(p, 3)`` among which lie all vertices of the convex piece ``[lo, lo + h] ∩ hull``
    (so a ball holding them holds the piece): the hull's vertices in the cell, the cell's corners
    in the hull, the hull's edges through the cell's faces and the cell's edges where they enter
    and leave the hull. ``V (v, 3)``, ``E (e, 2)``: the hull's vertices and edges; ``faces (f, 4)``
    its face equations."""
    hi = lo + h
    in_cell = lambda x: x[np.all((x >= lo - _IN_TOL) & (x <= hi + _IN_TOL), axis=1)]
    corners = lo + _CORNERS * h
    out = [in_cell(V), corners[np.max(corners @ faces[:, :3].T + faces[:, 3], axis=1) <= _IN_TOL]]
    p, d = V[E[:, 0]], V[E[:, 1]] - V[E[:, 0]]
    for axis in range(3):
        for plane in (lo[axis], hi[axis]):
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (plane - p[:, axis]) / d[:, axis]
            ok = np.isfinite(t) & (t >= 0) & (t <= 1)  # an edge in the plane: its ends are found elsewhere
            out.append(in_cell(p[ok] + t[ok, None] * d[ok]))
    a, b = corners[_CELL_EDGES[:, 0]], corners[_CELL_EDGES[:, 1]]  # (12, 3)
    fa = a @ faces[:, :3].T + faces[:, 3]  # (12, f): face distance along the edge is fa + t (fb - fa)
    slope = (b @ faces[:, :3].T + faces[:, 3]) - fa
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -fa / slope
    t0 = np.max(np.where(slope < 0, t, 0.0), axis=1, initial=0.0)
    t1 = np.min(np.where(slope > 0, t, 1.0), axis=1, initial=1.0)
    cut = (t0 <= t1) & ~np.any((slope == 0) & (fa > _IN_TOL), axis=1)
    out += [(a + t0[:, None] * (b - a))[cut], (a + t1[:, None] * (b - a))[cut]]
    return np.concatenate(out)


@functools.lru_cache(maxsize=256)
def _mesh_spheres_cached(data: bytes, n: int, cell: float) -> tuple[np.ndarray, np.ndarray]:
    vertices = np.frombuffer(data).reshape(n, 3)
    V, E = _hull_edges(vertices)
    faces = _hull_faces(vertices)
    lo, hi = V.min(0), V.max(0)
    counts = np.maximum(1, np.ceil((hi - lo) / cell - 1e-9).astype(int))
    h = (hi - lo) / counts
    reach = np.linspace(0.0, np.linalg.norm(hi - lo) / 2, _DEPTHS)[:, None]
    centres, radii = [], []
    for ijk in np.ndindex(*counts):
        P = _cell_piece(lo + np.array(ijk) * h, h, V, E, faces)
        if len(P) < 4 or np.min(np.ptp(P, axis=0)) <= 1e-7 * cell:
            continue  # no piece, or a flat one: it lies in its neighbours' pieces too
        # The ball of least bulge out of the hull, r + largest face distance of its centre, among
        # centres from the piece's box middle inwards (against the summed normals of the hull's
        # faces the piece touches): deep centres put the ball's rim on the piece's faces.
        touch = np.any(P @ faces[:, :3].T + faces[:, 3] > -_IN_TOL, axis=0)
        inward = -faces[touch, :3].sum(0)
        inward /= max(np.linalg.norm(inward), 1e-300)
        c = (P.min(0) + P.max(0)) / 2 + reach * inward  # (_DEPTHS, 3)
        r = np.max(np.linalg.norm(c[:, None] - P[None], axis=2), axis=1)
        best = np.argmin(r + np.max(c @ faces[:, :3].T + faces[:, 3], axis=1))
        centres.append(c[best])
        radii.append(r[best] * (1 + 1e-12) + _IN_TOL)
    return np.array(centres).reshape(-1, 3), np.array(radii)


def _mesh_spheres(vertices: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Spheres covering the convex hull of ``vertices (v, 3)`` [m] (MuJoCo collides a mesh as
    its hull): centres ``(n, 3)``, radii ``(n,)`` [m], one per cell (edges ≤ ``cell``) of a grid
    over the hull's bounding box that the hull enters.

    Each sphere holds the cell's piece of the hull (every vertex of the piece lies in it, and
    the ball is convex), so together they hold the hull; its centre is the one, on a line from
    the piece's middle into the hull, with the least bulge out of the hull (the circumscribed
    sphere of a cell cut by a face bulges by up to its radius, √3/2 of the cell's edge). Cached
    by the vertices' bytes: a link's spheres are fitted once per process.
    """
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    centres, radii = _mesh_spheres_cached(vertices.tobytes(), len(vertices), float(cell))
    return centres.copy(), radii.copy()


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
    ``i = order[t]``, that the spheres reject, or −1 (see :class:`SphereChecker`).

    Over 80 lines as one function: the motion's whole loop is one compiled Numba kernel, whose
    scratch arrays (frames, placed spheres) are allocated once per call and reused per sample;
    split into calls, each sample would pass them all and stop early less cheaply."""
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
