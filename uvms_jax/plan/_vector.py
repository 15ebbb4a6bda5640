"""The fast collision checker of a robot in a :class:`~uvms_jax.plan.World`: the robot's fitted
spheres (:func:`uvms_jax.robot.collision_spheres`) on its chain, the world's primitives, one
compiled call per batch of states or per motion (VAMP's approach: Thomason et al., "Motions in
Microseconds via Vectorized Sampling-Based Planning", ICRA 2024).

The spheres contain the robot's geometry, so a state the checker calls free is free for the
exact geometry too (up to the sphere fit's coverage, checked by the tests); the reverse does
not hold (a sphere bulges past its shape by at most the fit's stated excess).

Self-collision: the robot's links form groups (a moving body with the fixed links folded into
it; each finger on its own; the card's jaws, :func:`uvms_jax.robot.card_jaws`, and each shape
attached for the query — an object in the hand — on their own too). A pair of groups is
skipped when they are adjacent (on one body, or on a body and its parent: a link and its
parent, a finger and its hand, the two fingers of one opening, as MuJoCo filters them), when
their spheres touch in every sampled pose (MoveIt's "always in collision"), or when the world's
allowed collision matrix allows every link pair between them. The base link's groups are never
tested against the world: both are fixed (MuJoCo does not test geoms welded together either).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools

import mujoco
import numpy as np
from scipy.cluster.vq import kmeans2

from uvms_jax.plan._rrtc import load
from uvms_jax.plan._pair_tables import pair_tables
from uvms_jax.plan._vector_kernels import (make_scratch, motion_free, pairs_touching, settle, state_free,
                                           states_status, without_exact, without_tables)
from uvms_jax.plan._spec import Obstacle
from uvms_jax.plan._worlds import World, add_obstacles, near_obstacles, obstacle_rows
from uvms_jax.robot import (BASE, Robot, RobotSpheres, Shape, base_body, card_jaws, collision_spheres, inscribed_spheres,
                            robot_spec)

__all__ = ["LIMIT_TOL", "ExactChecker", "RobotSpheresModel", "VectorChecker", "check_in_limits", "robot_spheres_model",
           "warm_kernels"]

#: A joint value this close outside a limit counts as at the limit [rad or m]: the chain keeps
#: limits in float32, which rounds a limit such as 2.8973 rad by up to 2.4e-7.
LIMIT_TOL = 1e-6
_OBSTACLE = "obstacle_"  # prefix of the world's geoms in the exact model
_CLUSTER = 8  # spheres per cluster (on average): the bound tested before them
_ALWAYS_SAMPLES = 200  # poses of the "touching in every pose" test (as MoveIt's setup assistant)


def check_in_limits(robot: Robot, q, label: str) -> np.ndarray:
    """``q (n,)`` [rad/m] as float64, within the limits up to :data:`LIMIT_TOL`; a ValueError
    naming the joint, its value and its limit otherwise."""
    q = np.asarray(q, dtype=np.float64)
    if q.shape != (robot.n_joints,):
        raise ValueError(f"{label} has {q.size} values, the arm {robot.name!r} has {robot.n_joints} joints")
    for name, v, lo, hi in zip(robot.joint_names, q, robot.lower, robot.upper):
        if not np.isfinite(v):
            raise ValueError(f"{label}: joint {name!r} is {v}")
        if v < lo - LIMIT_TOL or v > hi + LIMIT_TOL:
            raise ValueError(f"{label}: joint {name!r} at {v:.6g} is outside its limits [{lo:.6g}, {hi:.6g}] "
                             f"(tolerance {LIMIT_TOL:g})")
    return q


def _kin_rows(robot: Robot) -> np.ndarray:
    """``(n, 16)``: each joint's fixed pose in its parent body, its axis in its own body, its kind."""
    chain = robot.chain
    T0 = np.asarray(chain.T_base_joint0, dtype=np.float64)
    twists = np.asarray(chain.twists, dtype=np.float64)
    rows = np.zeros((robot.n_joints, 16))
    parent = np.eye(4)
    for i in range(robot.n_joints):
        F = np.linalg.inv(parent) @ T0[i]
        R, p = T0[i][:3, :3], T0[i][:3, 3]
        v, w = twists[i, :3], twists[i, 3:]
        prismatic = chain.kinds[i] == "prismatic"
        if not prismatic and np.linalg.norm(v + np.cross(w, p)) > 1e-6:
            raise ValueError(f"joint {robot.joint_names[i]!r}: its axis does not pass through its body's origin")
        rows[i, :9], rows[i, 9:12] = F[:3, :3].reshape(9), F[:3, 3]
        rows[i, 12:15], rows[i, 15] = R.T @ (v if prismatic else w), float(prismatic)
        parent = T0[i]
    return rows


@dataclasses.dataclass(frozen=True, eq=False)
class RobotSpheresModel:
    """A robot's side of the checker at one finger opening: the compiled arrays and its groups.

    Attributes:
      robot: the robot.
      opening: the gripper joint's value the fingers are posed at [m] (0 without a gripper).
      kin: ``(n, 16)`` joint rows; groups: ``(G, 11)``; spheres: ``(S, 4)``; clusters:
        ``(C, 6)``; inner: ``(I, 4)`` inscribed spheres (:mod:`uvms_jax.plan._vector_kernels`).
      group_links: per group, the description's links in it.
      group_bodies: per group, the moving body it belongs to (``-1`` the base) and its part
        (``-1`` none; ``0 … F-1`` the fingers, then the card's jaws, then ``attached``).
      skipped: group pairs never checked against each other, with the reason
        (``"adjacent"``: one body, or a body and its parent; ``"always"``).
      attached: the shapes fixed to the arm for this model (besides the card's jaws).
    """

    robot: Robot
    opening: float
    kin: np.ndarray
    groups: np.ndarray
    spheres: np.ndarray
    clusters: np.ndarray
    inner: np.ndarray
    group_links: tuple[frozenset[str], ...]
    group_bodies: tuple[tuple[int, int], ...]
    skipped: dict[tuple[int, int], str]
    attached: tuple[Shape, ...] = ()

    def pairs(self, world: World) -> np.ndarray:
        """``(P, 2)`` group pairs checked in ``world``: every pair not skipped and not allowed by
        its collision matrix for every link pair between the two groups."""
        out = [(a, b) for a, b in itertools.combinations(range(len(self.groups)), 2)
               if (a, b) not in self.skipped
               and not all(world.allows(x, y) for x in self.group_links[a] for y in self.group_links[b])]
        return np.array(out, dtype=np.int64).reshape(-1, 2)

    def model(self, world: World, margin: float = 0.0, exact: "ExactChecker | None" = None) -> tuple:
        """The compiled checker's arrays for this robot in ``world`` with ``margin`` [m];
        ``exact``: MuJoCo's model of both, which settles what the spheres cannot tell (None:
        such states come out MAYBE) and measures the pair tables
        (:mod:`uvms_jax.plan._pair_tables`; none without it)."""
        rows, planes = obstacle_rows(world.obstacles)
        # Obstacles beyond every pose's reach never meet a sphere: left out of the loops.
        # A body's origin is at most max_reach from the base's; its group within |centre| + radius.
        reach = self.robot.max_reach + float(np.max(np.linalg.norm(self.groups[:, 3:6], axis=1) + self.groups[:, 6]))
        near = np.linalg.norm(rows[:, 16:19], axis=1) - rows[:, 19] <= reach + float(margin)
        pairs = self.pairs(world)
        if exact is None:
            arrays, tables = without_exact(len(self.groups), int(np.sum(near))), without_tables(len(pairs))
        else:
            arrays, tables = exact.arrays(near), pair_tables(exact, self, pairs)
        rows = rows[near]
        return (self.kin, self.groups, self.spheres, rows, planes, pairs, float(margin), self.clusters,
                self.inner, arrays, int(exact is not None), tables,
                near_obstacles(self.kin, self.groups, rows, planes, float(margin)))


def _bound(c: np.ndarray, r: np.ndarray) -> list[float]:
    """A sphere ``[x, y, z, radius]`` containing the spheres ``c (k, 3)``, ``r (k,)``."""
    mid = (c.min(0) + c.max(0)) / 2
    return [*mid, float(np.max(np.linalg.norm(c - mid, axis=1) + r))]


def _clusters(c: np.ndarray) -> list[np.ndarray]:
    """Index sets of neighbouring centres ``c (k, 3)``, about :data:`_CLUSTER` each (k-means,
    seeded: the same clusters every time)."""
    k = int(np.ceil(len(c) / _CLUSTER))
    if k <= 1:
        return [np.arange(len(c))]
    _, label = kmeans2(c, k, seed=0, minit="++")
    return [np.flatnonzero(label == j) for j in range(k) if np.any(label == j)]


def _posed(robot: Robot, spheres: RobotSpheres, opening: float) -> np.ndarray:
    """``(S, 3)`` sphere centres in their bodies' frames, the fingers' slid to ``opening`` [m]."""
    centre = np.asarray(spheres.centre, dtype=np.float64).copy()
    for k, f in enumerate(robot.fingers):
        centre[spheres.finger == k] += np.asarray(f.axis) * f.value(opening)
    return centre


def _opening(robot: Robot, opening: float | None) -> float:
    """The opening [m] the hand is posed at: the gripper joint's value for the description's
    fingers (within its limits), the gap between the boxes for the card's jaws (any length
    >= 0, as :func:`uvms_jax.robot.add_robot` takes it: a scene's ``jaws_open``)."""
    g = robot.gripper
    if g is None:
        if opening not in (None, 0.0):
            raise ValueError(f"robot {robot.name!r} has no gripper: opening must be None, got {opening}")
        return 0.0
    value = g.upper if opening is None else float(opening)
    if not robot.fingers:
        if not (np.isfinite(value) and value >= 0):
            raise ValueError(f"the jaws' opening must be a finite gap >= 0 [m], got {value}")
        return value
    if not (g.lower - LIMIT_TOL <= value <= g.upper + LIMIT_TOL):
        raise ValueError(f"gripper joint {g.joint!r} at {value:.6g} is outside its limits [{g.lower:.6g}, "
                         f"{g.upper:.6g}] (tolerance {LIMIT_TOL:g})")
    return value


def _group_spheres(robot: Robot, opening: float, spheres: RobotSpheres, attached: tuple[Shape, ...]) -> list:
    """Per collision group: ``(body, part)``, its links, covering centres ``(k, 3)`` and radii
    ``(k,)``, inscribed centres and radii, in the body's frame at ``opening`` [m]. Parts: the
    fingers ``0 … F-1``, then the card's jaws and the ``attached`` shapes, one group each."""
    fingers = robot.fingers
    keys = [(BASE, -1)] + [(b, -1) for b in range(robot.n_joints)] + [(f.body, k) for k, f in enumerate(fingers)]
    links = [{robot.base_link}] + [{name} for name in robot.link_names] + [{f.link} for f in fingers]
    for shape in robot.shapes:
        links[shape.body + 1].add(shape.link)
    inner = inscribed_spheres(robot)
    centre, inner_centre = (_posed(robot, sp, opening) for sp in (spheres, inner))
    out = []
    for key, link_set in zip(keys, links):
        sel = (spheres.body == key[0]) & (spheres.finger == key[1])
        own = (inner.body == key[0]) & (inner.finger == key[1])
        out.append((key, link_set, centre[sel], np.asarray(spheres.radius, dtype=np.float64)[sel], inner_centre[own],
                    np.asarray(inner.radius, dtype=np.float64)[own]))
    for j, shape in enumerate(card_jaws(robot, opening) + attached):
        cover, inside = collision_spheres(robot, shapes=(shape,)), inscribed_spheres(robot, shapes=(shape,))
        out.append(((shape.body, len(fingers) + j), {shape.link}, cover.centre, cover.radius, inside.centre,
                    inside.radius))
    return [g for g in out if len(g[3])]


@functools.lru_cache(maxsize=16)
def robot_spheres_model(robot: Robot, opening: float | None = None, spheres: RobotSpheres | None = None,
                        attached: tuple[Shape, ...] = ()) -> RobotSpheresModel:
    """The robot's side of the checker at a finger ``opening`` [m] (default: the gripper's
    largest), from ``spheres`` (default: :func:`uvms_jax.robot.collision_spheres`), with the
    card's jaws (:func:`uvms_jax.robot.card_jaws`) and the ``attached`` shapes (e.g. an object
    in the hand: ``Shape.body`` the body it is fixed to, its pose in that body's frame) as
    groups of their own, each fitted with its covering and inscribed spheres. Cached."""
    opening = _opening(robot, opening)
    spheres = collision_spheres(robot) if spheres is None else spheres
    n = robot.n_joints
    rows, cluster_rows, inner_rows, group_rows, group_links, group_bodies = [], [], [], [], [], []
    for key, link_set, c, r, inner_c, inner_r in _group_spheres(robot, opening, spheres, attached):
        first_sphere, first_cluster, first_inner = len(rows), len(cluster_rows), len(inner_rows)
        for members in _clusters(c):
            cluster_rows.append([len(rows), len(rows) + len(members), *_bound(c[members], r[members])])
            rows += [[*c[i], r[i]] for i in members]
        inner_rows += [[*ci, ri] for ci, ri in zip(inner_c, inner_r)]
        group_rows.append([first_sphere, len(rows), key[0], *_bound(c, r), first_cluster, len(cluster_rows),
                           first_inner, len(inner_rows)])
        group_links.append(frozenset(link_set))
        group_bodies.append(key)
    kin, groups, sphere_rows = _kin_rows(robot), np.array(group_rows, dtype=np.float64), np.array(rows)
    clusters = np.array(cluster_rows, dtype=np.float64)
    inner_rows = np.array(inner_rows, dtype=np.float64).reshape(-1, 4)
    # Adjacent: groups of one body or of a body and its parent (MuJoCo's filter of the exact check).
    skipped = {(a, b): "adjacent" for a, b in itertools.combinations(range(len(groups)), 2)
               if abs(group_bodies[a][0] - group_bodies[b][0]) <= 1}
    candidates = np.array([p for p in itertools.combinations(range(len(groups)), 2) if p not in skipped],
                          dtype=np.int64).reshape(-1, 2)
    Q = np.random.default_rng(0).uniform(robot.lower, robot.upper, (_ALWAYS_SAMPLES, n))
    no_rows, no_planes = np.zeros((0, 20)), np.zeros((0, 4))
    model = (kin, groups, sphere_rows, no_rows, no_planes, np.zeros((0, 2), np.int64), 0.0, clusters, inner_rows,
             without_exact(len(groups), 0), 0, without_tables(0), near_obstacles(kin, groups, no_rows, no_planes, 0.0))
    touching = pairs_touching(Q, model, candidates)
    for (a, b), always in zip(candidates, np.all(touching, axis=0)):
        if always:
            skipped[(int(a), int(b))] = "always"
    return RobotSpheresModel(robot, opening, kin, groups, sphere_rows, clusters, inner_rows, tuple(group_links),
                             tuple(group_bodies), skipped, attached)


def _part_of(side: RobotSpheresModel):
    """``part(geom name) -> int``: the part of the exact model's geom (robot_spec's names: a
    finger's ``geom_<finger joint>_<k>``, a jaw's or attached shape's ``geom_<link>``), ``-1``
    for a body's own geoms and ``-2`` for the world's."""
    robot = side.robot
    fingers = [f"geom_{f.joint}_" for f in robot.fingers]
    shapes = {f"geom_{s.link}": len(fingers) + j for j, s in enumerate(card_jaws(robot, side.opening) + side.attached)}

    def part(name: str) -> int:
        if name.startswith(_OBSTACLE):
            return -2
        return shapes.get(name, next((k for k, prefix in enumerate(fingers) if name.startswith(prefix)), -1))

    return part


class ExactChecker:
    """MuJoCo's collision test of the robot's own geometry (meshes, primitives, the fingers at
    the opening, the card's jaws, attached shapes) against the world's, with the same skipped and allowed pairs as the spheres
    (MuJoCo excludes body pairs: a body pair is checked where any of its group pairs is).

    Args:
      side: the robot's sphere model (its robot, opening and group pairs).
      world: the world.
    """

    def __init__(self, side: RobotSpheresModel, world: World):
        robot = side.robot
        spec = robot_spec(robot, jaws_open=side.opening if robot.gripper else None, attached=side.attached)
        add_obstacles(spec, world.obstacles, _OBSTACLE)
        # The fingers are geoms of their arm body in this model, fixed at the opening: a body
        # pair is left out only where every group pair between the two bodies is.
        bodies = [base_body(robot), *robot.link_names]
        on = [bodies[body + 1] for body, _ in side.group_bodies]
        checked = {(on[a], on[b]) for a, b in side.pairs(world)}
        checked |= {(b, a) for a, b in checked}
        for a, b in itertools.combinations(bodies, 2):
            if (a, b) not in checked:
                spec.add_exclude(bodyname1=a, bodyname2=b)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self._arm = np.array([self.model.joint(j).qposadr[0] for j in robot.joint_names])
        m = self.model
        part = _part_of(side)
        ranges, geoms = [], []
        for (body, k), body_name in zip(side.group_bodies, on):
            own = [g for g in range(m.ngeom) if part(m.geom(g).name) == k
                   and (k >= 0 or m.body(m.geom_bodyid[g]).name == body_name)]
            ranges.append([len(geoms), len(geoms) + len(own)])
            geoms += own
        self._ranges, self._geoms = np.array(ranges, np.int64).reshape(-1, 2), np.array(geoms, np.int32)
        self._obstacles = np.array([m.geom(_OBSTACLE + o.name).id for o in world.obstacles], np.int32)
        # MuJoCo excludes body pairs; the spheres skip group pairs. A contact between two of the
        # robot's geoms counts only where the spheres check their groups' pair, so both checkers
        # judge the same pairs: True where a geom pair's contact counts.
        group = np.full(m.ngeom, -1)
        for k, (a, b) in enumerate(self._ranges):
            group[self._geoms[a:b]] = k
        pairs = {tuple(p) for p in side.pairs(world)}
        self._counts = np.array([[group[a] < 0 or group[b] < 0 or (min(group[a], group[b]), max(group[a], group[b]))
                                  in pairs for b in range(m.ngeom)] for a in range(m.ngeom)], dtype=bool)

    def arrays(self, rows) -> tuple:
        """The compiled checker's view of this model (see :mod:`uvms_jax.plan._vector_kernels`),
        for the obstacle rows selected by the mask ``rows (M,)``."""
        return (self.model._address, self.data._address, self.data.qpos, self._arm.astype(np.int64), self._ranges,
                self._geoms, self._obstacles[rows])

    def _penetrating(self, q) -> np.ndarray:
        """Indices of the contacts at ``q (n,)`` [rad] that penetrate and count."""
        m, d = self.model, self.data
        d.qpos[self._arm] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        if not d.ncon:
            return np.zeros(0, int)
        geom = d.contact.geom
        return np.flatnonzero((d.contact.dist < 0) & self._counts[geom[:, 0], geom[:, 1]])

    def free(self, q) -> bool:
        """Whether ``q (n,)`` [rad] is free of penetrating contacts."""
        return not len(self._penetrating(q))

    def contacts(self, Q) -> list[tuple[int, str, str, float]]:
        """Penetrating contacts at the rows of ``Q (k, n)`` [rad]: ``(row, geom, geom, depth [m])``."""
        m, d = self.model, self.data
        out = []
        for i, q in enumerate(np.atleast_2d(Q)):
            for k in self._penetrating(q):
                g1, g2 = d.contact.geom[k]
                out.append((i, m.geom(g1).name, m.geom(g2).name, float(-d.contact.dist[k])))
        return out


def _limits(a) -> np.ndarray:
    """Joint limits as the kernels take them: float64, read-only whatever the robot holds, so
    that one compiled variant serves every robot (Numba compiles a read-only array apart)."""
    out = np.array(a, dtype=np.float64)
    out.setflags(write=False)
    return out


class VectorChecker:
    """The compiled sphere checker of a robot in a world (see the module docstring).

    Args:
      robot: the robot.
      world: its world.
      opening: the finger opening [m] (default: the gripper's largest; the card's jaws: the
        gap between them).
      margin: safety distance [m] added to every sphere.
      spheres: the robot's spheres (default: :func:`uvms_jax.robot.collision_spheres`).
      attached: shapes fixed to the arm's bodies for this checker, e.g. an object in the hand
        (``Shape.body`` its body, its pose in that body's frame, ``Shape.link`` its name):
        covered and inscribed by their own spheres, and in MuJoCo's model.
    """

    def __init__(self, robot: Robot, world: World, opening: float | None = None, margin: float = 0.0,
                 spheres: RobotSpheres | None = None, attached: tuple[Shape, ...] = ()):
        if not (np.isfinite(margin) and margin >= 0):
            raise ValueError(f"margin must be finite and >= 0 [m], got {margin}")
        self.robot, self.world = robot, world
        self.side = robot_spheres_model(robot, opening, spheres, tuple(attached))
        self.exact = ExactChecker(self.side, world)
        self.model = self.side.model(world, margin, self.exact)
        self.lower, self.upper = _limits(robot.lower), _limits(robot.upper)
        self._scratch = make_scratch(self.model)
        q = np.zeros((1, robot.n_joints))
        self.states_free(q), self.motion_free(q[0], q[0], 1.0), load(self.model, self.lower, self.upper)  # see load

    def _rows(self, Q) -> np.ndarray:
        Q = np.ascontiguousarray(np.atleast_2d(Q), dtype=np.float64)
        if Q.ndim != 2 or Q.shape[1] != self.robot.n_joints:
            raise ValueError(f"Q must have shape (k, {self.robot.n_joints}), got {Q.shape}")
        return Q

    def states_status(self, Q) -> np.ndarray:
        """``(k,)`` uint8 FREE / HIT / MAYBE of the rows of ``Q (k, n)`` [rad] by the spheres
        alone (see :func:`~uvms_jax.plan._vector_kernels.state_status`), in one compiled call
        over the CPU's threads."""
        return states_status(self._rows(Q), *self.model[:9], *self.model[11:])

    def states_free(self, Q) -> np.ndarray:
        """``(k,)`` bool: rows of ``Q (k, n)`` [rad] where the robot touches nothing (limits not
        checked): the spheres' verdict, MuJoCo's where the spheres cannot tell."""
        Q = self._rows(Q)
        return settle(Q, states_status(Q, *self.model[:9], *self.model[11:]), self.model)

    def state_free(self, q) -> bool:
        """Whether the robot at ``q (n,)`` [rad] touches nothing (limits not checked), in one
        serial compiled call: :meth:`states_free` of a single state (an OMPL callback's)."""
        return bool(state_free(np.asarray(q, dtype=np.float64), self.model, self._scratch))

    def motion_free(self, q0, q1, resolution: float) -> bool:
        """Whether the straight motion ``q0 → q1`` is free at every sample ``resolution`` [rad]
        apart on every joint (``q0`` itself not checked)."""
        return bool(motion_free(np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64), float(resolution),
                                self.model, self._scratch))


def warm_kernels(robot: Robot) -> None:
    """Compile (or load from Numba's cache) every kernel a :class:`VectorChecker` of ``robot``
    calls, on a world with one box: the kernels' types do not depend on the world's sizes, so a
    later checker of any world of this robot compiles nothing. Meant for a background thread
    while other work runs (:func:`uvms_jax.pipeline.run_pipeline` starts one before the stages
    that plan): on a machine's first run it takes the compilation (about 25 s on 2 CPU cores) out
    of the planning stage's path."""
    # The box lies within the arm's reach: a box beyond it is left out of the model, and the
    # distance kernel that decides each group's near obstacles would not compile.
    box = Obstacle(name="warm", shape="box", pos=(robot.max_reach, 0.0, 0.0), dims=(0.05, 0.05, 0.05))
    VectorChecker(robot, World((box,)), margin=0.005)
