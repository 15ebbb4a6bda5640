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
  fingers, the held object) becomes one sphere per cell of a grid over its bounding box that
  its convex hull enters, holding the cell's piece of the hull with the least bulge out of it;
* scene: planes are half-spaces and meshes their convex hulls (face equations); capsules and
  spheres of fixed bodies (the base link) become spheres as above;
* pairs: exactly the geom pairs MuJoCo tests in the query's :class:`Context` (the reference
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

Like the reference checker's, every query takes its :class:`Context` as an argument: the pairs
of a context are built once (~2 ms) and cached by context, so a query's answer depends on its
arguments only, never on the contexts of earlier queries.
"""

from __future__ import annotations

import functools

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.robot import SPHERE_SPACING, capsule_spheres
from uvms_jax.plan._collision import CollisionChecker
from uvms_jax.plan._scene import Context
from uvms_jax.plan._sphere_kernels import (_box_distance, _box_of, _clearance_bounds,
                                          _first_collision, _hull_faces, _mesh_spheres, coarse_to_fine)

# Grid cell of a mesh's spheres [m]. Docking tests every pair of them per IK solution: the
# Panda's meshes give 1 381 spheres (589 k pairs per target) at 3 cm, 656 (133 k) at 4 cm, whose
# free share of random configurations is 15.6 % against 17.0 % at 3 cm (MuJoCo: 21.6 %); 4.5 cm
# cells, cut across its links less evenly, leave 11.9 %.
MESH_CELL = 0.04

__all__ = ["SphereChecker", "coarse_to_fine"]

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
        bits define the pairs of a context, and it confirms the rejections.
      spacing: sphere spacing along the capsules [m].
      cell: largest cell edge of the sphere grid over meshes [m].

    Attributes:
      n_motions, n_states: motions checked and samples visited by the compiled kernel.
      n_confirmed: rejections that went to MuJoCo.

    Every query takes its :class:`Context` as an argument. Not thread-safe (nor is the
    reference checker).
    """

    def __init__(self, reference: CollisionChecker, spacing: float = SPHERE_SPACING, cell: float = MESH_CELL):
        if spacing <= 0 or cell <= 0:
            raise ValueError(f"spacing and cell must be > 0 [m], got {spacing}, {cell}")
        self.reference = reference
        self.margin = reference.margin
        self.lower, self.upper = reference.lower, reference.upper
        m = reference.scene.model
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        slot, self._origin, self._chain = _arm_chain(m, d)
        centres, radii, sph_body = [], [], []
        self._moving: list[int] = []  # geom ids of moving geoms, in kernel order
        g_start, g_end, g_body, g_centre, g_radius, g_seg, g_cap = [], [], [], [], [], [], []
        self._static: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # fixed capsules/spheres
        faces, self._poly_range, self._poly_ball = [], {}, {}
        for g in range(m.ngeom):
            b = m.geom_bodyid[g]
            moving = m.body_weldid[b] != 0
            shape = _geom_shape(m, d, g, moving, spacing, cell)
            if shape[0] == "polytope":  # a fixed mesh's hull or a plane's half-space
                _, eq, ball = shape
                self._poly_range[g] = (len(faces), len(faces) + len(eq))
                self._poly_ball[g] = ball
                faces += list(eq)
                continue
            _, c, r, seg, cap = shape
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
        # The last context asked for and its pairs: a query in the same Context instance as the
        # one before skips hashing it (the pairs are a function of the context's value).
        self._last: tuple[Context | None, tuple] = (None, ())
        self.n_motions = self.n_states = self.n_confirmed = 0
        # Compile (or load Numba's on-disk cache) now, not inside a planner's time budget.
        self.spheres_free(np.zeros((1, m.nq)), Context())
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
        last = self._last
        if last[0] is context:
            return last[1]
        pairs = self._cache.get(context) if isinstance(context, Context) else None
        if pairs is None:
            pairs = self._build_pairs(context)
        self._last = (context, pairs)
        return pairs

    def _build_pairs(self, context: Context) -> tuple:
        # The reference's model in this context gives MuJoCo's filters (and rejects a bad context).
        self.reference._enter(context)
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

    # -- queries -------------------------------------------------------------------------
    def _first(self, q0: np.ndarray, q1: np.ndarray, steps: int, order: np.ndarray, pairs: tuple,
               start: int = 0) -> int:
        """Index into ``order`` of the first sample from ``start`` that the spheres reject, -1
        if none; ``pairs``: :meth:`_pairs` of the query's context."""
        active, *pairs = pairs
        t = _first_collision(q0, q1, steps, order, start, active, *self._chain, *self._spheres, *pairs, self.margin)
        self.n_states += (len(order) if t < 0 else t + 1) - start
        return int(t)

    def spheres_free(self, Q, context: Context) -> np.ndarray:
        """``(k,)`` bool: the compiled sphere test alone (no limits, no MuJoCo) at every row
        of ``Q (k, n)`` [rad] in ``context``; True guarantees no MuJoCo pair nearer than the
        margin."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        one = coarse_to_fine(1)
        pairs = self._pairs(context)
        return np.array([self._first(q, q, 1, one, pairs) < 0 for q in Q], dtype=bool)

    def motion_is_valid(self, q0, q1, context: Context, resolution: float) -> bool:
        """Whether the straight segment ``q0 → q1`` (each ``(n,)`` [rad]; ``q0`` assumed valid, as
        OMPL does) is valid in ``context`` at the samples of :func:`densify` at ``resolution``
        [rad].

        The compiled test visits the samples coarse to fine; MuJoCo checks each sample it
        rejects: a collision there ends the check, a false alarm of the spheres resumes it."""
        self.n_motions += 1
        pairs = self._pairs(context)  # first: a bad context raises whatever the motion
        q0, q1 = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
        if not np.all((q1 >= self.lower) & (q1 <= self.upper)):
            return False  # the limits are a box: both ends inside, so is the segment
        steps = max(1, int(np.ceil(np.max(np.abs(q1 - q0)) / resolution - 1e-12)))
        order = coarse_to_fine(steps)
        t = self._first(q0, q1, steps, order, pairs)
        while t >= 0:
            self.n_confirmed += 1
            if not self.reference.is_valid(q0 + (order[t] / steps) * (q1 - q0), context):
                return False
            t = self._first(q0, q1, steps, order, pairs, t + 1)
        return True

    # -- clearance -----------------------------------------------------------------------
    def _clearance_pairs(self, context: Context) -> tuple:
        """Kernel arrays of the pairs of the reference checker's clearance model in
        ``context`` (arm geoms against polytopes, then against spheres of fixed geoms), less
        polytopes farther than ``clearance_max`` from anything the arm reaches."""
        if context in self._clearance_cache:
            return self._clearance_cache[context]
        self.reference._enter(context)
        collides = _pair_filter(self.reference._mc)
        cp_geom, cp_poly, cs_geom, cs_c, cs_r = self._scene_pairs(collides, self._reach() + self.reference.clearance_max)
        ints = lambda x: np.array(x, dtype=np.int64)  # noqa: E731
        pairs = (ints(cp_geom), ints(cp_poly), ints(cs_geom), np.array(cs_c, dtype=float).reshape(-1, 3),
                 np.array(cs_r, dtype=float))
        self._clearance_cache[context] = pairs
        return pairs

    def clearance_lower_bounds(self, Q, context: Context) -> np.ndarray:
        """``(k,)`` lower bounds [m] of the reference checker's :meth:`~CollisionChecker.clearance`
        at the rows of ``Q (k, n)`` [rad], in ``context``, in one compiled call.

        Each is the smallest distance of an arm sphere to a scene polytope (its largest face
        distance, a box's exact distance) or a fixed sphere, capped at ``clearance_max``: the
        spheres contain the arm's geoms, so no pair MuJoCo measures is nearer (up to MuJoCo's
        own tolerance)."""
        Q = self.reference._check_batch(Q)
        _, sph_local, sph_r, g_start, g_end, g_body, g_centre, g_radius, _, _ = self._spheres
        _, faces, starts, ends, _, _, boxes, *_ = self._pairs(context)
        return _clearance_bounds(Q, self.reference.clearance_max, *self._chain, sph_local, sph_r, g_start, g_end,
                                 g_body, g_centre, g_radius, faces, starts, ends, boxes,
                                 *self._clearance_pairs(context))

    def min_clearance(self, Q, context: Context) -> float:
        """The reference checker's :meth:`~CollisionChecker.min_clearance` of ``Q (k, n)``
        [rad] in ``context`` (the same value), with MuJoCo run only where
        :meth:`clearance_lower_bounds` leaves the minimum open."""
        return self.reference.min_clearance(Q, context, self.clearance_lower_bounds(Q, context))


def _arm_chain(m: mujoco.MjModel, d: mujoco.MjData) -> tuple[dict[int, int], np.ndarray, tuple]:
    """The arm's moving bodies in the model at ``d``'s kinematics: body id → slot, the first
    joint's origin in the world ``(3,)`` [m] (fixed: the first joint turns about it), and the
    chain's arrays for the kernel (root frame, parent slots, body rotations and positions,
    joint axes, qpos addresses).

    Raises:
      ValueError: a body that does not have exactly one hinge at its origin.
    """
    bodies = [b for b in range(1, m.nbody) if m.body_weldid[b] == b]
    for b in bodies:
        if m.body_jntnum[b] != 1 or m.jnt_type[m.body_jntadr[b]] != mujoco.mjtJoint.mjJNT_HINGE \
                or np.any(m.jnt_pos[m.body_jntadr[b]] != 0):
            raise ValueError(f"body {b} of the arm must have one hinge at its origin")
    slot = {b: i for i, b in enumerate(bodies)}
    root = m.body_parentid[bodies[0]]
    chain = (d.xmat[root].reshape(3, 3).copy(), d.xpos[root].copy(),
             np.array([slot.get(m.body_parentid[b], -1) for b in bodies]),
             np.stack([frames.quat_matrix(m.body_quat[b]) for b in bodies]),
             np.stack([m.body_pos[b] for b in bodies]).astype(float),
             np.stack([m.jnt_axis[m.body_jntadr[b]] for b in bodies]).astype(float),
             np.array([m.jnt_qposadr[m.body_jntadr[b]] for b in bodies]))
    return slot, d.xpos[bodies[0]].copy(), chain


def _geom_shape(m: mujoco.MjModel, d: mujoco.MjData, g: int, moving: bool, spacing: float, cell: float) -> tuple:
    """Geom ``g`` for the sphere checker: ``("spheres", centres (s, 3), radii (s,), capsule
    segment (2, 3), capsule radius)`` (in its body's frame if ``moving``, else the world's; a
    radius of 0 and no segment for a non-capsule), or for a fixed mesh or plane ``("polytope",
    faces (f, 4), (centre, radius) of a ball around it)``.

    Raises:
      ValueError: a geom type the sphere checker does not support.
    """
    pos, R = ((m.geom_pos[g].astype(float), frames.quat_matrix(m.geom_quat[g])) if moving else
              (d.geom_xpos[g].copy(), d.geom_xmat[g].reshape(3, 3).copy()))
    t = m.geom_type[g]
    seg, cap = np.zeros((2, 3)), 0.0
    if t == mujoco.mjtGeom.mjGEOM_CAPSULE:
        c, r = capsule_spheres(pos, R, m.geom_size[g, 0], m.geom_size[g, 1], spacing)
        seg, cap = pos + np.outer([-1.0, 1.0], R[:, 2] * m.geom_size[g, 1]), float(m.geom_size[g, 0])
    elif t == mujoco.mjtGeom.mjGEOM_SPHERE:
        c, r = pos[None], m.geom_size[g, :1].astype(float)
    elif t == mujoco.mjtGeom.mjGEOM_MESH:
        k = m.geom_dataid[g]
        v = pos + m.mesh_vert[m.mesh_vertadr[k]: m.mesh_vertadr[k] + m.mesh_vertnum[k]].astype(float) @ R.T
        if not moving:
            mid = (v.min(0) + v.max(0)) / 2
            return "polytope", _hull_faces(v), (mid, float(np.max(np.linalg.norm(v - mid, axis=1))))
        c, r = _mesh_spheres(v, cell)
    elif t == mujoco.mjtGeom.mjGEOM_PLANE and not moving:
        n = R[:, 2]  # solid behind the plane: signed distance n·(x − p0)
        return "polytope", [np.r_[n, -n @ pos]], (pos, np.inf)
    else:
        raise ValueError(f"geom {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)!r}: type {int(t)} "
                         "is not supported by the sphere checker")
    return "spheres", c, r, seg, cap
