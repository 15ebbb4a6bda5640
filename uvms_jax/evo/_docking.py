"""The docking run as one stage: GA runs, grid reference, CMA-ES, w_max maps, pose checks.

:func:`run_docking` computes everything (docking paper Tables 2–3, Figs 9–10) and returns a
:class:`DockingRun`; :func:`uvms_jax.evo.write_docking` turns it into files and plots.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import time

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax import progress
from uvms_jax.settings import parameters
from uvms_jax.evo._binary import BinaryCodec, make_codec
from uvms_jax.evo._cmaes import run_cmaes
from uvms_jax.evo._ga import BinaryGA, GAParams, ga_batch_compiled, run_ga
from uvms_jax.evo._grid import distinct_best, grid_search, refine_grid_search, zoom_from
from uvms_jax.evo._arm import ArmDockingProblem, ArmReport, arm_report, evaluate_arm
from uvms_jax.evo._fitness import Problem
from uvms_jax.evo._problem import DockingProblem, docking_point, evaluate, make_docking_problem
from uvms_jax.evo._scenes import ArmTask, arm_docking_problem
from uvms_jax.evo._settings import FIELDS, ArmSceneSettings, DockingSettings, GASettings, SceneSettings, term_weights
from uvms_jax.evo._wmax import WmaxMap, wmax_map

log = logging.getLogger(__name__)

PERIODIC = (False, False, False, True)  # ψ wraps: the grid does not sample −π and π twice

def docking_problem(scene: SceneSettings | ArmSceneSettings, dtype: str = "float32",
                    task: ArmTask | None = None, robot=None) -> Problem:
    """The problem of a scene: :func:`make_docking_problem` for the paper's
    :class:`SceneSettings`, :func:`arm_docking_problem` (with ``task``, and the arm ``robot``
    when given, else the scene's) for an :class:`ArmSceneSettings`.

    Raises:
      ValueError: a task given for the paper's scene (its task area is part of the scene).
    """
    if isinstance(scene, ArmSceneSettings):
        return arm_docking_problem(scene, task, jnp.dtype(dtype), robot)
    if task is not None:
        raise ValueError("the paper's scene has its own task area: pass a task only with an arm scene")
    plain = {f.name: getattr(scene, f.name) for f in dataclasses.fields(scene) if f.name != "terms"}
    return make_docking_problem(**plain, terms=term_weights(scene.terms), dtype=jnp.dtype(dtype))


def evaluate_any(problem: Problem, pose):
    """:func:`evaluate` or :func:`evaluate_arm`, by the problem's kind."""
    return evaluate_arm(problem, pose) if isinstance(problem, ArmDockingProblem) else evaluate(problem, pose)


def grid_periodicity(problem: Problem) -> tuple[bool, ...]:
    """Grid periodicity: ψ wraps when its range is a full turn."""
    full = bool(np.isclose(float(problem.pose_high[3] - problem.pose_low[3]), 2 * np.pi, atol=1e-5))
    return (False, False, False, full)


def make_ga(settings: GASettings, problem: Problem) -> tuple[BinaryCodec, BinaryGA, GAParams]:
    """Codec over the problem's box, static GA sizes and hyperparameters from the settings."""
    s = settings
    codec = make_codec(problem.pose_low, problem.pose_high, [getattr(s.bits, f) for f in FIELDS], gray=s.gray)
    return codec, parameters(BinaryGA, s, n_bits=codec.n_bits), parameters(GAParams, s)


@dataclasses.dataclass(frozen=True)
class GridOptimum:
    """Best grid point: ``pose (4,)`` [m, rad], fitness (eq. 15), M_a (eq. 1), D (eq. 3) [m],
    grid points evaluated and wall time [s]."""

    pose: np.ndarray
    fitness: float
    M_a: float
    D: float
    candidates: int
    seconds: float


@dataclasses.dataclass(frozen=True)
class CMAESRuns:
    """CMA-ES runs: best ``poses (R, 4)``, ``fitness (R,)``, ``history (R, generations)``,
    batch wall time [s] after compilation, and evaluations per run."""

    poses: np.ndarray
    fitness: np.ndarray
    history: np.ndarray
    seconds: float
    evaluations_per_run: int


@dataclasses.dataclass(frozen=True)
class PoseMap:
    """The w_max map (eq. 16) of one docking pose ``(4,)`` and the pose's M_a (eq. 1)."""

    pose: np.ndarray
    map: WmaxMap
    M_a: float


@dataclasses.dataclass(frozen=True)
class BestPose:
    """A run's best pose, of its GA runs and its grid search together.

    Attributes:
      pose: ``(4,)`` ``[x, y, z, ψ]`` [m, rad]; fitness (eq. 15) and M_a (eq. 1) there.
      source: who found it, ``"analytic GA"`` or ``"grid search"`` (ties go to the GA).
      ik: an arm scene's best IK solution per demanded tool pose at ``pose``
        (:class:`~uvms_jax.evo.ArmReport`); None for the paper scene.
    """

    pose: np.ndarray
    fitness: float
    M_a: float
    source: str
    ik: ArmReport | None


@dataclasses.dataclass(frozen=True)
class DockingRun:
    """Everything a docking run found (arrays are NumPy; R = ``settings.n_runs``).

    Attributes:
      settings: the settings of the run.
      problem: the problem it solved (scene, task and objective; a pytree).
      poses: ``(R, 4)`` best pose ``[x, y, z, ψ]`` of each GA run [m, rad].
      fitness, M_a: ``(R,)`` their fitness (eq. 15) and area manipulability (eq. 1).
      generations, evaluations: ``(R,)`` generations and fitness evaluations per run.
      histories: per run, best fitness per generation, ``(generations[r],)``.
      run_seconds: ``(R,)`` time of each run alone, or the batch time for each.
      ga_batch_seconds: all R runs in one call, after compilation [s].
      ga_compile_seconds: compilation and the first batch [s].
      grid, refined_grid: the dense grid's optimum and its polish by zoom stages.
      refine_stage_fitness: best fitness after each zoom stage.
      candidates, candidate_fitness: ``(K, 4)`` the distinct local optima the polish found
        (best first; K ≤ ``grid.refine_starts``) and ``(K,)`` their fitness: the docking
        poses to compare further, e.g. hovering (:func:`uvms_jax.hover.batch_candidates`).
      cmaes: the CMA-ES baseline, or None when disabled.
      wmax_best: w_max map of the best GA pose (paper scene; None for an arm scene). The
        paper's ill-placed pose (Fig. 10) is mapped beside it by :mod:`uvms_jax.papers.docking`.
      pose_checks: per GA run, where its pose lies (see :func:`pose_checks`; paper scene,
        empty for an arm scene).
      best: the run's best pose, of the GA runs and the grid search (:class:`BestPose`).
      load_average, device: machine state at the end of the run.
    """

    settings: DockingSettings
    problem: Problem
    poses: np.ndarray
    fitness: np.ndarray
    M_a: np.ndarray
    generations: np.ndarray
    evaluations: np.ndarray
    histories: tuple[np.ndarray, ...]
    run_seconds: tuple[float, ...]
    ga_batch_seconds: float
    ga_compile_seconds: float
    grid: GridOptimum
    refined_grid: GridOptimum
    refine_stage_fitness: tuple[float, ...]
    candidates: np.ndarray
    candidate_fitness: np.ndarray
    cmaes: CMAESRuns | None
    wmax_best: PoseMap | None
    pose_checks: tuple[dict, ...]
    best: BestPose
    load_average: tuple[float, float, float]
    device: str

    @property
    def ga_ratio_to_grid(self) -> np.ndarray:
        """``(R,)`` GA best fitness / grid optimum."""
        return self.fitness / self.grid.fitness

    @property
    def ga_ratio_to_refined_grid(self) -> np.ndarray:
        return self.fitness / self.refined_grid.fitness

    @property
    def ga_evaluations_per_second(self) -> float:
        """Fitness evaluations of all GA runs per second of the batch."""
        return float(np.sum(self.evaluations)) / self.ga_batch_seconds

    @property
    def all_face_task_area(self) -> bool:
        """Every GA run's vehicle heads towards the task centre."""
        return all(c["faces_task_area"] for c in self.pose_checks)


def _timed(fn, *args):
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - t0


def pose_checks(problem: DockingProblem, pose, p_init, tol: float) -> dict:
    """Where a pose ``(4,)`` lies relative to the start ``p_init (3,)`` [m]: the quarter of the
    top face nearest ``p_init`` (closed, within ``tol`` [m], for the arm base; open for the
    docking point) and the heading vs the task area."""
    pose = np.asarray(pose, dtype=float)
    sx, sy = np.sign(p_init[0]), np.sign(p_init[1])
    p_d = np.asarray(docking_point(jnp.asarray(pose), problem.p_bp))
    c = np.asarray(problem.task_center)
    bearing = np.arctan2(c[1] - pose[1], c[0] - pose[0])
    off = float(np.abs(np.angle(np.exp(1j * (pose[3] - bearing)))))
    return {
        "base_in_near_quarter": bool(pose[0] * sx >= -tol and pose[1] * sy >= -tol),
        "docking_point": p_d.tolist(),
        "docking_point_in_near_quarter": bool(p_d[0] * sx > 0 and p_d[1] * sy > 0),
        "heading_off_task_centre_deg": float(np.degrees(off)),
        "faces_task_area": bool(off < np.pi / 2),  # the task centre lies ahead of the vehicle
    }


def _grid_optimum(x, fitness, terms, i: int, candidates: int, seconds: float) -> GridOptimum:
    """The grid optimum ``x`` with its terms, row ``i`` of ``terms``."""
    return GridOptimum(np.asarray(x), float(fitness), float(terms.M_a[i]), float(terms.D[i]), int(candidates), seconds)


def _pose_map(problem: DockingProblem, pose, n_per_side: int) -> PoseMap:
    return PoseMap(np.asarray(pose), wmax_map(problem, pose, n_per_side), float(evaluate(problem, pose).M_a))


def _polish(problem: Problem, grid, ga, g, periodic) -> tuple:
    """Zoom stages from the grid's best point (``g.refine_starts == 1``: the reference's
    polish) or from the ``g.refine_starts`` best distinct points of the grid and the GA runs
    ``ga``. Returns the best point (``x``, ``fitness``), the best fitness after each stage,
    the poses evaluated, the wall time [s], and the distinct polished points best first
    (``(K, 4)`` poses, ``(K,)`` fitness; the best alone with one start)."""
    t0 = time.perf_counter()
    per_box = int(np.prod(g.refine_counts))
    if g.refine_starts == 1:
        stages = refine_grid_search(problem, grid, g.refine_counts, g.refine_stages, g.refine_shrink, g.chunk_size)
        best = stages[-1] if stages else grid
        return (best, tuple(float(st.fitness) for st in stages), len(stages) * per_box, time.perf_counter() - t0,
                (np.asarray(best.x)[None], np.asarray(best.fitness).reshape(1)))
    x = np.concatenate([np.asarray(grid.top_x), np.asarray(ga.best_x)])
    f = np.concatenate([np.asarray(grid.top_fitness), np.asarray(ga.best_fitness)])
    cell = np.asarray(problem.pose_high - problem.pose_low) / np.asarray(g.counts)
    starts = distinct_best(x, f, g.refine_starts, cell)
    zoom = zoom_from(problem, x[starts], f[starts], problem.pose_low, problem.pose_high, g.refine_counts,
                     g.refine_stages, g.refine_shrink, periodic, width=cell / g.refine_shrink, chunk_size=g.chunk_size)
    k = int(np.argmax(zoom.fitness))
    best = grid._replace(x=jnp.asarray(zoom.x[k]), fitness=jnp.asarray(zoom.fitness[k]))
    kept = distinct_best(zoom.x, zoom.fitness, len(starts), cell)  # starts may polish into one optimum
    return (best, tuple(float(v) for v in zoom.fitness_history.max(axis=-1)), g.refine_stages * per_box * len(starts),
            time.perf_counter() - t0, (zoom.x[kept], zoom.fitness[kept]))


def _ga_runs(s: DockingSettings, problem: Problem, ga_parts: tuple, bar) -> tuple:
    """The GA's ``R`` runs in one call, compiled ahead of time so that the timed call runs only
    once; each run alone too with ``s.time_single_runs``. Returns the batch's result, the
    seconds of each run (the batch's time when not timed alone), the batch's seconds and its
    compile seconds."""
    codec, ga, params = ga_parts
    keys = jax.random.split(jax.random.key(s.seed), s.n_runs)
    t0 = time.perf_counter()
    compiled = ga_batch_compiled(keys, problem, codec, ga, params)
    t_compile = time.perf_counter() - t0
    res, t_batch = _timed(compiled, keys, problem, codec, params)
    log.info("GA: %d runs in %.3f s after compilation (compile + first run %.1f s)", s.n_runs, t_batch, t_compile)
    bar.update()
    seconds = [t_batch] * s.n_runs
    if s.time_single_runs:
        run_ga(keys[0], problem, codec, ga, params)  # compile the single-run path
        seconds = [_timed(run_ga, keys[r], problem, codec, ga, params)[1] for r in range(s.n_runs)]
        bar.update()
    return res, seconds, t_batch, t_compile


def _cmaes_runs(s: DockingSettings, problem: Problem, bar) -> CMAESRuns:
    """The CMA-ES baseline's runs, timed after a compiling call."""
    c = s.cmaes
    ckeys = jax.random.split(jax.random.key(s.seed + 1), c.n_runs)
    args = (ckeys, problem, problem.pose_low, problem.pose_high, c.population_size, c.generations, c.std_init)
    _timed(run_cmaes, *args)  # compile
    cma, t_cma = _timed(run_cmaes, *args)
    cmaes = CMAESRuns(np.asarray(cma.best_x), np.asarray(cma.best_fitness), np.asarray(cma.history),
                      t_cma, c.population_size * c.generations)
    log.info("CMA-ES: %d runs in %.2f s, best %.4f", c.n_runs, t_cma, float(np.max(cmaes.fitness)))
    bar.update()
    return cmaes


def run_docking(settings: DockingSettings, task: ArmTask | None = None, robot=None) -> DockingRun:
    """The docking experiment: GA batch (compiled ahead, then timed), optional single-run
    timing, dense grid + zoom refinement, optional CMA-ES, w_max maps, pose checks.

    Args:
      settings: the run's settings.
      task: an arm scene's task when it has no panel (e.g. :func:`uvms_jax.plan.docking_task`).
      robot: the arm (:class:`uvms_jax.robot.Robot`); None: the one the arm scene names.

    Raises:
      ValueError: float64 asked for without ``jax_enable_x64`` (set it once at start), or a
        missing or surplus task (see :func:`docking_problem`).
    """
    if jnp.dtype(settings.dtype) == jnp.float64 and not jax.config.jax_enable_x64:
        raise ValueError("dtype float64 needs jax.config.update('jax_enable_x64', True) before the run")
    s = settings
    problem = docking_problem(s.scene, s.dtype, task, robot)
    codec, ga, params = make_ga(s.ga, problem)
    log.info("load average %s; devices %s", os.getloadavg(), jax.devices())
    # Each step is one compiled call (the GA batch, the grid, ...): progress counts steps.
    bar = progress.bar(total=3 + s.time_single_runs + s.cmaes.enabled, desc="docking", unit="step")

    # Grid reference: a global grid (compiled once for any size), then zoom stages. Compiled
    # first: with ga.host_loop and chunk_size = eval_chunk its fitness is the GA's too.
    g = s.grid
    low, high = problem.pose_low, problem.pose_high
    per = grid_periodicity(problem)
    keep = 1 if g.refine_starts == 1 else 8 * g.refine_starts  # enough to find K distinct ones
    shift = np.asarray(jax.random.uniform(jax.random.key(s.seed + 2), (len(g.counts),))) if g.shift else None
    grid_search(problem, low, high, (2, 2, 2, 2), per, g.chunk_size, keep, shift)  # compile

    res, seconds, t_batch, t_compile = _ga_runs(s, problem, (codec, ga, params), bar)

    grid, t_grid = _timed(grid_search, problem, low, high, g.counts, per, g.chunk_size, keep, shift)
    bar.update()
    ref, stage_fitness, n_refine, t_refine, (candidates, candidate_fitness) = _polish(problem, grid, res, g, per)
    bar.update()
    # Objective terms of the GA bests and the two grid optima in one call (one compilation).
    scored = jnp.concatenate([res.best_x, grid.x[None], ref.x[None]])
    report = arm_report(problem, scored) if isinstance(problem, ArmDockingProblem) else None
    terms = report.terms if report is not None else evaluate(problem, scored)
    R = s.n_runs
    grid_opt = _grid_optimum(grid.x, grid.fitness, terms, R, grid.n_candidates, t_grid)
    refined = _grid_optimum(ref.x, ref.fitness, terms, R + 1, n_refine, t_refine)
    log.info("grid: %d candidates in %.1f s, optimum %.4f; refined (%d more) %.4f",
             grid.n_candidates, t_grid, grid_opt.fitness, refined.candidates, refined.fitness)

    cmaes = _cmaes_runs(s, problem, bar) if s.cmaes.enabled else None
    bar.close()

    poses, fitness = np.asarray(res.best_x), np.asarray(res.best_fitness)
    generations = np.asarray(res.generations)
    best_ga = int(np.argmax(fitness))
    best_row = R + 1 if refined.fitness > float(fitness[best_ga]) else best_ga  # a row of `scored`
    paper = isinstance(problem, DockingProblem)
    tol = float(np.max(np.asarray(codec.resolution)[:2]))  # x = 0 / y = 0 is not on the lattice
    return DockingRun(
        settings=s,
        problem=problem,
        poses=poses,
        fitness=fitness,
        M_a=np.asarray(terms.M_a[:R]),
        generations=generations,
        evaluations=np.asarray(res.evaluations),
        histories=tuple(np.asarray(h)[: int(n)] for h, n in zip(res.history, generations)),
        run_seconds=tuple(seconds),
        ga_batch_seconds=t_batch,
        ga_compile_seconds=t_compile,
        grid=grid_opt,
        refined_grid=refined,
        refine_stage_fitness=stage_fitness,
        candidates=candidates,
        candidate_fitness=candidate_fitness,
        cmaes=cmaes,
        wmax_best=_pose_map(problem, poses[best_ga], s.wmax.n_per_side) if paper else None,
        pose_checks=tuple(pose_checks(problem, x, s.scene.p_init, tol) for x in poses) if paper else (),
        best=BestPose(np.asarray(scored[best_row]), float(refined.fitness if best_row == R + 1 else fitness[best_ga]),
                      float(terms.M_a[best_row]), "grid search" if best_row == R + 1 else "analytic GA",
                      None if paper else jax.tree_util.tree_map(lambda a: a[best_row], report)),
        load_average=os.getloadavg(),
        device=str(jax.devices()[0]),
    )
