"""A learned dexterity map of an arm on its vehicle, and docking that keeps the optimum with it.

The analytic docking fitness of an arm (:class:`uvms_jax.evo.ArmDockingProblem`) spends
nearly all its time in multi-seed numerical IK: for every vehicle pose and demanded tool pose,
``S`` seeds × a fixed number of DLS iterations. What it extracts per tool pose is the best
manipulability ``w`` over the valid solutions (reached, within the limits, clear of the
vehicle), and without the scene's obstacles that depends only on the tool pose seen from the
arm's base: the arm's reach, its limits and its own vehicle move with it. That function is
what :class:`ReachMap` learns (an FFBN: tanh hidden layer, linear output, trained by Adam on
normalised data), from tool poses sampled in the arm's base frame (:func:`reach_dataset`):
positions the arm reaches (forward kinematics of random joint angles, jittered), approaches
within a cone about the world's downward vertical (grasps from above; the vehicle only yaws,
so that cone is fixed in the base frame). The samples use the arm, its mount, the vehicle's
body and the IK settings, never the task or the scene: one map serves every task of the arm
on that vehicle.

:func:`dock_with_map` then docks in three steps, only the last two of which evaluate the
analytic fitness: the GA runs on :class:`SurrogateDockingProblem` (eq. 15 with ``M_a`` from
the map, ``D`` and Wd analytic) and proposes; the best distinct poses of its final populations
are scored analytically (the scene's obstacles, which the map does not know, included); from
the best of them a trust-region refinement alternates a search on the map corrected to the
analytic w of the current pose (tool pose by tool pose) with one analytic evaluation of what
that search finds. The map's error is largest exactly where its optimum lies (the apex where
the targets' w meet, which a min over targets turns into the map's worst error); corrected at
the current pose, it is right there and keeps its slope around it.
"""

from __future__ import annotations

import dataclasses
import functools
import time

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array

from uvms_jax import evo, kin
from uvms_jax.settings import check_fields, setting
from uvms_jax.surrogate._adam import fit_adam
from uvms_jax.surrogate._ffbn import MLP, mlp_apply
from uvms_jax.surrogate._scaler import Scaler, fit_scaler
from uvms_jax.surrogate._timing import time_index_fn

__all__ = ["MapDocking", "ReachData", "ReachMap", "ReachMapRun", "ReachMapSettings", "SurrogateDockingProblem",
           "dock_with_map", "fit_reach_map", "reach_dataset", "reach_features", "run_reach_map"]

REFINE_COUNTS = (3, 3, 3, 3)  # a zoom stage on the corrected map: the 3^4 points of a box about its best


@dataclasses.dataclass(frozen=True)
class ReachMapSettings:
    """Learning the map and docking with it (``reach`` in ``configs/pipeline.yaml``).

    Attributes:
      n_samples: tool poses sampled in the arm's base frame, each scored analytically once.
      approach_cone_deg: largest angle of a sampled tool z axis (the approach) from the
        world's downward vertical [deg]; a task whose targets lie outside is refused.
      position_noise_m: std of the jitter added to the reached positions [m] (the map also
        learns where the reach ends).
      test_fraction: share of the samples held out to measure the map's error.
      hidden: tanh units of the FFBN.
      steps, learning_rate: full-batch Adam.
      chunk: tool poses per jitted analytic call (bounds memory).
      seed: sampling and initialisation.
      candidates: best distinct poses of the GA on the map scored analytically.
      refine_iterations: trust-region steps from the best of them, one analytic evaluation
        each at most.
      refine_stages: zoom stages of each step's search on the corrected map (81 poses each).
      refine_width: the trust region as a fraction of the pose box; halved after a step that
        does not improve the analytic fitness.
    """

    n_samples: int = setting(32768, ge=10)
    approach_cone_deg: float = setting(30.0, gt=0, le=180)
    position_noise_m: float = setting(0.03, ge=0)
    test_fraction: float = setting(0.1, gt=0, lt=1)
    hidden: int = setting(128, ge=1)
    steps: int = setting(6000, ge=1)
    learning_rate: float = setting(1e-2, gt=0)
    chunk: int = setting(256, ge=1)
    seed: int = 0
    candidates: int = setting(16, ge=1)
    refine_iterations: int = setting(24, ge=0)
    refine_stages: int = setting(6, ge=1)
    refine_width: float = setting(0.25, gt=0, le=1)

    def __post_init__(self):
        check_fields(self)


def reach_features(T_base_tool: Array) -> Array:
    """``(..., 10)`` inputs of the map from tool poses ``(..., 4, 4)`` in the arm's base frame:
    the distance from the base's z axis and the height [m], the azimuth's cosine and sine, and
    the tool's x and z axes turned by minus the azimuth. The first joint turns the arm about
    that axis, so w hardly depends on the azimuth but for the vehicle's body: the features
    make the function smooth where raw coordinates would make it wind."""
    p = T_base_tool[..., :3, 3]
    r = jnp.hypot(p[..., 0], p[..., 1])
    azimuth = jnp.arctan2(p[..., 1], p[..., 0])
    c, s = jnp.cos(azimuth), jnp.sin(azimuth)

    def unturn(v):  # the axis seen from the vertical plane through the tool's position
        return jnp.stack([c * v[..., 0] + s * v[..., 1], c * v[..., 1] - s * v[..., 0], v[..., 2]], axis=-1)

    return jnp.concatenate([jnp.stack([r, p[..., 2], c, s], axis=-1), unturn(T_base_tool[..., :3, 0]),
                            unturn(T_base_tool[..., :3, 2])], axis=-1)


@struct.dataclass
class ReachMap:
    """Learned best manipulability of the arm at a tool pose seen from its base.

    Attributes:
      params: flax parameters of :class:`uvms_jax.surrogate.MLP` on normalised data.
      x_norm: scaler of the 10 features (:func:`reach_features`).
      y_norm: scaler of w.
    """

    params: dict
    x_norm: Scaler
    y_norm: Scaler

    def __call__(self, T_base_tool: Array) -> Array:
        """``(...)`` predicted w at tool poses ``(..., 4, 4)`` (base frame, m)."""
        x = self.x_norm(reach_features(T_base_tool))
        return self.y_norm.inverse(mlp_apply(self.params, x))


@struct.dataclass
class SurrogateDockingProblem:
    """The docking problem with the IK part replaced by a :class:`ReachMap` (module docstring);
    for the GA, a problem like any other (``fitness``, ``pose_low``, ``pose_high``).

    Attributes:
      problem: the analytic problem (task, D, Wd).
      reach: the map.
      shift: ``(k,)`` added to the map's w of each demanded tool pose: 0 for the map alone, the
        analytic w minus the map's at a pose for the map corrected there.
    """

    problem: evo.ArmDockingProblem
    reach: ReachMap
    shift: Array

    @property
    def pose_low(self) -> Array:
        return self.problem.pose_low

    @property
    def pose_high(self) -> Array:
        return self.problem.pose_high

    def terms(self, pose: Array) -> evo.DockingEval:
        """Objective terms (eq. 1, 3, 14, 15) of vehicle poses ``(..., 4)`` [m, rad]."""
        T_base_tool = evo.arm_tool_poses(self.problem, pose)[2]
        return evo.arm_terms(self.problem, pose, (self.reach(T_base_tool) + self.shift)[..., None])

    def fitness(self, pose: Array) -> Array:
        """Fitness of eq. 15 for ``(..., 4)`` vehicle poses (traceable)."""
        return self.terms(pose).fitness


class ReachData(struct.PyTreeNode):
    """Analytic samples of the map.

    Attributes:
      T_base_tool: ``(N, 4, 4)`` tool poses in the arm's base frame [m].
      w: ``(N,)`` best w over the valid IK solutions, vehicle included, no scene (0: none).
      seconds: wall time of the analytic scoring (compilation excluded) [s].
    """

    T_base_tool: Array
    w: Array
    seconds: float = struct.field(pytree_node=False)


def _world_down_in_base(problem: evo.ArmDockingProblem) -> Array:
    """``(3,)`` the world's downward vertical in the arm's base frame (the same at every vehicle
    pose: the vehicle only yaws about the vertical)."""
    return problem.T_vehicle_base[:3, :3].T @ jnp.asarray([0.0, 0.0, -1.0], problem.T_vehicle_base.dtype)


# One compiled program: run op by op, the sampler's ~40 operations each compiled a program of
# their own on a cold start (~0.1 s each on a CPU).
@functools.partial(jax.jit, static_argnames=("n",))
def _sample_tool_poses(key: Array, problem: evo.ArmDockingProblem, n: int, cone_deg: float, noise: float) -> Array:
    """``(n, 4, 4)`` tool poses in the base frame. Positions: half reached (FK of joint angles
    uniform in the limits, jittered by ``noise`` m), half uniform in the ball of 1.25 × the
    farthest of those about the base (without them the map extrapolates beyond the reach, and an
    optimistic w there is what a min over targets picks). Tool z within ``cone_deg`` of the
    world's downward vertical (uniform over the cap), roll about it uniform."""
    k_q, k_n, k_b, k_u, k_p = jax.random.split(key, 5)
    chain, dtype = problem.chain, problem.T_vehicle_base.dtype
    q = jax.random.uniform(k_q, (n - n // 2, chain.n_joints), dtype, chain.lower, chain.upper)
    reached = kin.kinematics(chain, q).T_base_tool[:, :3, 3]
    reached = reached + noise * jax.random.normal(k_n, reached.shape, dtype)
    k_d, k_r = jax.random.split(k_b)
    d = jax.random.normal(k_d, (n // 2, 3), dtype)
    radius = 1.25 * jnp.max(jnp.linalg.norm(reached, axis=-1)) * jax.random.uniform(k_r, (n // 2, 1), dtype) ** (1 / 3)
    p = jnp.concatenate([reached, radius * d / jnp.linalg.norm(d, axis=-1, keepdims=True)])
    p = jax.random.permutation(k_p, p)  # any slice (the held-out one) draws from both halves
    u = jax.random.uniform(k_u, (n, 3), dtype)
    cos_t = 1.0 - u[:, 0] * (1.0 - jnp.cos(jnp.radians(cone_deg)))
    sin_t, phi, roll = jnp.sqrt(1.0 - cos_t**2), 2 * jnp.pi * u[:, 1], 2 * jnp.pi * u[:, 2]
    down = _world_down_in_base(problem)
    # An orthonormal frame (e1, e2, down) in the base frame; the tool's z axis in the cap about `down`.
    helper = jnp.where(jnp.abs(down[0]) < 0.9, jnp.asarray([1.0, 0.0, 0.0], dtype), jnp.asarray([0.0, 1.0, 0.0], dtype))
    e1 = jnp.cross(down, helper)
    e1 = e1 / jnp.linalg.norm(e1)
    e2 = jnp.cross(down, e1)
    z = (sin_t * jnp.cos(phi))[:, None] * e1 + (sin_t * jnp.sin(phi))[:, None] * e2 + cos_t[:, None] * down
    a = jnp.cos(roll)[:, None] * e1 + jnp.sin(roll)[:, None] * e2
    x = a - jnp.sum(a * z, axis=-1, keepdims=True) * z
    x = x / jnp.linalg.norm(x, axis=-1, keepdims=True)
    R = jnp.stack([x, jnp.cross(z, x), z], axis=-1)
    return jnp.concatenate([jnp.concatenate([R, p[:, :, None]], axis=-1),
                            jnp.broadcast_to(jnp.asarray([0.0, 0.0, 0.0, 1.0], dtype), (n, 1, 4))], axis=-2)


@jax.jit
def _best_w(problem: evo.ArmDockingProblem, T_base_tool: Array) -> Array:
    """``(c,)`` best w of tool poses ``(c, 4, 4)`` in the base frame, by the analytic fitness's own
    IK and checks: the poses are the task of the vehicle at the origin, with no scene."""
    dtype, c = T_base_tool.dtype, T_base_tool.shape[0]
    # The world's rows are per target context (what a target holds or ignores); a sampled tool
    # pose has none, so every one tests the first target's row, with the scene switched off.
    world = problem.world.without_scene()
    world = world.replace(rows=jax.tree.map(lambda a: a[:1], world.rows))
    at_origin = problem.replace(T_world_tool=kin.matmul(problem.T_vehicle_base, T_base_tool),
                                group=jnp.zeros((c,), jnp.int32), n_groups=1, world=world,
                                T_world_box=jnp.zeros((0, 4, 4), dtype), scene_half=jnp.zeros((0, 3), dtype))
    return jnp.max(evo.arm_solutions(at_origin, jnp.zeros((4,), dtype))[2], axis=-1)


def reach_dataset(key: Array, problem: evo.ArmDockingProblem, n_samples: int, approach_cone_deg: float = 30.0,
                  position_noise_m: float = 0.03, chunk: int = 256) -> ReachData:
    """Sample ``n_samples`` tool poses in the arm's base frame (module docstring) and score each
    analytically.

    Args:
      key: PRNG key.
      problem: supplies the arm, its mount, the vehicle's body and the IK settings; its task and
        scene are not used.
      n_samples: tool poses; chunk: tool poses per jitted call.
      approach_cone_deg, position_noise_m: see :class:`ReachMapSettings`.

    Returns:
      :class:`ReachData` (NumPy arrays).
    """
    n = -(-n_samples // chunk) * chunk  # whole chunks: one compilation
    T = _sample_tool_poses(key, problem, n, approach_cone_deg, position_noise_m)
    jax.block_until_ready(_best_w(problem, T[:chunk]))  # compile
    t0 = time.perf_counter()
    w = np.concatenate([np.asarray(jax.block_until_ready(_best_w(problem, T[i:i + chunk]))) for i in range(0, n, chunk)])
    seconds = time.perf_counter() - t0
    return ReachData(np.asarray(T)[:n_samples], w[:n_samples], seconds * n_samples / n)


def fit_reach_map(key: Array, data: ReachData, hidden: int = 128, steps: int = 6000,
                  learning_rate: float = 1e-2) -> tuple[ReachMap, Array]:
    """Train a :class:`ReachMap` on every (tool pose, w) pair of ``data``.

    Returns:
      ``(map, history)``: the map and the training mse (normalised units) per Adam step.
    """
    x = reach_features(jnp.asarray(data.T_base_tool))
    y = jnp.asarray(data.w)
    x_norm, y_norm = fit_scaler(np.asarray(x)), fit_scaler(np.asarray(y), axis=None)
    params = MLP(hidden).init(key, x_norm(x[:1]))["params"]
    params, history = fit_adam(mlp_apply, params, x_norm(x), y_norm(y), steps=steps, learning_rate=learning_rate)
    return ReachMap(params, x_norm, y_norm), history


@dataclasses.dataclass(frozen=True)
class ReachMapRun:
    """A learned map and how well it stands for the analytic w.

    Attributes:
      reach: the map.
      settings: how it was learned.
      n_train, n_test: tool poses for training and held out.
      analytic_seconds: analytic scoring of all samples (compilation excluded) [s].
      train_seconds: Adam training, compilation included [s].
      history: ``(steps + 1,)`` training mse (normalised units).
      test: errors on the held-out tool poses: ``rmse_w``, ``max_abs_error_w``, ``w_range``
        (the largest w sampled), ``w_std`` (the held-out w's spread: the rmse of predicting
        their mean), ``reached_fraction`` (share of all samples with w > 0), ``n_samples``.
    """

    reach: ReachMap
    settings: ReachMapSettings
    n_train: int
    n_test: int
    analytic_seconds: float
    train_seconds: float
    history: np.ndarray
    test: dict


def run_reach_map(problem: evo.ArmDockingProblem, settings: ReachMapSettings = ReachMapSettings()) -> ReachMapRun:
    """Sample and score tool poses in the arm's base frame, learn the map on most of them and
    measure it on the rest (the surrogate stage of the end-to-end run)."""
    s = settings
    k_data, k_init = jax.random.split(jax.random.key(s.seed))
    data = reach_dataset(k_data, problem, s.n_samples, s.approach_cone_deg, s.position_noise_m, s.chunk)
    n_test = max(1, int(round(s.test_fraction * s.n_samples)))
    train, test = (jax.tree_util.tree_map(lambda a: a[sl], data) for sl in (slice(n_test, None), slice(None, n_test)))
    t0 = time.perf_counter()
    reach, history = fit_reach_map(k_init, train, s.hidden, s.steps, s.learning_rate)
    history = np.asarray(jax.block_until_ready(history))
    train_seconds = time.perf_counter() - t0
    err = np.asarray(jax.jit(reach.__call__)(jnp.asarray(test.T_base_tool))) - test.w
    metrics = {"rmse_w": float(np.sqrt(np.mean(err**2))), "max_abs_error_w": float(np.max(np.abs(err))),
               "w_range": float(np.max(data.w)), "w_std": float(np.std(test.w)),
               "reached_fraction": float(np.mean(data.w > 0)),
               "n_samples": int(err.size)}
    return ReachMapRun(reach, s, s.n_samples - n_test, n_test, data.seconds, train_seconds, history, metrics)


@dataclasses.dataclass(frozen=True)
class MapDocking:
    """Docking with the map: the GA on it proposes, the analytic fitness confirms and refines.

    Attributes:
      candidates: ``(K, 4)`` the best distinct poses of the GA on the map [m, rad].
      candidate_map_fitness, candidate_fitness: ``(K,)`` their fitness on the map and analytic.
      pose: ``(4,)`` the refined best pose [m, rad]; fitness, M_a: its analytic eq. 15 and eq. 1
        (the scene's obstacles included).
      refine_fitness: ``(refine_iterations + 1,)`` analytic best before and after each step.
      map_evaluations: vehicle poses the GA runs scored on the map.
      analytic_evaluations: vehicle poses scored analytically (candidates + refinement).
      seconds: GA on the map (compiled before), candidates and refinement (their compilation
        included) [s].
      eval_seconds: time per vehicle pose of the map's fitness on a batch, compilation excluded [s].
    """

    candidates: np.ndarray
    candidate_map_fitness: np.ndarray
    candidate_fitness: np.ndarray
    pose: np.ndarray
    fitness: float
    M_a: float
    refine_fitness: np.ndarray
    map_evaluations: int
    analytic_evaluations: int
    seconds: float
    eval_seconds: float


def _check_approaches(problem: evo.ArmDockingProblem, cone_deg: float) -> None:
    """Refuse a task with a demanded approach outside the cone the map was sampled in."""
    z = np.asarray(problem.T_world_tool[:, :3, 2], dtype=np.float64)
    angle = np.degrees(np.arccos(np.clip(-z[:, 2], -1.0, 1.0)))
    if np.any(angle > cone_deg + 1e-6):
        i = int(np.argmax(angle))
        raise ValueError(f"demanded tool pose {i} approaches {angle[i]:.1f}° from the downward vertical, outside the "
                         f"map's sampled cone of {cone_deg}°: raise reach.approach_cone_deg")


@jax.jit
def _map_w(learned: SurrogateDockingProblem, pose: Array) -> Array:
    """``(..., k)`` the map's w (without shift) of the demanded tool poses at vehicle poses ``(..., 4)``."""
    return learned.reach(evo.arm_tool_poses(learned.problem, pose)[2])


def _refine(problem: evo.ArmDockingProblem, reach: ReachMap, x: np.ndarray, report: evo.ArmReport,
            s: ReachMapSettings, chunk: int) -> tuple[np.ndarray, evo.ArmReport, np.ndarray, int]:
    """Trust-region refinement from pose ``x (4,)`` with its analytic ``report`` (fields of shape
    ``(1, ...)``): correct the map to the analytic w at ``x``, zoom on the corrected map inside
    the trust region (``chunk`` poses per evaluation), score its best analytically; keep it if
    better, else halve the region. Returns the best pose, its report, the analytic best per step
    and the analytic evaluations."""
    width = np.asarray(problem.pose_high - problem.pose_low) * s.refine_width
    periodic = evo.grid_periodicity(problem)
    learned = SurrogateDockingProblem(problem, reach, jnp.zeros_like(problem.group, dtype=problem.pose_low.dtype))
    history, evaluations = [float(report.terms.fitness[0])], 0
    for _ in range(s.refine_iterations):
        corrected = learned.replace(shift=jnp.asarray(report.w[0]) - _map_w(learned, jnp.asarray(x)))
        # The corrected map equals the analytic fitness at x: its search moves only to a pose it predicts better.
        zoom = evo.zoom_from(corrected, x[None], report.terms.fitness, problem.pose_low, problem.pose_high,
                             REFINE_COUNTS, s.refine_stages, 0.5, periodic, width=width,
                             chunk_size=chunk)
        if np.array_equal(zoom.x[0], x):
            width = width / 2
        else:
            trial = evo.arm_report(problem, zoom.x)
            evaluations += 1
            if trial.terms.fitness[0] > report.terms.fitness[0]:
                x, report = zoom.x[0], trial
            else:
                width = width / 2
        history.append(float(report.terms.fitness[0]))
    return x, report, np.asarray(history), evaluations


def dock_with_map(problem: evo.ArmDockingProblem, run: ReachMapRun, ga: evo.GASettings, n_runs: int, seed: int,
                  timing_batch: int = 128) -> MapDocking:
    """The map proposes, the analytic fitness confirms (module docstring).

    ``n_runs`` GA runs on :class:`SurrogateDockingProblem` (the analytic runs' GA settings);
    the ``run.settings.candidates`` best poses of their final populations by map fitness, no
    two closer than a sixteenth of the pose box along every variable, are scored analytically;
    ``refine_iterations`` trust-region steps refine the best of them (:func:`_refine`). The
    map's fitness is timed on ``timing_batch`` random poses.

    Raises:
      ValueError: a target's approach outside the map's sampled cone.
    """
    s = run.settings
    _check_approaches(problem, s.approach_cone_deg)
    learned = SurrogateDockingProblem(problem, run.reach, jnp.zeros_like(problem.group, dtype=problem.pose_low.dtype))
    codec, ga_, params = evo.make_ga(ga, learned)
    keys = jax.random.split(jax.random.key(seed), n_runs)
    ga_run = evo.ga_batch_compiled(keys, learned, codec, ga_, params)
    t0 = time.perf_counter()
    res = jax.block_until_ready(ga_run(keys, learned, codec, params))
    poses = np.asarray(jax.vmap(codec.decode)(res.state.population.reshape(-1, res.state.population.shape[-1])))
    poses = np.concatenate([poses, np.asarray(res.best_x)])
    map_fit = np.asarray(jax.jit(learned.fitness)(poses))
    pick = evo.distinct_best(poses, map_fit, s.candidates, np.asarray(problem.pose_high - problem.pose_low) / 16)
    # One batch shape for the analytic scoring (the best repeated): one compilation.
    candidates = poses[np.resize(pick, s.candidates)]
    scored = evo.arm_report(problem, candidates)
    best = int(np.argmax(scored.terms.fitness))
    start = jax.tree_util.tree_map(lambda a: a[best:best + 1], scored)
    # The zoom in chunks of the GA's evaluation: with ga.host_loop one compiled map fitness serves both.
    chunk = ga.eval_chunk if ga.host_loop else int(np.prod(REFINE_COUNTS))
    pose, report, history, n_refine = _refine(problem, run.reach, candidates[best], start, s, chunk)
    seconds = time.perf_counter() - t0
    sample = jax.random.uniform(jax.random.key(seed + 1), (timing_batch, 4), problem.pose_low.dtype,
                                problem.pose_low, problem.pose_high)
    eval_seconds = time_index_fn(learned.fitness, sample, repeats=3)["seconds"] / timing_batch
    return MapDocking(candidates[:len(pick)], map_fit[pick], np.asarray(scored.terms.fitness)[:len(pick)], pose,
                      float(report.terms.fitness[0]), float(report.terms.M_a[0]), history, int(np.sum(res.evaluations)),
                      s.candidates + n_refine, seconds, eval_seconds)
