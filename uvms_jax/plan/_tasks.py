"""The pick-and-place task graph (thesis Table 5.1, eq. 4.1): its edges, planning one edge,
the metric tensor for ``uvms_jax.sched``, and the :class:`uvms_jax.planfile.Plan` of a schedule.

Nodes: 0 start, the objects, the bases, and the goal (= the start configuration, numbered
one past the last base; 9 in the thesis). Allowed moves (the rules of ``uvms_jax.sched``):
start → any object; object → a base it fits; base → any object, the start or the goal. An
edge's motion runs from where the arm leaves the source (start, or the post-grasp / post-final
configuration) to where it arrives at the destination (pre-grasp / pre-final, or the start);
the arm holds the object on edges out of an object. The descent to the grasp/final pose and
back is the same whatever the schedule, so it belongs to the node, not to the edges (and to
``plan.json``).

The scene is static (thesis 5.2: "only static collision objects"): objects stay at their
start positions as obstacles, except the one held or being grasped.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np

from uvms_jax import planfile, sched
from uvms_jax.plan._collision import CollisionChecker, densify
from uvms_jax.plan._metrics import EdgeMetrics, trajectory_metrics
from uvms_jax.plan._planning import PlanResult, Trajectory, check_trajectory, plan_motion, time_parameterize
from uvms_jax.plan._scene import Context, Scene
from uvms_jax.plan._scenequery import plan_scene_query
from uvms_jax.plan._settings import PlanSettings
from uvms_jax.plan._spheres import SphereChecker
from uvms_jax.plan._targets import NodeTarget, node_contexts

__all__ = [
    "EdgeResult",
    "compatibility",
    "edge_endpoints",
    "goal_node",
    "metric_tensor",
    "plan_edge",
    "plan_from_edges",
    "task_edges",
]

START = 0


def goal_node(scene: Scene) -> int:
    """Number of the goal node (one past the last object/base node)."""
    return max(*scene.objects, *scene.bases) + 1


def compatibility(scene: Scene) -> dict[int, tuple[int, ...]]:
    """Object node → the base nodes it fits (the scene's ``fits``): the scheduler's compat."""
    return {o: tuple(b for b in sorted(scene.bases) if o in scene.bases[b].fits) for o in sorted(scene.objects)}


def task_edges(scene: Scene) -> list[tuple[int, int]]:
    """All allowed moves ``(src, dst)`` of the task graph, in row-major order: the static move
    rules of ``uvms_jax.sched`` (``PickPlaceProblem.rule``) on the scene's nodes.

    Raises:
      ValueError: the scene's nodes do not form a pick-and-place problem (e.g. an object that
        fits no base, or node numbers with gaps).
    """
    goal = goal_node(scene)
    n = goal + 1
    problem = sched.PickPlaceProblem.from_matrix(np.zeros((n, n)), compatibility(scene), START, goal)
    if problem.bases != tuple(sorted(scene.bases)):
        raise ValueError(f"scene nodes must be start {START}, objects, bases, goal {goal} without gaps; "
                         f"got objects {sorted(scene.objects)}, bases {sorted(scene.bases)}")
    return [(int(i), int(j)) for i, j in np.argwhere(np.asarray(problem.rule)[:n, :n])]


def _edge_set(scene: Scene) -> frozenset[tuple[int, int]]:
    """:func:`task_edges` of ``scene`` as a set, computed once and kept by the scene (it is not
    changed after it is built; the rules cost ~1 ms, as much as planning an edge)."""
    if "task_edges" not in scene.derived:
        scene.derived["task_edges"] = frozenset(task_edges(scene))
    return scene.derived["task_edges"]


def _q_at_node(scene: Scene, targets: Mapping[int, NodeTarget], node: int) -> np.ndarray:
    if node in (START, goal_node(scene)):
        return np.asarray(scene.start_q, dtype=float)
    if node not in targets:
        raise ValueError(f"unknown node {node} (known: {sorted(targets)}, start {START}, goal {goal_node(scene)})")
    return targets[node].q_pre


def edge_endpoints(scene: Scene, targets: Mapping[int, NodeTarget], src: int, dst: int) -> tuple[np.ndarray, np.ndarray, Context]:
    """``(q_from, q_to, context)`` of edge ``src → dst``; raises ValueError for a move the
    task graph forbids."""
    if (src, dst) not in _edge_set(scene):
        raise ValueError(f"move {src} -> {dst} is not in the task graph")
    ctx = Context(held=src) if src in scene.objects else Context()
    return _q_at_node(scene, targets, src), _q_at_node(scene, targets, dst), ctx


@dataclasses.dataclass(frozen=True)
class EdgeResult:
    """One planned edge: planner output, trajectory, re-check and metrics."""

    planner: str
    src: int
    dst: int
    plan: PlanResult
    trajectory: Trajectory | None
    metrics: EdgeMetrics | None
    check: dict

    @property
    def success(self) -> bool:
        return self.plan.success

    @property
    def revalidated(self) -> bool:
        c = self.check
        return bool(c) and c["collision_free"] and c["in_limits"] and c["within_velocity"]


def plan_edge(
    scene: Scene,
    checker: CollisionChecker,
    targets: Mapping[int, NodeTarget],
    src: int,
    dst: int,
    planner: str,
    settings: PlanSettings = PlanSettings(),
    fast: SphereChecker | None = None,
) -> EdgeResult:
    """Plan one edge, time-parameterise it, re-check it and measure its metrics.

    ``settings`` give the path (``checker``: the query path, :func:`plan_scene_query`, or
    OMPL on the scene's checkers, :func:`plan_motion`), the budget, the resolutions, the time
    parameterisation's limits and the planner's parameters. Metrics are measured on the path interpolated at
    ``settings.recheck_resolution`` (clearance at ``clearance_resolution``), torques from the arm's own weight and buoyancy plus the held
    object's load (edges out of an object), gravity rotated into the arm's base frame. With ``fast`` (a
    :class:`SphereChecker` on ``checker``) the planner checks motions with it; every result is
    re-checked with MuJoCo.
    """
    s = settings
    q0, q1, ctx = edge_endpoints(scene, targets, src, dst)
    recheck_resolution = s.recheck_resolution
    if s.checker == "query":
        res = plan_scene_query(scene, checker, q0, q1, ctx, planner, s)
    else:
        res = plan_motion(checker, q0, q1, ctx, planner, s.budget_s, s.resolution, recheck_resolution, s.simplify_s,
                          fast=fast, params=s.planner_params.get(planner), straight_shortcut=s.straight_shortcut)
    if not res.success:
        return EdgeResult(planner, src, dst, res, None, None, {})
    traj = time_parameterize(res.path, s.joint_velocity(scene.robot), s.max_acceleration)
    check = check_trajectory(checker, traj, ctx, recheck_resolution, collision_free=res.success)
    force = None
    if ctx.held is not None:
        force = scene.T_base_world[:3, :3] @ scene.payload_force_world(ctx.held)
    dense = densify(res.path, recheck_resolution)
    # Gravity in the base frame: the base may be tilted or hang (SceneSpec.with_base).
    gravity = scene.T_base_world[:3, :3] @ np.array([0.0, 0.0, -scene.spec.gravity])
    jm, ee, tau = trajectory_metrics(scene.robot, dense, force, gravity_base=gravity,
                                     water_density=scene.spec.water_density)
    clearance = (fast or checker).min_clearance(densify(res.path, s.clearance_resolution), ctx)
    metrics = EdgeMetrics(planning_time=res.planning_time_s, joint_movement=jm, ee_distance=ee, security=clearance,
                          max_torque=tau)
    return EdgeResult(planner, src, dst, res, traj, metrics, check)


def metric_tensor(scene: Scene, results: Sequence[EdgeResult]) -> np.ndarray:
    """``(5, N, N)`` raw metrics of the planned edges in ``uvms_jax.sched.METRICS`` order
    (N = goal node + 1), NaN where the move is forbidden or its planning failed: the input of
    ``sched.normalise_metrics``."""
    n = goal_node(scene) + 1
    out = np.full((len(sched.METRICS), n, n), np.nan)
    for r in results:
        if r.success and r.metrics is not None:
            out[:, r.src, r.dst] = tuple(r.metrics)
    return out


def _motion(name: str, traj: Trajectory, jaws_mm: float | None = None) -> planfile.Segment:
    return planfile.Segment(name, tuple(float(x) for x in traj.t),
                            tuple(tuple(float(v) for v in row) for row in traj.q), jaws_mm)


def _gripper(name: str, jaws_mm: float, q, dwell_s: float | None) -> planfile.Segment:
    """A gripper step: the jaws to ``jaws_mm`` [mm]; for an arm without a gripper (``dwell_s``
    given), the arm holding still at ``q (n,)`` [rad] for ``dwell_s`` [s] instead."""
    if dwell_s is None:
        return planfile.Segment(name, (), (), float(jaws_mm))
    q = tuple(float(v) for v in q)
    return planfile.Segment(f"{name} (dwell: no gripper)", (0.0, float(dwell_s)), (q, q))


def gripper_steps(robot, dwell_s: float) -> dict:
    """How ``robot``'s plans take their gripper steps, as ``plan.json``'s ``meta`` and
    ``results.json`` record it: ``{"gripper_steps": "jaws"}``, or for an arm without a gripper
    ``{"gripper_steps": "dwell", "dwell_s": dwell_s}`` (the arm holds still that long [s])."""
    if robot.gripper is not None:
        return {"gripper_steps": "jaws"}
    return {"gripper_steps": "dwell", "dwell_s": float(dwell_s)}


def plan_from_edges(
    scene: Scene,
    targets: Mapping[int, NodeTarget],
    edges: Mapping[tuple[int, int], EdgeResult],
    sequence: Sequence[int],
    *,
    jaws_open_mm: float = 35.0,
    jaws_closed_mm: float = 0.0,
    dwell_s: float = 1.0,
    max_velocity=0.5,
    max_acceleration=1.0,
    checker: CollisionChecker | None = None,
    resolution: float = 0.01,
) -> planfile.Plan:
    """The :class:`uvms_jax.planfile.Plan` of a schedule, from planned edges.

    For every move of ``sequence`` (e.g. ``[0, 2, 5, 4, 8, 0, 1, 6, 3, 7, 9]``) it emits the
    edge's motion, then at an object: ``open``, ``grasp`` (down), ``close``, ``post-grasp``
    (up); at a base: ``final`` (down), ``release`` (open), ``post-final`` (up). Pre-grasp and
    pre-final are the ends of the edge motions. The plan records the scene's base orientation
    (``base_rpy``), so a simulated run of it has the gravity it was planned under. An arm without
    a gripper holds still for ``dwell_s`` at each gripper step instead (a motion segment from
    where it stands to the same point, named ``… (dwell: no gripper)``), which the plan's
    ``meta`` records (:func:`gripper_steps`).

    Args:
      scene, targets: the scene and its node targets.
      edges: ``(src, dst)`` → planned edge.
      sequence: node sequence of the schedule.
      jaws_open_mm, jaws_closed_mm: jaw openings of the open/release and close steps [mm].
      dwell_s: an arm without a gripper's dwell at each gripper step [s].
      max_velocity, max_acceleration: limits of the down/up motions [rad/s, rad/s²].
      checker: when given, the down/up motions are checked at ``resolution`` [rad].

    Raises:
      ValueError: a move of the sequence has no successful edge in ``edges``, or (with a
        ``checker``) a node's down/up motion is not collision-free.
    """
    names = {o.node: o.name for o in scene.spec.objects} | {b.node: b.name for b in scene.spec.bases}
    names |= {START: "start", goal_node(scene): "goal"}
    segments: list[planfile.Segment] = []
    dwell = None if scene.robot.gripper is not None else dwell_s
    for src, dst in zip(sequence[:-1], sequence[1:]):
        e = edges.get((src, dst))
        if e is None or not e.success or e.trajectory is None:
            raise ValueError(f"no successful plan for the move {src} -> {dst}")
        segments.append(_motion(f"{src}->{dst} to {names[dst]}", e.trajectory))
        if dst not in targets:
            continue
        tg = targets[dst]
        down = time_parameterize(np.stack([tg.q_pre, tg.q_at]), max_velocity, max_acceleration)
        up = time_parameterize(np.stack([tg.q_at, tg.q_pre]), max_velocity, max_acceleration)
        if checker is not None:
            ctx = node_contexts(scene, dst)
            for key, tr in (("down", down), ("up", up)):
                if not checker.path_is_valid(tr.q, ctx[key], resolution):
                    raise ValueError(f"node {dst}: the {key} motion collides")
        if dst in scene.objects:
            segments += [_gripper(f"open at {names[dst]}", jaws_open_mm, tg.q_pre, dwell),
                         _motion(f"grasp {names[dst]}", down),
                         _gripper(f"close on {names[dst]}", jaws_closed_mm, tg.q_at, dwell),
                         _motion(f"post-grasp {names[dst]}", up)]
        else:
            segments += [_motion(f"final on {names[dst]}", down),
                         _gripper(f"release on {names[dst]}", jaws_open_mm, tg.q_at, dwell),
                         _motion(f"post-final {names[dst]}", up)]
    return planfile.Plan(scene.robot.joint_names, tuple(segments),
                         base_rpy=tuple(float(v) for v in scene.spec.mount_rpy), arm=scene.robot.record(),
                         meta=gripper_steps(scene.robot, dwell_s))
