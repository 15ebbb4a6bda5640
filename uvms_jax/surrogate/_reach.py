"""A learned dexterity map of an arm on its vehicle, and the docking fitness built on it.

The analytic docking fitness of an arm (:class:`uvms_jax.evo.ArmDockingProblem`) spends
nearly all its time in multi-seed numerical IK: for every vehicle pose and demanded tool pose,
``S`` seeds × a fixed number of DLS iterations. What it extracts per tool pose is the best
manipulability ``w`` over the valid solutions (reached, within the limits, clear of the
vehicle), and that depends only on the tool pose seen from the arm's base: the arm's reach,
its limits and its own vehicle move with it. That function — the index of this arm on this
vehicle over the space of tool poses — is what :class:`ReachMap` learns (an FFBN: tanh hidden
layer, linear output, trained by Adam on normalised data) from the analytic evaluations of
random vehicle poses.

:class:`SurrogateDockingProblem` is then the docking fitness (eq. 15) with ``M_a`` = min over
targets of max over their alternatives of the map, and ``D`` and Wd analytic: a drop-in
problem for the GA (``fitness(pose)``). The scene's obstacles (tables) are not in the map, so
a pose the surrogate chooses is scored again by the analytic fitness, which has them.
"""

from __future__ import annotations

import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct
from jax import Array

from uvms_jax import evo
from uvms_jax.surrogate._adam import fit_adam
from uvms_jax.surrogate._ffbn import MLP, mlp_apply
from uvms_jax.surrogate._scaler import Scaler, fit_scaler
from uvms_jax.surrogate._timing import time_index_fn

__all__ = ["MapDocking", "ReachData", "ReachMap", "ReachMapRun", "ReachMapSettings", "SurrogateDockingProblem",
           "dock_with_map", "fit_reach_map", "reach_dataset", "reach_features", "run_reach_map"]


@dataclasses.dataclass(frozen=True)
class ReachMapSettings:
    """Learning the map (``pipeline.surrogate`` in ``configs/pipeline.yaml``).

    Attributes:
      n_poses: random vehicle poses in the docking box, scored analytically; each gives one
        sample per demanded tool pose.
      test_fraction: share of those poses held out to measure the map's error.
      hidden: tanh units of the FFBN.
      steps, learning_rate: full-batch Adam.
      chunk: vehicle poses per jitted analytic call (bounds memory).
      seed: sampling and initialisation.
      rounds, infill: docking on the map (:func:`dock_with_map`): GA rounds, and the poses
        scored analytically between rounds to refine the map.
    """

    n_poses: int = 1000
    test_fraction: float = 0.2
    hidden: int = 32
    steps: int = 3000
    learning_rate: float = 1e-2
    chunk: int = 128
    seed: int = 0
    rounds: int = 4
    infill: int = 128

    def __post_init__(self):
        if self.n_poses < 10 or not 0 < self.test_fraction < 1 or self.hidden < 1 or self.steps < 1 \
                or not self.learning_rate > 0 or self.chunk < 1 or self.rounds < 1 or self.infill < 1:
            raise ValueError(f"need n_poses >= 10, 0 < test_fraction < 1, hidden >= 1, steps >= 1, "
                             f"learning_rate > 0, chunk >= 1, rounds >= 1, infill >= 1; got {self}")


def reach_features(T_base_tool: Array) -> Array:
    """``(..., 9)`` inputs of the map from tool poses ``(..., 4, 4)`` in the arm's base frame:
    the position [m] and the tool's x and z axes (its approach), which fix the rotation."""
    return jnp.concatenate([T_base_tool[..., :3, 3], T_base_tool[..., :3, 0], T_base_tool[..., :3, 2]], axis=-1)


@struct.dataclass
class ReachMap:
    """Learned best manipulability of the arm at a tool pose seen from its base.

    Attributes:
      params: flax parameters of :class:`uvms_jax.surrogate.MLP` on normalised data.
      x_norm: scaler of the 9 features (:func:`reach_features`).
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
    for the GA, a problem like any other (``fitness``, ``pose_low``, ``pose_high``)."""

    problem: evo.ArmDockingProblem
    reach: ReachMap

    @property
    def pose_low(self) -> Array:
        return self.problem.pose_low

    @property
    def pose_high(self) -> Array:
        return self.problem.pose_high

    def terms(self, pose: Array) -> evo.DockingEval:
        """Objective terms (eq. 1, 3, 14, 15) of vehicle poses ``(..., 4)`` [m, rad]."""
        T_base_tool = evo.arm_tool_poses(self.problem, pose)[2]
        return evo.arm_terms(self.problem, pose, self.reach(T_base_tool)[..., None])

    def fitness(self, pose: Array) -> Array:
        """Fitness of eq. 15 for ``(..., 4)`` vehicle poses (traceable)."""
        return self.terms(pose).fitness


class ReachData(struct.PyTreeNode):
    """Analytic samples of the map.

    Attributes:
      poses: ``(N, 4)`` vehicle poses [m, rad].
      T_base_tool: ``(N, k, 4, 4)`` the demanded tool poses seen from the arm's base.
      w: ``(N, k)`` best w over the valid IK solutions without the scene's obstacles (0: none).
      seconds: wall time of the analytic scoring (compilation excluded) [s].
    """

    poses: Array
    T_base_tool: Array
    w: Array
    seconds: float = struct.field(pytree_node=False)


def _without_scene(problem: evo.ArmDockingProblem) -> evo.ArmDockingProblem:
    """The problem with no scene obstacles: what the arm on its vehicle can do anywhere."""
    dtype = problem.T_world_box.dtype
    return problem.replace(T_world_box=jnp.zeros((0, 4, 4), dtype), scene_half=jnp.zeros((0, 3), dtype),
                           world=problem.world.without_scene())


@jax.jit
def _score(problem: evo.ArmDockingProblem, poses: Array) -> tuple[Array, Array]:
    w = evo.arm_solutions(problem, poses)[2]  # (c, k, S)
    return evo.arm_tool_poses(problem, poses)[2], jnp.max(w, axis=-1)


def reach_dataset(key: Array, problem: evo.ArmDockingProblem, n_poses: int, chunk: int = 128) -> ReachData:
    """Score ``n_poses`` vehicle poses drawn uniformly from the problem's box analytically.

    Args:
      key: PRNG key.
      problem: the analytic docking problem (its obstacles are left out here).
      n_poses: number of vehicle poses; chunk: poses per jitted call.

    Returns:
      :class:`ReachData` (NumPy arrays).
    """
    free = _without_scene(problem)
    dtype = problem.pose_low.dtype
    n = -(-n_poses // chunk) * chunk  # whole chunks: one compilation
    poses = jax.random.uniform(key, (n, 4), dtype, problem.pose_low, problem.pose_high)
    jax.block_until_ready(_score(free, poses[:chunk]))  # compile
    t0 = time.perf_counter()
    parts = [jax.block_until_ready(_score(free, poses[i:i + chunk])) for i in range(0, n, chunk)]
    seconds = time.perf_counter() - t0
    T, w = (np.concatenate([np.asarray(p[j]) for p in parts])[:n_poses] for j in (0, 1))
    return ReachData(np.asarray(poses)[:n_poses], T, w, seconds * n_poses / n)


def fit_reach_map(key: Array, data: ReachData, hidden: int = 32, steps: int = 3000,
                  learning_rate: float = 1e-2, start: ReachMap | None = None) -> tuple[ReachMap, Array]:
    """Train a :class:`ReachMap` on every (tool pose, w) pair of ``data``.

    Args:
      start: go on training this map (its scalers kept) instead of a new one.

    Returns:
      ``(map, history)``: the map and the training mse (normalised units) per Adam step.
    """
    x = reach_features(jnp.asarray(data.T_base_tool)).reshape(-1, 9)
    y = jnp.asarray(data.w).reshape(-1)
    if start is None:
        x_norm, y_norm = fit_scaler(np.asarray(x)), fit_scaler(np.asarray(y), axis=None)
        params = MLP(hidden).init(key, x_norm(x[:1]))["params"]
    else:
        x_norm, y_norm, params = start.x_norm, start.y_norm, start.params
    params, history = fit_adam(mlp_apply, params, x_norm(x), y_norm(y), steps=steps, learning_rate=learning_rate)
    return ReachMap(params, x_norm, y_norm), history


@dataclasses.dataclass(frozen=True)
class ReachMapRun:
    """A learned map and how well it stands for the analytic index.

    Attributes:
      reach: the map.
      settings: how it was learned.
      train: its training samples.
      n_train, n_test: vehicle poses for training and held out (× k tool poses each).
      analytic_seconds: analytic scoring of all poses (compilation excluded) [s].
      train_seconds: Adam training, compilation included [s].
      history: ``(steps + 1,)`` training mse (normalised units).
      test: errors on the held-out poses: ``rmse_w``, ``max_abs_error_w``, ``w_range``,
        ``mae_M_a`` and ``corr_M_a`` (M_a = min over targets of max over alternatives, no
        scene obstacles), and ``n_samples``.
    """

    reach: ReachMap
    settings: ReachMapSettings
    train: ReachData
    n_train: int
    n_test: int
    analytic_seconds: float
    train_seconds: float
    history: np.ndarray
    test: dict


def _area_manipulability(problem: evo.ArmDockingProblem, w: Array) -> np.ndarray:
    """``(N,)`` M_a from one w per tool pose ``(N, k)``."""
    return np.asarray(jnp.min(evo.target_w(problem, jnp.asarray(w)[..., None]), axis=-1))


def run_reach_map(problem: evo.ArmDockingProblem, settings: ReachMapSettings = ReachMapSettings()) -> ReachMapRun:
    """Score random vehicle poses analytically, learn the map on most of them and measure it
    on the rest (the surrogate stage of the end-to-end run)."""
    s = settings
    k_data, k_init = jax.random.split(jax.random.key(s.seed))
    data = reach_dataset(k_data, problem, s.n_poses, s.chunk)
    n_test = max(1, int(round(s.test_fraction * s.n_poses)))
    train, test = (jax.tree_util.tree_map(lambda a: a[sl], data) for sl in (slice(n_test, None), slice(None, n_test)))
    t0 = time.perf_counter()
    reach, history = fit_reach_map(k_init, train, s.hidden, s.steps, s.learning_rate)
    history = np.asarray(jax.block_until_ready(history))
    train_seconds = time.perf_counter() - t0
    w_hat = np.asarray(jax.jit(reach.__call__)(jnp.asarray(test.T_base_tool)))
    err = w_hat - test.w
    M_a, M_a_hat = _area_manipulability(problem, test.w), _area_manipulability(problem, w_hat)
    corr = float(np.corrcoef(M_a, M_a_hat)[0, 1]) if np.std(M_a) > 0 and np.std(M_a_hat) > 0 else float("nan")
    metrics = {"rmse_w": float(np.sqrt(np.mean(err**2))), "max_abs_error_w": float(np.max(np.abs(err))),
               "w_range": float(np.max(data.w)), "mae_M_a": float(np.mean(np.abs(M_a_hat - M_a))),
               "corr_M_a": corr, "n_samples": int(err.size)}
    return ReachMapRun(reach, s, train, s.n_poses - n_test, n_test, data.seconds, train_seconds, history, metrics)


@dataclasses.dataclass(frozen=True)
class MapDocking:
    """GA runs on the learned fitness, each run's best pose scored again analytically.

    Attributes:
      poses: ``(R, 4)`` best pose of each run [m, rad], after the last round.
      map_fitness: ``(R,)`` their fitness on the map.
      fitness, M_a: ``(R,)`` their analytic fitness (eq. 15) and M_a (eq. 1), obstacles included.
      evaluations: ``(R,)`` map evaluations per run, all rounds.
      analytic_evaluations: vehicle poses scored analytically to refine the map between rounds.
      seconds: all rounds, compilation excluded (GA runs, analytic scoring, retraining) [s].
      eval_seconds: time per vehicle pose of the map's fitness on a batch of poses,
        compilation excluded [s].
    """

    poses: np.ndarray
    map_fitness: np.ndarray
    fitness: np.ndarray
    M_a: np.ndarray
    evaluations: np.ndarray
    analytic_evaluations: int
    seconds: float
    eval_seconds: float

    @property
    def best(self) -> int:
        """Index of the run whose pose is best by the analytic fitness."""
        return int(np.argmax(self.fitness))


def _best_of_populations(learned: SurrogateDockingProblem, codec, res, m: int) -> Array:
    """``(m, 4)`` the best distinct poses by map fitness of all runs' final populations (the
    best repeated if there are fewer than ``m``: one shape, one compilation)."""
    poses = jax.vmap(codec.decode)(res.state.population.reshape(-1, res.state.population.shape[-1]))
    fit = np.asarray(learned.fitness(poses))
    _, first = np.unique(np.asarray(poses), axis=0, return_index=True)
    order = first[np.argsort(-fit[first])][:m]
    return poses[np.resize(order, m)]


def dock_with_map(problem: evo.ArmDockingProblem, run: ReachMapRun, ga: evo.GASettings, n_runs: int, seed: int,
                  rounds: int = 4, infill: int = 128, timing_batch: int = 128) -> MapDocking:
    """Dock on the learned fitness, refining the map where the GA looks.

    Each round runs the GA ``n_runs`` times on :class:`SurrogateDockingProblem` (the same GA
    settings as the analytic runs); before the next round, the ``infill`` best distinct poses of
    the final populations are scored analytically, join the training samples and the map trains
    on (the map is least reliable exactly where its optimum lies). Each run's final best pose is
    scored analytically; the map's fitness is timed on ``timing_batch`` random poses.
    """
    if rounds < 1 or infill < 1:
        raise ValueError(f"need rounds >= 1 and infill >= 1, got {rounds}, {infill}")
    s = run.settings
    free = _without_scene(problem)
    reach, data = run.reach, run.train
    learned = SurrogateDockingProblem(problem, reach)
    codec, ga_, params = evo.make_ga(ga, learned)
    keys = jax.random.split(jax.random.key(seed), n_runs)
    ga_run = evo.ga_batch_compiled(keys, learned, codec, ga_, params)
    evaluations, n_infill, seconds = 0, 0, 0.0
    for r in range(rounds):
        t0 = time.perf_counter()
        res = jax.block_until_ready(ga_run(keys, learned, codec, params))
        evaluations = evaluations + np.asarray(res.evaluations)
        seconds += time.perf_counter() - t0
        if r == rounds - 1:
            break
        t0 = time.perf_counter()
        poses = _best_of_populations(learned, codec, res, infill)
        T, w = (np.asarray(a) for a in _score(free, poses))
        n_infill += len(poses)
        data = ReachData(np.concatenate([data.poses, np.asarray(poses)]), np.concatenate([data.T_base_tool, T]),
                         np.concatenate([data.w, w]), data.seconds)
        reach, _ = fit_reach_map(jax.random.key(seed), data, steps=max(1, s.steps // 3),
                                 learning_rate=s.learning_rate, start=reach)
        learned = SurrogateDockingProblem(problem, reach)
        keys = jax.random.split(keys[0], n_runs)
        seconds += time.perf_counter() - t0
    poses = np.asarray(res.best_x)
    terms = evo.arm_report(problem, poses).terms
    sample = jax.random.uniform(jax.random.key(seed + 1), (timing_batch, 4), problem.pose_low.dtype, problem.pose_low, problem.pose_high)
    eval_seconds = time_index_fn(learned.fitness, sample, repeats=3)["seconds"] / timing_batch
    return MapDocking(poses, np.asarray(res.best_fitness), np.asarray(terms.fitness), np.asarray(terms.M_a),
                      evaluations, n_infill, seconds, eval_seconds)
