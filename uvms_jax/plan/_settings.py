"""Settings of the planning stage: plain frozen dataclasses that mirror ``configs/plan/*.yaml``.

Build them from a config with ``uvms_jax.settings.from_mapping(PlanSettings, d)``; the defaults
are those of ``configs/plan/default.yaml``. Units: s, rad, m.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from uvms_jax import sched
from uvms_jax.plan._planners import check_parameters, ompl_planners
from uvms_jax.plan._planning import PLANNERS

__all__ = ["CHECKERS", "IkSettings", "PlanJsonSettings", "PlanSettings"]

CHECKERS = ("query", "spheres", "mujoco")  # see PlanSettings.checker


def _require(ok: bool, message: str) -> None:
    if not ok:
        raise ValueError(message)


TARGET_SELECTION = ("manipulability", "nearest_start")


@dataclasses.dataclass(frozen=True)
class IkSettings:
    """Batched numerical IK of the pick-and-place targets (:func:`~uvms_jax.plan.pick_place_targets`).

    Attributes:
      n_seeds: IK seeds per tool pose.
      iterations: damped-least-squares iterations per seed.
      n_yaw_continuous: yaws tried for a rotationally symmetric object (cylinder).
      max_branch_jump: largest joint change between the pre and the grasp/final
        configuration [rad].
      select: which of a node's valid target pairs is kept: ``"manipulability"`` (the largest
        w of the pair, the thesis's choice) or ``"nearest_start"`` (the pre configuration
        nearest the start in joint space: one IK branch for every node, so that the moves
        between them stay short — for arms whose joints turn more than a turn or that reach
        a pose in several elbow branches).
    """

    n_seeds: int = 64
    iterations: int = 150
    n_yaw_continuous: int = 8
    max_branch_jump: float = 1.0
    select: str = "manipulability"

    def __post_init__(self):
        _require(self.n_seeds >= 1, f"ik.n_seeds must be >= 1, got {self.n_seeds}")
        _require(self.iterations >= 1, f"ik.iterations must be >= 1, got {self.iterations}")
        _require(self.n_yaw_continuous >= 1, f"ik.n_yaw_continuous must be >= 1, got {self.n_yaw_continuous}")
        _require(self.max_branch_jump > 0, f"ik.max_branch_jump must be > 0 [rad], got {self.max_branch_jump}")
        _require(self.select in TARGET_SELECTION, f"ik.select must be one of {TARGET_SELECTION}, got {self.select!r}")


@dataclasses.dataclass(frozen=True)
class PlanJsonSettings:
    """Which schedule becomes ``plan.json`` and how the gripper moves in it.

    Attributes:
      planner: whose trajectories the plan uses.
      sequence: node sequence of the schedule (default: the thesis's greedy schedule, 4.7).
      jaws_open_mm, jaws_closed_mm: jaw openings of the open/release and close steps [mm].
      dwell_s: an arm without a gripper (a tool changer, a suction cup, no tool) holds still
        this long at each gripper step instead [s].
    """

    planner: str = "RRTConnect"
    sequence: tuple[int, ...] = (0, 2, 5, 4, 8, 0, 1, 6, 3, 7, 9)
    jaws_open_mm: float = 35.0
    jaws_closed_mm: float = 0.0
    dwell_s: float = 1.0

    def __post_init__(self):
        _require(self.planner in ompl_planners(),
                 f"plan_json.planner {self.planner!r} is not an OMPL planner ({', '.join(ompl_planners())})")
        _require(len(self.sequence) >= 2, f"plan_json.sequence needs at least two nodes, got {list(self.sequence)}")
        _require(self.dwell_s > 0, f"plan_json.dwell_s must be > 0 [s], got {self.dwell_s}")


@dataclasses.dataclass(frozen=True)
class PlanSettings:
    """Planning every edge of the pick-and-place task graph (:func:`~uvms_jax.plan.plan_task_graph`).

    Attributes:
      seed: IK seeds (``jax.random.PRNGKey(seed)`` in the experiments) and OMPL's RNG
        (``seed + 1``; one OMPL seed per process, see :func:`~uvms_jax.plan.seed_ompl`).
      planners: OMPL geometric planners run over every edge, in this order (any of
        :func:`~uvms_jax.plan.ompl_planners`; the thesis's three by default).
      planner_params: planner → its parameters (:func:`~uvms_jax.plan.planner_parameters`),
        e.g. ``{"RRTConnect": {"range": 1.0}}``; planners left out keep OMPL's defaults.
      checker: how edges are planned: ``query`` (:func:`~uvms_jax.plan.plan_query` on the
        scene as a world, :func:`~uvms_jax.plan.scene_checker`: ``RRTConnect`` compiled, any
        other planner in OMPL on the same compiled checker; ``planner_params`` and
        ``simplify_s`` not used), or OMPL checking motions with ``spheres`` (one compiled call
        per motion, :class:`~uvms_jax.plan.SphereChecker`, MuJoCo confirming its rejections)
        or with ``mujoco`` (state by state). Every result is re-checked with the scene's
        MuJoCo checker either way.
      budget_s: planning budget per edge, all attempts together [s].
      resolution: the planner's motion-check step [rad].
      recheck_resolution: joint step of the re-check of every result, of the metrics and of
        the IK targets' down/up segments [rad].
      clearance_resolution: joint step of the clearance (security) sampling [rad].
      simplify_s: path simplification time per attempt [s].
      straight_shortcut: return the straight joint-space segment instead of the planner's
        path whenever it is free (fast; the planners then differ only where it is not free).
      margin: safety distance while planning [m]; re-checks use 0.
      clearance_max: clearances above this read as it [m].
      max_velocity, max_acceleration: joint limits of the time parameterisation, one value
        for all joints or one per joint [rad/s, rad/s²]; ``max_velocity`` None: the arm's
        velocity limits (:meth:`joint_velocity`).
      ik: the IK of the targets.
      weights: metric name (``uvms_jax.sched.METRICS``) → weight K of the cost matrix (thesis
        eqs. 4.16–4.17, Table 4.3); a metric left out weighs 0.
      plan_json: the schedule written as ``plan.json``.
      render: whether the experiment renders offscreen frames (not used by the stage).
    """

    seed: int = 0
    planners: tuple[str, ...] = PLANNERS
    planner_params: dict[str, dict[str, float | int | bool]] = dataclasses.field(default_factory=dict)
    checker: str = "query"
    budget_s: float = 5.0
    resolution: float = 0.02
    recheck_resolution: float = 0.01
    clearance_resolution: float = 0.05
    simplify_s: float = 0.2
    straight_shortcut: bool = False
    margin: float = 0.005
    clearance_max: float = 0.3
    max_velocity: float | tuple[float, ...] | None = None
    max_acceleration: float | tuple[float, ...] = 1.0
    ik: IkSettings = IkSettings()
    weights: dict[str, float] = dataclasses.field(default_factory=lambda: {m: 0.2 for m in sched.METRICS})
    plan_json: PlanJsonSettings = PlanJsonSettings()
    render: bool = True

    def __post_init__(self):
        _require(self.seed >= 0, f"seed must be >= 0, got {self.seed}")
        _require(len(self.planners) >= 1, "planners must name at least one planner")
        unknown = [p for p in self.planners if p not in ompl_planners()]
        _require(not unknown, f"unknown planners {unknown} (OMPL's geometric planners: {', '.join(ompl_planners())})")
        for planner, params in self.planner_params.items():
            _require(planner in self.planners, f"planner_params names {planner!r}, which is not in planners "
                                               f"{list(self.planners)}")
            check_parameters(planner, params)
        _require(len(set(self.planners)) == len(self.planners), f"planners repeat: {list(self.planners)}")
        _require(self.checker in CHECKERS, f"checker {self.checker!r} is not one of {CHECKERS}")
        for name in ("budget_s", "resolution", "recheck_resolution", "clearance_resolution", "simplify_s"):
            _require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        _require(0 <= self.margin < self.clearance_max,
                 f"need 0 <= margin < clearance_max, got {self.margin}, {self.clearance_max}")
        for name in ("max_velocity", "max_acceleration"):
            v = getattr(self, name)
            if v is None and name == "max_velocity":
                continue
            _require(all(x > 0 for x in (v if isinstance(v, tuple) else (v,))), f"{name} must be > 0, got {v}")
        unknown = sorted(set(self.weights) - set(sched.METRICS))
        _require(not unknown, f"unknown metrics {unknown} in weights (known: {sched.METRICS})")

    def joint_velocity(self, robot) -> np.ndarray:
        """``(n,)`` the joint speeds of the time parameterisation [rad/s or m/s]: ``max_velocity``,
        or the arm's velocity limits where it is None.

        Raises:
          ValueError: ``max_velocity`` exceeds the arm's limit at some joint (naming them).
        """
        limits = robot.velocity_limits
        if self.max_velocity is None:
            return limits
        v = np.broadcast_to(np.asarray(self.max_velocity, dtype=float), limits.shape)
        over = [f"{name} ({a:g} > {b:g})" for name, a, b in zip(robot.joint_names, v, limits) if a > b * (1 + 1e-9)]
        _require(not over, f"plan max_velocity exceeds the velocity limits of {robot.name!r}: {', '.join(over)}")
        return np.array(v)

    def weight_vector(self) -> tuple[float, ...]:
        """The weights in ``uvms_jax.sched.METRICS`` order (missing metrics 0)."""
        return tuple(float(self.weights.get(m, 0.0)) for m in sched.METRICS)
