"""Compiled kernels of the fast query path: a robot as spheres on a serial chain against a world
of primitives, state by state and motion by motion.

Everything is a flat array so that Numba compiles one loop per kernel:

* ``kin``: per joint ``(n, 16)``: the fixed pose of the joint's body in its parent's frame at
  ``q = 0`` (rotation row-major ``[0:9]``, translation ``[9:12]``), the unit axis in the body's
  frame ``[12:15]`` and the kind ``[15]`` (0 revolute about the body origin, 1 prismatic);
* ``groups``: per collision group ``(G, 11)``: first and last sphere, the body it moves with
  (``-1`` the base), a bounding sphere in that body's frame (centre, radius), first and last
  cluster, first and last inscribed sphere. A group is a link of the description (the fingers are groups of their own on the
  hand's body);
* ``clusters``: ``(C, 6)``: first and last sphere, bounding sphere (centre, radius) in the
  body's frame: a few neighbouring spheres of one group, tested as one before their spheres;
* ``spheres``: ``(S, 4)`` centre in the body frame and radius [m] of the covering spheres
  (together they contain the robot's geometry); ``inner``: ``(I, 4)`` inscribed spheres (each
  inside it);
* ``obstacles``: ``(M, 20)`` rows of one kind each (:data:`BOX` … :data:`POLYTOPE`), with a
  bounding sphere ``[16:20]`` for the broad phase;
* ``planes``: ``(F, 4)`` face equations ``n·x + d ≤ 0`` of the polytopes;
* ``pairs``: ``(P, 2)`` group pairs checked against each other (self-collision).

The model tuple is ``(kin, groups, spheres, obstacles, planes, pairs, margin, clusters, inner,
exact, resolve, tables, near)``. ``exact`` is MuJoCo's model of the same robot and world, called through its C
API: ``(mjModel address, mjData address, qpos (view of the mjData's), the arm joints' qpos
addresses (n,), per group its geoms' range (G, 2) into geom ids (K,), each obstacle row's geom
id (M,))``; ``resolve`` 1: the states the spheres cannot tell are measured by it (never in
parallel threads: the mjData is shared). ``tables``: MuJoCo's distance between the two groups of
a pair two joints apart, over a grid of those joints (:mod:`uvms_jax.plan._pair_tables`):
``(index (P,) per pair its table or -1, meta (T, 8) [joint a, joint b, first node a, first
node b, spacing, bound, nodes a, nodes b], values (T, Na, Nb) float32 [m])``. ``near``: per group the
obstacles within its reach and their boxes (:func:`~uvms_jax.plan._worlds.near_obstacles`).

A sphere collides with an obstacle when its signed distance is below its radius plus the
margin; a polytope's distance is bounded below by its largest face distance, so polytopes are
tested conservatively (never a false "free"). A state whose covering spheres touch something
but whose inscribed spheres do not is undecided by spheres (MAYBE): the exact geometry is
within the covering spheres' excess of contact, and MuJoCo decides.
"""

from __future__ import annotations

from pathlib import Path

import llvmlite.binding as llvm
import mujoco
import numba
import numpy as np

from uvms_jax.plan import _kernel_cache  # noqa: F401  # the kernels below are cached by content

BOX, SPHERE, CAPSULE, CYLINDER, POLYTOPE = 0, 1, 2, 3, 4
FREE, HIT, MAYBE = 0, 1, 2  # outcomes of state_status
_TABLE_CAP = 0.1  # [m] a table's distances are measured up to this (farther: stored as it)


def _load_mujoco() -> None:
    """Make MuJoCo's C library (the one its Python bindings ship and load) known to Numba's
    linker by name, so that compiled kernels call it directly and stay cacheable."""
    folder = Path(mujoco.__file__).parent
    found = sorted(folder.glob("libmujoco.so*")) + sorted(folder.glob("libmujoco*.dylib")) + sorted(
        folder.glob("mujoco.dll"))
    if not found:
        raise ImportError(f"MuJoCo's C library was not found in {folder}")
    llvm.load_library_permanently(str(found[0]))


_load_mujoco()
_ptr = numba.types.uintp  # mjModel* / mjData* as the address the bindings give (``_address``)
_mj_kinematics = numba.types.ExternalFunction("mj_kinematics", numba.types.void(_ptr, _ptr))
_mj_geom_distance = numba.types.ExternalFunction(
    "mj_geomDistance", numba.types.float64(_ptr, _ptr, numba.types.intc, numba.types.intc, numba.types.float64, _ptr))
_DISTMAX = 1e-3  # [m] past the margin: MuJoCo stops measuring a pair there
# The per-state helpers allocate nothing: compiled without Numba's reference counting, a call
# does not count a reference in and out for each array argument (two atomic operations each).
_NO_NRT = {"cache": True, "_nrt": False}


@numba.njit(**_NO_NRT)
def pose_bodies(q, kin, R_out, t_out) -> None:
    """World poses of the chain's bodies at ``q (n,)``: ``R_out (n, 3, 3)``, ``t_out (n, 3)``
    (body ``i`` is moved by joint ``i``; body ``i - 1`` is its parent, the base for ``i = 0``)."""
    n = kin.shape[0]
    for i in range(n):
        k = kin[i]
        # Joint motion in the body's own frame: a rotation about the axis through its origin,
        # or a translation along it.
        ax, ay, az = k[12], k[13], k[14]
        if k[15] == 0.0:
            c, s = np.cos(q[i]), np.sin(q[i])
            v = 1.0 - c
            m00 = c + ax * ax * v
            m01 = ax * ay * v - az * s
            m02 = ax * az * v + ay * s
            m10 = ay * ax * v + az * s
            m11 = c + ay * ay * v
            m12 = ay * az * v - ax * s
            m20 = az * ax * v - ay * s
            m21 = az * ay * v + ax * s
            m22 = c + az * az * v
            dx = dy = dz = 0.0
        else:
            m00, m01, m02, m10, m11, m12, m20, m21, m22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
            dx, dy, dz = ax * q[i], ay * q[i], az * q[i]
        # Fixed offset then motion: R_pb = F · M, t_pb = F_t + F · d.
        f = k
        r00 = f[0] * m00 + f[1] * m10 + f[2] * m20
        r01 = f[0] * m01 + f[1] * m11 + f[2] * m21
        r02 = f[0] * m02 + f[1] * m12 + f[2] * m22
        r10 = f[3] * m00 + f[4] * m10 + f[5] * m20
        r11 = f[3] * m01 + f[4] * m11 + f[5] * m21
        r12 = f[3] * m02 + f[4] * m12 + f[5] * m22
        r20 = f[6] * m00 + f[7] * m10 + f[8] * m20
        r21 = f[6] * m01 + f[7] * m11 + f[8] * m21
        r22 = f[6] * m02 + f[7] * m12 + f[8] * m22
        tx = f[9] + f[0] * dx + f[1] * dy + f[2] * dz
        ty = f[10] + f[3] * dx + f[4] * dy + f[5] * dz
        tz = f[11] + f[6] * dx + f[7] * dy + f[8] * dz
        if i == 0:
            R_out[0, 0, 0], R_out[0, 0, 1], R_out[0, 0, 2] = r00, r01, r02
            R_out[0, 1, 0], R_out[0, 1, 1], R_out[0, 1, 2] = r10, r11, r12
            R_out[0, 2, 0], R_out[0, 2, 1], R_out[0, 2, 2] = r20, r21, r22
            t_out[0, 0], t_out[0, 1], t_out[0, 2] = tx, ty, tz
        else:
            P = R_out[i - 1]
            for a in range(3):
                R_out[i, a, 0] = P[a, 0] * r00 + P[a, 1] * r10 + P[a, 2] * r20
                R_out[i, a, 1] = P[a, 0] * r01 + P[a, 1] * r11 + P[a, 2] * r21
                R_out[i, a, 2] = P[a, 0] * r02 + P[a, 1] * r12 + P[a, 2] * r22
                t_out[i, a] = t_out[i - 1, a] + P[a, 0] * tx + P[a, 1] * ty + P[a, 2] * tz


@numba.njit(cache=True, inline="always")
def _to_world(R, t, b, x, y, z):
    if b < 0:
        return x, y, z
    return (R[b, 0, 0] * x + R[b, 0, 1] * y + R[b, 0, 2] * z + t[b, 0],
            R[b, 1, 0] * x + R[b, 1, 1] * y + R[b, 1, 2] * z + t[b, 1],
            R[b, 2, 0] * x + R[b, 2, 1] * y + R[b, 2, 2] * z + t[b, 2])


@numba.njit(cache=True)
def sphere_obstacle_distance(x, y, z, o, planes) -> float:
    """Signed distance [m] of the point ``(x, y, z)`` to the obstacle row ``o (20,)`` (a lower
    bound for a polytope)."""
    return _obstacle_distance(x, y, z, o.reshape((1, o.shape[0])), 0, planes)


@numba.njit(**_NO_NRT)
def _obstacle_distance(x, y, z, rows, m, planes) -> float:
    """:func:`sphere_obstacle_distance` of row ``m`` of ``rows (M, 20)``, read in place (a row
    taken as an array of its own costs a reference count per test)."""
    kind = rows[m, 0]
    if kind == BOX:  # [1:4] centre, [4:13] rotation row-major (columns: box axes), [13:16] half edges
        px, py, pz = x - rows[m, 1], y - rows[m, 2], z - rows[m, 3]
        out2, inside = 0.0, -np.inf
        for a in range(3):
            u = px * rows[m, 4 + a] + py * rows[m, 7 + a] + pz * rows[m, 10 + a]
            e = abs(u) - rows[m, 13 + a]
            if e > inside:
                inside = e
            if e > 0.0:
                out2 += e * e
        return np.sqrt(out2) if out2 > 0.0 else inside
    if kind == SPHERE:  # [1:4] centre, [4] radius
        return np.sqrt((x - rows[m, 1]) ** 2 + (y - rows[m, 2]) ** 2 + (z - rows[m, 3]) ** 2) - rows[m, 4]
    if kind == CAPSULE or kind == CYLINDER:  # [1:4] centre, [4:7] unit axis, [7] half length, [8] radius
        px, py, pz = x - rows[m, 1], y - rows[m, 2], z - rows[m, 3]
        along = px * rows[m, 4] + py * rows[m, 5] + pz * rows[m, 6]
        rx, ry, rz = px - along * rows[m, 4], py - along * rows[m, 5], pz - along * rows[m, 6]
        radial = np.sqrt(rx * rx + ry * ry + rz * rz)
        if kind == CAPSULE:
            a = min(max(along, -rows[m, 7]), rows[m, 7])
            return np.sqrt(radial * radial + (along - a) ** 2) - rows[m, 8]
        dr, dz = radial - rows[m, 8], abs(along) - rows[m, 7]
        if dr > 0.0 and dz > 0.0:
            return np.sqrt(dr * dr + dz * dz)
        return max(dr, dz)
    # POLYTOPE: [1], [2] first and end face row
    best = -np.inf
    for f in range(int(rows[m, 1]), int(rows[m, 2])):
        d = planes[f, 0] * x + planes[f, 1] * y + planes[f, 2] * z + planes[f, 3]
        if d > best:
            best = d
    return best


@numba.njit(**_NO_NRT)
def _hits_obstacle(g, m, groups, spheres, obstacles, planes, margin, clusters, R, t, cc, sw, splaced) -> bool:
    """Whether a sphere of group ``g`` is nearer than ``margin`` to obstacle row ``m``: its
    clusters' bounds (world centres ``cc (C, 3)``) first, then their spheres (world centres
    ``sw (S, 3)``, placed by :func:`_place_spheres`)."""
    b = int(groups[g, 2])
    for c in range(int(groups[g, 7]), int(groups[g, 8])):
        if _obstacle_distance(cc[c, 0], cc[c, 1], cc[c, 2], obstacles, m, planes) >= clusters[c, 5] + margin:
            continue
        _place_spheres(c, b, clusters, spheres, R, t, sw, splaced)
        for s in range(int(clusters[c, 0]), int(clusters[c, 1])):
            if _obstacle_distance(sw[s, 0], sw[s, 1], sw[s, 2], obstacles, m, planes) < spheres[s, 3] + margin:
                return True
    return False


@numba.njit(cache=True, inline="always")
def _place_spheres(c, b, clusters, spheres, R, t, sw, splaced) -> None:
    """World centres ``sw`` of cluster ``c``'s spheres (on body ``b``), once per state
    (``splaced (C,)``, cleared with its group's cluster centres): a sphere met by several
    obstacles or clusters is placed once."""
    if splaced[c]:
        return
    for s in range(int(clusters[c, 0]), int(clusters[c, 1])):
        sw[s, 0], sw[s, 1], sw[s, 2] = _to_world(R, t, b, spheres[s, 0], spheres[s, 1], spheres[s, 2])
    splaced[c] = True


@numba.njit(**_NO_NRT)
def _groups_touch(g1, g2, groups, spheres, margin, clusters, R, t, cc, sw, splaced) -> bool:
    """Whether a sphere of group ``g1`` is nearer than ``margin`` to one of group ``g2``:
    cluster bounds (world centres ``cc (C, 3)``) against cluster bounds, then their spheres
    (world centres ``sw (S, 3)``)."""
    b1, b2 = int(groups[g1, 2]), int(groups[g2, 2])
    # g2's bound in the world: the clusters of g1 outside it meet none of g2's.
    x2, y2, z2 = _to_world(R, t, b2, groups[g2, 3], groups[g2, 4], groups[g2, 5])
    for c1 in range(int(groups[g1, 7]), int(groups[g1, 8])):
        r = clusters[c1, 5] + groups[g2, 6] + margin
        if (cc[c1, 0] - x2) ** 2 + (cc[c1, 1] - y2) ** 2 + (cc[c1, 2] - z2) ** 2 >= r * r:
            continue
        for c2 in range(int(groups[g2, 7]), int(groups[g2, 8])):
            r = clusters[c1, 5] + clusters[c2, 5] + margin
            if (cc[c1, 0] - cc[c2, 0]) ** 2 + (cc[c1, 1] - cc[c2, 1]) ** 2 + (cc[c1, 2] - cc[c2, 2]) ** 2 >= r * r:
                continue
            # Each sphere of c1 against c2's bound, then against its spheres.
            _place_spheres(c1, b1, clusters, spheres, R, t, sw, splaced)
            for s1 in range(int(clusters[c1, 0]), int(clusters[c1, 1])):
                r1 = spheres[s1, 3] + margin
                r = r1 + clusters[c2, 5]
                if (sw[s1, 0] - cc[c2, 0]) ** 2 + (sw[s1, 1] - cc[c2, 1]) ** 2 + (sw[s1, 2] - cc[c2, 2]) ** 2 >= r * r:
                    continue
                _place_spheres(c2, b2, clusters, spheres, R, t, sw, splaced)
                for s2 in range(int(clusters[c2, 0]), int(clusters[c2, 1])):
                    r = r1 + spheres[s2, 3]
                    d2 = (sw[s1, 0] - sw[s2, 0]) ** 2 + (sw[s1, 1] - sw[s2, 1]) ** 2 + (sw[s1, 2] - sw[s2, 2]) ** 2
                    if d2 < r * r:
                        return True
    return False


@numba.njit(**_NO_NRT)
def _inner_hits_obstacle(g, m, groups, obstacles, planes, margin, inner, R, t) -> bool:
    """Whether an inscribed sphere of group ``g`` is certainly nearer than ``margin`` to row
    ``m`` (a polytope only when the centre is inside it, where its face bound is exact)."""
    b = int(groups[g, 2])
    for s in range(int(groups[g, 9]), int(groups[g, 10])):
        x, y, z = _to_world(R, t, b, inner[s, 0], inner[s, 1], inner[s, 2])
        d = _obstacle_distance(x, y, z, obstacles, m, planes)
        if d < inner[s, 3] + margin and (obstacles[m, 0] != POLYTOPE or d <= 0.0):
            return True
    return False


@numba.njit(**_NO_NRT)
def _inner_groups_touch(g1, g2, groups, margin, inner, R, t, iw) -> bool:
    """Whether an inscribed sphere of group ``g1`` is nearer than ``margin`` to one of ``g2``
    (their world centres placed once into ``iw (I, 3)``)."""
    lo1, hi1, lo2, hi2 = int(groups[g1, 9]), int(groups[g1, 10]), int(groups[g2, 9]), int(groups[g2, 10])
    for g, lo, hi in ((g1, lo1, hi1), (g2, lo2, hi2)):
        b = int(groups[g, 2])
        for s in range(lo, hi):
            iw[s, 0], iw[s, 1], iw[s, 2] = _to_world(R, t, b, inner[s, 0], inner[s, 1], inner[s, 2])
    for s1 in range(lo1, hi1):
        r1 = inner[s1, 3] + margin
        for s2 in range(lo2, hi2):
            r = r1 + inner[s2, 3]
            if (iw[s1, 0] - iw[s2, 0]) ** 2 + (iw[s1, 1] - iw[s2, 1]) ** 2 + (iw[s1, 2] - iw[s2, 2]) ** 2 < r * r:
                return True
    return False


@numba.njit(cache=True)
def _pose_exact(q, exact) -> None:
    """MuJoCo's kinematics of its model at ``q`` (the arm's joints; the rest as built)."""
    m, d, qpos, qadr = exact[0], exact[1], exact[2], exact[3]
    for j in range(qadr.shape[0]):
        qpos[qadr[j]] = q[j]
    _mj_kinematics(m, d)


@numba.njit(cache=True)
def _exact_near(g, other, exact, margin) -> bool:
    """Whether MuJoCo measures a geom of group ``g`` nearer than ``margin`` [m] to geom
    ``other`` (after :func:`_pose_exact`)."""
    m, d, ranges, geoms = exact[0], exact[1], exact[4], exact[5]
    for k in range(ranges[g, 0], ranges[g, 1]):
        if _mj_geom_distance(m, d, geoms[k], other, margin + _DISTMAX, 0) < margin:
            return True
    return False


@numba.njit(cache=True, inline="always")
def _undecided(q, g, others, exact, resolve, margin, posed):
    """The verdict on group ``g`` and the geoms ``others`` (ids) where the spheres cannot tell:
    MAYBE without the exact model (``resolve`` 0), else HIT where MuJoCo measures one of ``g``'s
    geoms nearer than ``margin`` [m] to one of them, else FREE; with whether MuJoCo's model is
    posed at ``q`` (once per state)."""
    if not resolve:
        return MAYBE, posed
    if not posed:
        _pose_exact(q, exact)
    for k in range(others.shape[0]):
        if _exact_near(g, others[k], exact, margin):
            return HIT, True
    return FREE, True


@numba.njit(cache=True, inline="always")
def _place_clusters(g, groups, clusters, R, t, cc, placed, splaced) -> None:
    """World centres ``cc`` of group ``g``'s clusters, once per state (``placed (G,)``): only the
    groups whose bound meets something need them; their spheres are not placed yet
    (``splaced``)."""
    if placed[g]:
        return
    b = int(groups[g, 2])
    for c in range(int(groups[g, 7]), int(groups[g, 8])):
        cc[c, 0], cc[c, 1], cc[c, 2] = _to_world(R, t, b, clusters[c, 2], clusters[c, 3], clusters[c, 4])
        splaced[c] = False
    placed[g] = True


@numba.njit(cache=True, inline="always")
def _table_verdict(q, k, meta, values, margin) -> int:
    """A tabled pair's verdict at ``q``: the distance at the nearest grid node, give or take
    the table's bound (how far the pair's distance can change within half a spacing of each of
    its joints): FREE or HIT where that settles it against ``margin`` [m], else MAYBE (the
    spheres decide, as for an untabled pair; also off the grid)."""
    i = int(np.floor((q[int(meta[k, 0])] - meta[k, 2]) / meta[k, 4] + 0.5))
    j = int(np.floor((q[int(meta[k, 1])] - meta[k, 3]) / meta[k, 4] + 0.5))
    if i < 0 or j < 0 or i >= meta[k, 6] or j >= meta[k, 7]:
        return MAYBE
    d = values[k, i, j]
    if d - meta[k, 5] > margin:
        return FREE
    if d + meta[k, 5] < margin:
        return HIT
    return MAYBE


@numba.njit(cache=True, inline="always")
def _status(q, kin, groups, spheres, obstacles, planes, pairs, margin, clusters, inner, exact, resolve, tab_index,
            tab_meta, tab_values, near_start, near, R, t, gc, cc, placed, sw, splaced, iw) -> int:
    """:func:`state_status` with the model's and the scratch's arrays as arguments of their own,
    inlined where it is called: taken from a tuple, or passed in a call, each array costs a
    reference count in and out per state."""
    pose_bodies(q, kin, R, t)
    G = groups.shape[0]
    for g in range(G):
        gc[g, 0], gc[g, 1], gc[g, 2] = _to_world(R, t, int(groups[g, 2]), groups[g, 3], groups[g, 4], groups[g, 5])
        placed[g] = False
    status, posed = FREE, False
    for g in range(G):
        x, y, z, gr = gc[g, 0], gc[g, 1], gc[g, 2], groups[g, 6]
        for j in range(near_start[g], near_start[g + 1]):  # the obstacles within the group's reach
            if abs(x - near[j, 1]) > near[j, 4] or abs(y - near[j, 2]) > near[j, 5] or abs(z - near[j, 3]) > near[j, 6]:
                continue  # the group's bound is outside the obstacle's box
            m = int(near[j, 0])
            if _obstacle_distance(x, y, z, obstacles, m, planes) >= gr + margin:
                continue
            _place_clusters(g, groups, clusters, R, t, cc, placed, splaced)
            if not _hits_obstacle(g, m, groups, spheres, obstacles, planes, margin, clusters, R, t, cc, sw, splaced):
                continue
            if _inner_hits_obstacle(g, m, groups, obstacles, planes, margin, inner, R, t):
                return HIT
            verdict, posed = _undecided(q, g, exact[6][m:m + 1], exact, resolve, margin, posed)
            if verdict == HIT:
                return HIT
            status = max(status, verdict)
    for p in range(pairs.shape[0]):
        g1, g2 = pairs[p, 0], pairs[p, 1]
        if tab_index[p] >= 0:
            verdict = _table_verdict(q, tab_index[p], tab_meta, tab_values, margin)
            if verdict == FREE:
                continue
            if verdict == HIT:
                return HIT
        reach = groups[g1, 6] + groups[g2, 6] + margin
        if (gc[g1, 0] - gc[g2, 0]) ** 2 + (gc[g1, 1] - gc[g2, 1]) ** 2 + (gc[g1, 2] - gc[g2, 2]) ** 2 > reach * reach:
            continue
        _place_clusters(g1, groups, clusters, R, t, cc, placed, splaced)
        _place_clusters(g2, groups, clusters, R, t, cc, placed, splaced)
        if not _groups_touch(g1, g2, groups, spheres, margin, clusters, R, t, cc, sw, splaced):
            continue
        if _inner_groups_touch(g1, g2, groups, margin, inner, R, t, iw):
            return HIT
        verdict, posed = _undecided(q, g1, exact[5][exact[4][g2, 0]:exact[4][g2, 1]], exact, resolve, margin, posed)
        if verdict == HIT:
            return HIT
        status = max(status, verdict)
    return status


@numba.njit(cache=True)
def state_status(q, model, scratch) -> int:
    """The robot at ``q (n,)`` against the world and itself: :data:`FREE` (nothing nearer than
    the margin [m]) or :data:`HIT`; without the exact model (``model``'s ``resolve`` off),
    :data:`MAYBE` where the spheres cannot tell.

    ``model``: see the module docstring; ``scratch``: :func:`make_scratch`. Each group meets
    only the obstacles of its ``near`` list, and only where its bound is inside the obstacle's
    box there; each test goes from the group's bound to its clusters' bounds to their covering
    spheres; where these touch, an inscribed sphere that does settles HIT, else MuJoCo measures
    the pair's geoms (once posed for this state) or, without it, the state is MAYBE and the
    scan goes on (a later HIT settles it)."""
    tables, near = model[11], model[12]
    return _status(q, model[0], model[1], model[2], model[3], model[4], model[5], model[6], model[7], model[8],
                   model[9], model[10], tables[0], tables[1], tables[2], near[0], near[1], scratch[0], scratch[1],
                   scratch[2], scratch[4], scratch[5], scratch[6], scratch[7], scratch[8])


@numba.njit(cache=True)
def state_free(q, model, scratch) -> bool:
    return state_status(q, model, scratch) == FREE


@numba.njit(cache=True)
def without_exact(n_groups: int, n_obstacles: int) -> tuple:
    """The ``exact`` entry of a model with no MuJoCo model (MAYBE states stay open). Its two
    pointers are int64 zeros, not literal ones: a literal 0 would type the model apart from the
    one Python passes (int64), and compile every kernel that takes it twice."""
    null = np.int64(0)
    return (null, null, np.zeros(1), np.zeros(0, np.int64), np.zeros((n_groups, 2), np.int64),
            np.zeros(0, np.int32), np.zeros(n_obstacles, np.int32))


@numba.njit(cache=True)
def without_tables(n_pairs: int) -> tuple:
    """The ``tables`` entry of a model with no pair tables."""
    return np.full(n_pairs, -1, np.int64), np.zeros((0, 8)), np.zeros((0, 1, 1), np.float32)


@numba.njit(cache=True, parallel=True)
def states_status(Q, kin, groups, spheres, obstacles, planes, pairs, margin, clusters, inner, tables,
                  near) -> np.ndarray:
    """``(k,)`` uint8: :func:`state_status` of each row of ``Q (k, n)`` by the spheres and the
    pair tables alone (the model without ``exact``: threads share no mjData), in chunks over the
    CPU's threads."""
    k = Q.shape[0]
    out = np.empty(k, dtype=np.uint8)
    chunk = 256
    tab_index, tab_meta, tab_values = tables
    near_start, near_rows = near
    for c in numba.prange((k + chunk - 1) // chunk):
        exact = without_exact(groups.shape[0], obstacles.shape[0])
        R, t, gc, _, cc, placed, sw, splaced, iw = _scratch(kin.shape[0], groups.shape[0], spheres.shape[0],
                                                            clusters.shape[0], inner.shape[0])
        for i in range(c * chunk, min(k, (c + 1) * chunk)):
            out[i] = _status(Q[i], kin, groups, spheres, obstacles, planes, pairs, margin, clusters, inner, exact,
                             np.int64(0),
                             tab_index, tab_meta, tab_values, near_start, near_rows, R, t, gc, cc, placed, sw, splaced,
                             iw)
    return out


@numba.njit(cache=True)
def make_scratch(model):
    """Work arrays of one thread's checks: body rotations ``(n, 3, 3)`` and positions ``(n, 3)``,
    group centres ``(G, 3)``, one configuration ``(n,)``, cluster centres ``(C, 3)``, whether
    each group's cluster centres are placed for the current state ``(G,)``, sphere centres
    ``(S, 3)``, whether each cluster's spheres are placed ``(C,)``, inscribed sphere centres
    ``(I, 3)``."""
    return _scratch(model[0].shape[0], model[1].shape[0], model[2].shape[0], model[7].shape[0], model[8].shape[0])


@numba.njit(cache=True)
def _scratch(n, G, S, C, I):
    return (np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((G, 3)), np.empty(n), np.empty((C, 3)),
            np.zeros(G, np.bool_), np.empty((S, 3)), np.zeros(C, np.bool_), np.empty((I, 3)))


@numba.njit(cache=True)
def n_samples(q0, q1, resolution) -> int:
    """Samples of the straight motion ``q0 → q1`` so that no joint moves more than
    ``resolution`` [rad] between two (the end included, the start not)."""
    d = 0.0
    for j in range(q0.shape[0]):
        d = max(d, abs(q1[j] - q0[j]))
    return max(1, int(np.ceil(d / resolution - 1e-12)))


@numba.njit(cache=True, inline="always")
def _sample_collides(q0, q1, i, steps, model, scratch) -> bool:
    q = scratch[3]
    f = i / steps
    for j in range(q0.shape[0]):
        q[j] = q0[j] + f * (q1[j] - q0[j])
    return not state_free(q, model, scratch)


@numba.njit(cache=True)
def motion_free(q0, q1, resolution, model, scratch) -> bool:
    """Whether every sample of ``q0 → q1`` at ``resolution`` [rad] (:func:`n_samples`; ``q0``
    assumed free) is free. Samples are visited coarse to fine — the end, then the odd multiples
    of strides 2^m … 1 — so a collision is usually met after a few."""
    steps = n_samples(q0, q1, resolution)
    if _sample_collides(q0, q1, steps, steps, model, scratch):
        return False
    stride = 1
    while stride * 2 <= steps:
        stride *= 2
    while stride > 0:
        for i in range(stride, steps, 2 * stride):
            if _sample_collides(q0, q1, i, steps, model, scratch):
                return False
        stride //= 2
    return True


@numba.njit(cache=True)
def pairs_touching(Q, model, candidates) -> np.ndarray:
    """``(k, P)`` bool: whether the two groups of each candidate pair ``(P, 2)`` have spheres
    nearer than the margin at each row of ``Q (k, n)`` (for the pairs that touch in every pose)."""
    out = np.zeros((Q.shape[0], candidates.shape[0]), dtype=np.bool_)
    R, t, _, _, cc, placed, sw, splaced, _ = make_scratch(model)
    groups, clusters = model[1], model[7]
    for i in range(Q.shape[0]):
        pose_bodies(Q[i], model[0], R, t)
        placed[:] = False
        for g in range(groups.shape[0]):
            _place_clusters(g, groups, clusters, R, t, cc, placed, splaced)
        for p in range(candidates.shape[0]):
            out[i, p] = _groups_touch(candidates[p, 0], candidates[p, 1], groups, model[2], model[6], clusters, R, t,
                                      cc, sw, splaced)
    return out


@numba.njit(cache=True)
def settle(Q, status, model) -> np.ndarray:
    """``(k,)`` bool: whether each row of ``Q (k, n)`` is free, its :func:`states_status`
    ``status`` kept where it is FREE or HIT and measured by ``model``'s exact model (serially:
    one mjData) where it is MAYBE."""
    out = status == FREE
    scratch = make_scratch(model)
    for i in range(Q.shape[0]):
        if status[i] == MAYBE:
            out[i] = state_status(Q[i], model, scratch) == FREE
    return out


@numba.njit(cache=True)
def distance_table(exact, g1, g2, ja, jb, first_a, first_b, spacing, na, nb, n) -> np.ndarray:
    """``(na, nb)`` float32: MuJoCo's least distance [m] between the geoms of groups ``g1`` and
    ``g2`` (``exact``'s ranges) with joint ``ja`` at ``first_a + i spacing`` and ``jb`` at
    ``first_b + j spacing`` (the other ``n - 2`` joints at 0), up to :data:`_TABLE_CAP`."""
    m, d, ranges, geoms = exact[0], exact[1], exact[4], exact[5]
    out = np.empty((na, nb), np.float32)
    q = np.zeros(n)
    for i in range(na):
        q[ja] = first_a + i * spacing
        for j in range(nb):
            q[jb] = first_b + j * spacing
            _pose_exact(q, exact)
            best = _TABLE_CAP
            for k in range(ranges[g1, 0], ranges[g1, 1]):
                for l in range(ranges[g2, 0], ranges[g2, 1]):
                    best = min(best, _mj_geom_distance(m, d, geoms[k], geoms[l], _TABLE_CAP, 0))
            out[i, j] = best
    return out
