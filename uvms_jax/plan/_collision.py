"""Collision and clearance queries on a :class:`~uvms_jax.plan.Scene` (MuJoCo, CPU).

``is_valid(q, context)``: inside the joint limits, no arm–scene contact and no self-contact
between non-adjacent links closer than the safety ``margin``. ``clearance(q, context)``: the
smallest signed distance between the moving arm (links F…B, jaws, held object) and the scene.
Every query takes the :class:`~uvms_jax.plan.Context` it is asked in (which object is held,
which obstacles are ignored) as an argument rather than reading it from the checker: one
checker serves the approach, the lift and the transfer of a pick and place, and a context
left behind by an earlier caller can then never leak into a later check. Both run
``mj_kinematics`` + ``mj_collision`` (a few µs per configuration); clearance uses a second
copy of the model whose geom margins are ``clearance_max``, so that MuJoCo's broad and narrow
phases return every arm–scene pair nearer than that with its signed distance in one call.
A context is the models' ``contype``/``conaffinity`` bits (computed once per context); a query
writes them on entry when they are set for another context (a few µs) and skips that when they
already match (one identity test), so consecutive queries in one context cost nothing extra
and no result depends on the queries made before it.
Batched versions take ``(k, n)`` arrays (a whole trajectory or population) and loop over
MuJoCo calls without per-state Python objects. Validity never reads ``MjData.contact`` (building
that view costs ~100 µs): the checker keeps one model copy whose geom margins are the safety
margin and one whose margins are 0, and a state is valid exactly when MuJoCo reports no contact.
"""

from __future__ import annotations

import mujoco
import numpy as np

from uvms_jax.plan._scene import Context, Scene

__all__ = ["BOUND_SLACK", "CollisionChecker", "densify"]

#: How far [m] a lower bound of the geometric clearance may exceed MuJoCo's measure of it (seen:
#: 4e-5 m, mesh pairs) and still let :meth:`CollisionChecker.min_clearance` skip a row.
BOUND_SLACK = 1e-3


def densify(path: np.ndarray, resolution: float) -> np.ndarray:
    """Linear interpolation of a joint path so that no joint moves more than ``resolution``
    between consecutive rows.

    Args:
      path: ``(k, n)`` waypoints [rad], k ≥ 1.
      resolution: largest per-joint step [rad], > 0.

    Returns:
      ``(m, n)`` points, first and last equal to the path's; every waypoint is kept.
    """
    path = np.asarray(path, dtype=float)
    if path.ndim != 2 or path.shape[0] < 1:
        raise ValueError(f"path must have shape (k, n) with k >= 1, got {path.shape}")
    if not resolution > 0:
        raise ValueError(f"resolution must be positive, got {resolution}")
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        steps = max(1, int(np.ceil(np.max(np.abs(b - a)) / resolution - 1e-12)))
        s = np.arange(1, steps + 1)[:, None] / steps
        out.append(a + s * (b - a))
    return np.concatenate(out)


def _compile(spec: mujoco.MjSpec, margin: float) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """A copy of the scene's model with every geom's ``margin`` [m]."""
    spec = spec.copy()
    for g in spec.geoms:
        g.margin = margin
    m = spec.compile()
    return m, mujoco.MjData(m)


class CollisionChecker:
    """Validity and clearance of arm configurations in a scene.

    Args:
      scene: the built scene.
      margin: safety distance [m]: ``is_valid`` rejects any pair nearer than this.
      clearance_max: distances are reported up to this value [m] (farther pairs read as it).

    Every query takes its :class:`~uvms_jax.plan.Context` as an argument (no default: the
    context of a check is part of its question). The checker owns three model copies and one
    ``MjData`` each, whose geom bits it switches to the context of each query; it is not
    thread-safe.
    """

    def __init__(self, scene: Scene, margin: float = 0.005, clearance_max: float = 0.3):
        if margin < 0 or clearance_max <= margin:
            raise ValueError(f"need 0 <= margin < clearance_max, got {margin}, {clearance_max}")
        self.scene = scene
        self.margin = float(margin)
        self.clearance_max = float(clearance_max)
        self.lower = scene.model.jnt_range[:, 0].copy()
        self.upper = scene.model.jnt_range[:, 1].copy()
        # MuJoCo adds the two geoms' margins of a pair: half each gives the pair margin. The
        # margin must be compiled in (not set afterwards): broad-phase bounds include it.
        self._m, self._d = _compile(scene.mjspec, self.margin / 2)
        self._m0, self._d0 = _compile(scene.mjspec, 0.0)
        self._mc, self._dc = _compile(scene.mjspec, self.clearance_max / 2)
        self.n_checks = 0
        # The context the models' geom bits are set for: a private cache of MuJoCo state that
        # spares the switch when consecutive queries share a context, never an input.
        self._context: Context | None = None
        self._bits: dict[Context, tuple[np.ndarray, ...]] = {}  # context → its geom bits
        self._enter(Context())

    # -- context -------------------------------------------------------------------------
    def _enter(self, context: Context) -> None:
        """Set the models' geoms for ``context`` (held object on, ignored obstacles off) unless
        they already are; called on entry of every query. Raises ValueError for a context
        naming an unknown object or obstacle, TypeError for anything but a Context."""
        if context is self._context:
            return
        if not isinstance(context, Context):
            raise TypeError(f"context must be a plan.Context, got {context!r}")
        if context != self._context:
            self._apply(context)
        # Keep the caller's instance: its next query is then one identity test.
        self._context = context

    def _apply(self, context: Context) -> None:
        """Write the geom bits of ``context`` into the three models (a few µs: the bits of
        each context are computed once, :meth:`_bits_of`)."""
        bits = self._bits.get(context)
        if bits is None:
            bits = self._bits[context] = self._bits_of(context)
        contype, conaffinity, c_contype, c_conaffinity = bits
        for m in (self._m, self._m0):
            m.geom_contype[:] = contype
            m.geom_conaffinity[:] = conaffinity
        self._mc.geom_contype[:] = c_contype
        self._mc.geom_conaffinity[:] = c_conaffinity

    def _bits_of(self, context: Context) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(ngeom,)`` ``contype`` and ``conaffinity`` of the validity models, then of the
        clearance model, in ``context`` (:meth:`Scene.geom_bits`)."""
        out = self.scene.geom_bits(context).astype(self._m.geom_contype.dtype)
        out.flags.writeable = False
        return out[0], out[1], out[2], out[3]

    # -- single configurations ------------------------------------------------------------
    def in_limits(self, q: np.ndarray) -> bool:
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= self.lower) & np.all(q <= self.upper))

    def _pick(self, margin: float | None) -> tuple[mujoco.MjModel, mujoco.MjData]:
        if margin is None or margin == self.margin:
            return self._m, self._d
        if margin == 0.0:
            return self._m0, self._d0
        raise ValueError(f"margin must be the checker's margin ({self.margin}) or 0, got {margin}")

    def is_valid(self, q, context: Context, margin: float | None = None) -> bool:
        """Whether ``q (n,)`` [rad] is inside the limits and no pair active in ``context`` is
        nearer than ``margin`` [m]: the checker's safety margin (default) or 0 (no penetration)."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self._m.nq,) or not np.all(np.isfinite(q)):
            raise ValueError(f"q must be {self._m.nq} finite joint angles, got {q}")
        m, d = self._pick(margin)
        if context is not self._context:
            self._enter(context)
        if not self.in_limits(q):
            return False
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        self.n_checks += 1
        return d.ncon == 0

    def state_validator(self, n: int, context: Context):
        """A minimal-overhead ``valid(state) -> bool`` for OMPL states (indexable, ``n``
        values, inside the bounds), using the safety margin, in ``context``.

        A planning query binds its context here once; each call still makes sure the model is
        in it (one identity test while it is), as another query may have switched it since."""
        self._enter(context)  # reject a bad context now, not inside OMPL
        m, d = self._m, self._d
        qpos = d.qpos
        kinematics, collision = mujoco.mj_kinematics, mujoco.mj_collision
        idx = range(n)
        enter = self._enter

        def valid(state) -> bool:
            if self._context is not context:
                enter(context)
            for i in idx:
                qpos[i] = state[i]
            kinematics(m, d)
            collision(m, d)
            return d.ncon == 0

        return valid

    def contacts(self, q, context: Context, margin: float | None = None) -> list[tuple[str, str, float]]:
        """The pairs active in ``context`` nearer than ``margin`` at ``q``: ``(geom name, geom
        name, signed distance [m])``."""
        mod, d = self._pick(margin)
        self._enter(context)
        d.qpos[:] = np.asarray(q, dtype=float)
        mujoco.mj_kinematics(mod, d)
        mujoco.mj_collision(mod, d)
        name = lambda g: mujoco.mj_id2name(mod, mujoco.mjtObj.mjOBJ_GEOM, int(g))  # noqa: E731
        c = d.contact
        return [(name(c.geom[i][0]), name(c.geom[i][1]), float(c.dist[i])) for i in range(d.ncon)]

    def clearance(self, q, context: Context) -> float:
        """Smallest signed distance [m] between the moving arm (links F…B, jaws, held object)
        and the scene of ``context`` at ``q (n,)``, capped at ``clearance_max``; negative =
        penetration."""
        if context is not self._context:
            self._enter(context)
        d = self._dc
        d.qpos[:] = q
        mujoco.mj_kinematics(self._mc, d)
        mujoco.mj_collision(self._mc, d)
        if d.ncon == 0:
            return self.clearance_max
        return float(min(self.clearance_max, np.min(d.contact.dist[: d.ncon])))

    # -- batches -------------------------------------------------------------------------
    def _check_batch(self, Q) -> np.ndarray:
        Q = np.asarray(Q, dtype=float)
        if Q.ndim != 2 or Q.shape[1] != self._m.nq or not np.all(np.isfinite(Q)):
            raise ValueError(f"Q must be a finite (k, {self._m.nq}) array, got shape {Q.shape}")
        return Q

    def is_valid_batch(self, Q, context: Context, margin: float | None = None) -> np.ndarray:
        """``(k,)`` bool: :meth:`is_valid` of every row of ``Q (k, n)`` in ``context``."""
        Q = self._check_batch(Q)
        mod, d = self._pick(margin)
        self._enter(context)
        inside = np.all((Q >= self.lower) & (Q <= self.upper), axis=1)
        out = np.zeros(len(Q), dtype=bool)
        qpos = d.qpos
        for i in np.flatnonzero(inside):
            qpos[:] = Q[i]
            mujoco.mj_kinematics(mod, d)
            mujoco.mj_collision(mod, d)
            out[i] = d.ncon == 0
        self.n_checks += int(inside.sum())
        return out

    def clearance_batch(self, Q, context: Context) -> np.ndarray:
        """``(k,)`` :meth:`clearance` of every row of ``Q (k, n)`` in ``context`` [m]."""
        Q = self._check_batch(Q)
        self._enter(context)
        out = np.empty(len(Q))
        mod, d = self._mc, self._dc
        for i, q in enumerate(Q):
            d.qpos[:] = q
            mujoco.mj_kinematics(mod, d)
            mujoco.mj_collision(mod, d)
            out[i] = self.clearance_max if d.ncon == 0 else min(self.clearance_max, np.min(d.contact.dist[: d.ncon]))
        return out

    def min_clearance(self, Q, context: Context, lower_bounds=None) -> float:
        """Smallest :meth:`clearance` over the rows of ``Q (k, n)`` [m] (k ≥ 1).

        Args:
          Q: configurations [rad].
          context: the context of the clearance.
          lower_bounds: optional ``(k,)`` values [m], each non-negative one at most the
            geometric clearance of its row (e.g. :meth:`SphereChecker.clearance_lower_bounds`):
            MuJoCo then measures the rows in increasing bound order, and stops at the first
            bound that is non-negative and at least the smallest clearance found plus
            :data:`BOUND_SLACK` (MuJoCo's distances may fall short of the geometric ones by its
            solver tolerance), so the result is the minimum over all rows.
        """
        Q = self._check_batch(Q)
        if len(Q) == 0:
            raise ValueError("Q must have at least one row")
        if lower_bounds is None:
            return float(np.min(self.clearance_batch(Q, context)))
        lower_bounds = np.asarray(lower_bounds, dtype=float)
        if lower_bounds.shape != (len(Q),):
            raise ValueError(f"lower_bounds must have shape ({len(Q)},), got {lower_bounds.shape}")
        best = np.inf
        for i in np.argsort(lower_bounds, kind="stable"):
            if lower_bounds[i] >= max(best + BOUND_SLACK, 0.0):
                break  # a negative bound may exceed a penetration depth: never skip on it
            best = min(best, self.clearance(Q[i], context))
        return float(best)

    def path_is_valid(self, path, context: Context, resolution: float = 0.01, margin: float | None = None) -> bool:
        """Whether the piecewise-linear joint path ``(k, n)`` is valid in ``context`` at every
        point of a ``resolution`` [rad] interpolation."""
        return bool(np.all(self.is_valid_batch(densify(path, resolution), context, margin)))
