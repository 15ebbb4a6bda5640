"""The five stages of the end-to-end run, each a call of its package's stage function and
writer, and the part of ``summary.md`` it contributes (tables of ours beside the papers')."""

from __future__ import annotations

import dataclasses
import json
import logging
import math
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax import evo, hover, hw, planfile, progress, sched, surrogate
from uvms_jax import robot as robots
from uvms_jax import plan as planning
from uvms_jax.pipeline._precheck import baseline_scenario, vehicle_hull
from uvms_jax.pipeline._report import StageReport
from uvms_jax.files import write_atomic
from uvms_jax.text import md_table
from uvms_jax.pipeline._settings import PipelineSettings

log = logging.getLogger(__name__)

# Thesis Table 5.5: solver times on the eq. 4.1 matrix [ms] (docs/theory.md §5).
THESIS_SOLVER_MS = {"greedy": 0.0121, "grasp": 110.2, "astar": 0.9435, "exact": None}
# hw/run.mp4: the ~92 s demo run → ~730 frames, 22–25 s of software (Mesa) rendering on 2 cores.
VIDEO_FPS = 8.0
VIDEO_SIZE = (480, 360)  # width, height [pixels]


@dataclasses.dataclass
class Flow:
    """What a stage hands to the later ones, in memory.

    Attributes:
      robot: the arm of every stage (the scenario's).
      task: the scenario's grasp and place poses and tables, as the docking stage's task.
      problem: the docking problem of the arm on its vehicle over the scenario's task.
      reach: the surrogate stage's learned map.
      pose: the docking stage's vehicle pose ``(4,)`` [m, rad]; T_world_vehicle, T_world_base:
        ``(4, 4)`` the vehicle and the arm's base there.
      scene_spec: the planning scene (the scenario with the arm under the docked vehicle).
      scene: the planning scene built already, else None: the plan stage builds it from
        ``scene_spec``.
      baseline_scene, baseline_skipped: the baseline's scene (the arm at the fixed mount),
        built by the checks before the first stage, or why the baseline stage is skipped
        (:func:`~uvms_jax.pipeline.check_stages`).
      task_plan, plan, plan_source: planning → schedule → execution.
      reports: the reports of the stages run so far, by name.
    """

    robot: robots.Robot | None = None
    task: evo.ArmTask | None = None
    problem: evo.ArmDockingProblem | None = None
    reach: surrogate.ReachMapRun | None = None
    pose: np.ndarray | None = None
    T_world_vehicle: np.ndarray | None = None
    T_world_base: np.ndarray | None = None
    scene_spec: planning.SceneSpec | None = None
    scene: planning.Scene | None = None
    baseline_scene: planning.Scene | None = None
    baseline_skipped: str | None = None
    task_plan: planning.TaskGraphPlan | None = None
    plan: planfile.Plan | None = None
    plan_source: str = ""
    reports: dict[str, StageReport] = dataclasses.field(default_factory=dict)


def _pose(p) -> list[float]:
    return [round(float(v), 3) + 0.0 for v in p]


def _docking_problem(s: PipelineSettings, flow: Flow) -> evo.ArmDockingProblem:
    """The arm-on-vehicle docking problem over the scenario's grasp and place poses (built once)."""
    if flow.problem is None:
        flow.task = planning.docking_task(planning.build_scene(flow.robot, s.scenario), vehicle=s.docking.scene,
                                          margin=s.plan.margin)
        flow.problem = evo.docking_problem(s.docking.scene, s.docking.dtype, flow.task, flow.robot)
    return flow.problem


def surrogates(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Learn the arm's best manipulability at a tool pose seen from its base on this vehicle
    (the inner part of the docking fitness) from analytic scores of tool poses sampled in the
    base frame (the task and the scene are not used: one map per arm and vehicle)."""
    problem = _docking_problem(s, flow)
    run = surrogate.run_reach_map(problem, s.reach)
    flow.reach = run
    t, r = run.test, run.settings
    k = int(problem.group.shape[0])
    res = {"n_train_samples": run.n_train, "n_test_samples": run.n_test, "analytic_seconds": run.analytic_seconds,
           "train_seconds": run.train_seconds, "vehicle_pose_equivalents": (run.n_train + run.n_test) / k, **t}
    write_atomic(out / "reach_map.json", json.dumps({**res, "settings": dataclasses.asdict(r)}, indent=1))
    table = md_table(["tool poses (train / test)", "reached", "analytic scoring [s]", "FFBN units", "training [s]",
                      "test RMSE of w", "max error of w", "largest w"],
                     [[f"{run.n_train} / {run.n_test}", f"{100 * t['reached_fraction']:.0f} %", run.analytic_seconds,
                       r.hidden, run.train_seconds, t["rmse_w"], t["max_abs_error_w"], t["w_range"]]])
    notes = ["The docking fitness spends its time in multi-seed numerical IK; what it keeps per tool pose is the best "
             "w over the valid solutions (reached, within the limits, clear of the vehicle and of the arm itself), a "
             "function of the tool "
             "pose seen from the arm's base alone. An FFBN learns it here from tool poses sampled in the base frame "
             f"(reached positions, approaches within {r.approach_cone_deg:g}° of the downward vertical), each scored by "
             "the docking fitness's own IK: the arm, its mount, the vehicle and the IK settings, not the task or the "
             f"scene, so one map serves every task of this arm on this vehicle (its {run.n_train + run.n_test} tool "
             f"poses cost what {res['vehicle_pose_equivalents']:.0f} docking evaluations of this task's {k} tool poses "
             "do). The scene's obstacles are not in the map: the docking stage scores its proposals analytically. "
             "The dexterity paper's surrogates of the 12-DOF UVMS are reproduced apart: `python "
             "experiments/surrogate.py` (docs/reproduction.md)."]
    return StageReport("surrogate", f"Surrogate: the {flow.robot.name}'s dexterity map on its vehicle (docs/docking.md)",
                       [table], res, notes)


def docked_scene(scenario, problem: evo.ArmDockingProblem, pose) -> tuple[np.ndarray, np.ndarray, planning.SceneSpec]:
    """The planning scene of a docked vehicle: the scenario with the arm's base on the vehicle
    at ``pose (4,) = [x, y, z, ψ]`` [m, rad] (the docking problem's mount) and the vehicle's
    boxes as obstacles.

    Returns:
      ``(T_world_vehicle (4, 4), T_world_base (4, 4), scene spec)``.
    """
    T_world_vehicle, T_world_base, _ = (np.asarray(a, dtype=float)
                                        for a in evo.arm_tool_poses(problem, jnp.asarray(pose, problem.pose_low.dtype)))
    spec = planning.SceneSpec.from_mapping(scenario).with_base(T_world_base)
    vehicle = planning.vehicle_obstacles(T_world_vehicle, problem.T_vehicle_box, problem.vehicle_half)
    spec = dataclasses.replace(spec, obstacles=spec.obstacles + vehicle)
    return T_world_vehicle, T_world_base, spec


def docking(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Docking GA (+ grid reference) of the vehicle over the scenario's task; with a learned
    map, the GA on it too; the chosen pose puts the arm's base into the planning scene."""
    problem = _docking_problem(s, flow)
    run = evo.run_docking(s.docking, flow.task, flow.robot)
    evo.write_docking(run, out)
    best = int(np.argmax(run.fitness))
    rows = [[f"analytic GA run {i + 1}", *_pose(p), float(f), float(m), int(e)]
            for i, (p, f, m, e) in enumerate(zip(run.poses, run.fitness, run.M_a, run.evaluations))]
    g = s.docking.grid
    search = "grid + zoom" if g.refine_starts == 1 else f"grid + zoom from {g.refine_starts} starts"
    rows.append([search, *_pose(run.refined_grid.pose), run.refined_grid.fitness, run.refined_grid.M_a,
                 run.grid.candidates + run.refined_grid.candidates])
    res = {"ga_best_fitness": float(run.fitness[best]), "ga_best_M_a": float(run.M_a[best]),
           "ga_ratio_to_grid_min": float(run.ga_ratio_to_refined_grid.min()), "ga_batch_seconds": run.ga_batch_seconds,
           "grid_fitness": run.refined_grid.fitness, "ga_evaluations": int(np.sum(run.evaluations))}
    # The analytic optimisers' best: the GA runs or the grid search, whichever scores higher
    # (on a small CPU budget the GA can miss the narrow region that reaches every target).
    pose, source, pose_M_a, best_fitness = run.best.pose, run.best.source, run.best.M_a, run.best.fitness
    notes = [f"{len(run.fitness)} GA runs in one jitted batch: {run.ga_batch_seconds:.1f} s after compilation "
             f"({run.ga_evaluations_per_second:.0f} evaluations/s); GA / grid search "
             f"{run.ga_ratio_to_refined_grid.min():.3f}–{run.ga_ratio_to_refined_grid.max():.3f}. The grid search: "
             f"{run.grid.candidates} poses of a coarse lattice, then {len(run.refine_stage_fitness)} zoom stages "
             f"({run.refined_grid.candidates} poses) from "
             + ("its best point" if g.refine_starts == 1 else
                f"the {g.refine_starts} best distinct points of the lattice and the GA runs")
             + f" ({run.grid.seconds + run.refined_grid.seconds:.1f} s). Fitness: eq. 15 "
             f"(a·M_a − b·D in Wd), M_a = min over the {problem.n_groups} targets of the best w over each target's "
             f"alternatives and IK seeds."]
    if flow.reach is not None:
        md = surrogate.dock_with_map(problem, flow.reach, s.docking.ga, s.docking.n_runs, s.seed)
        rows += [[f"map candidate {i + 1} (analytic)", *_pose(p), float(f), "", ""]
                 for i, (p, f) in enumerate(zip(md.candidates[:3], md.candidate_fitness[:3]))]
        rows.append(["map + analytic refinement", *_pose(md.pose), md.fitness, md.M_a, md.analytic_evaluations])
        # The analytic route's evaluations: the GA runs', the lattice's and the zoom stages'.
        analytic_n = int(np.sum(run.evaluations)) + run.grid.candidates + run.refined_grid.candidates
        ratio = analytic_n / md.analytic_evaluations
        analytic_s = run.ga_batch_seconds / float(np.sum(run.evaluations))  # per pose, in the GA batch
        speedup = analytic_s / md.eval_seconds
        loss = 1.0 - md.fitness / best_fitness if best_fitness > 0 else math.nan
        res.update({"map_best_fitness": md.fitness, "map_best_M_a": md.M_a, "map_eval_speedup": speedup,
                    "map_loss_of_optimum": loss, "map_seconds": md.seconds, "map_evaluations": md.map_evaluations,
                    "map_analytic_evaluations": md.analytic_evaluations, "analytic_evaluations": analytic_n,
                    "map_evaluation_ratio": ratio})
        notes.append(
            f"**Surrogate-assisted docking** (`docking_fitness=surrogate` sends its pose on): the GA on the map "
            f"({md.map_evaluations} map evaluations, {md.eval_seconds * 1e6:.1f} µs each against "
            f"{analytic_s * 1e3:.1f} ms analytically in the GA batch) proposes; its {len(md.candidates)} best distinct "
            f"poses are scored analytically (best {float(np.max(md.candidate_fitness)):.3f}) and "
            f"{len(md.refine_fitness) - 1} trust-region steps (zoom on the map corrected to the analytic w at the "
            f"current pose, then one analytic evaluation) refine the best to {md.fitness:.3f}, against the analytic "
            f"optimisers' {best_fitness:.3f} ({source}): a loss of optimum of **{100 * loss:.2f} %** with "
            f"**{md.analytic_evaluations}** analytic evaluations against their {analytic_n} (**{ratio:.0f}× fewer**; "
            f"{md.seconds:.1f} s, the compilation of its analytic calls included). The map itself (surrogate stage) "
            "is the arm's on its vehicle, not the task's, and is not counted in the ratio.")
        if md.fitness > best_fitness and s.docking_fitness == "analytic":
            notes.append("The map's route found a better pose than the analytic optimisers (scored analytically); "
                         "`docking_fitness=surrogate` sends it on.")
        if s.docking_fitness == "surrogate":
            pose, source, pose_M_a = md.pose, "map + analytic refinement", md.M_a
    if not pose_M_a > 0:
        raise ValueError(f"the docking stage found no vehicle pose from which the arm reaches every target "
                         f"(M_a = 0 at the {source}'s best {_pose(pose)}): enlarge the GA (ga.population_size, "
                         "ga.max_generations) or change the pose box (docking scene pose_low / pose_high)")
    flow.pose = np.asarray(pose, dtype=float)
    flow.T_world_vehicle, flow.T_world_base, flow.scene_spec = docked_scene(s.scenario, problem, flow.pose)
    res.update({"pose": flow.pose.tolist(), "pose_source": source, "pose_M_a": pose_M_a, "base_xyz": _pose(flow.T_world_base[:3, 3])})
    t1 = md_table(["run", "x [m]", "y [m]", "z [m]", "ψ [rad]", "fitness (eq. 15)", "M_a (eq. 1)", "evaluations"], rows)
    notes.append(f"Chosen: the {source}'s best pose {_pose(flow.pose)} → the arm's base at "
                 f"{_pose(flow.T_world_base[:3, 3])} m in the planning scene, with the vehicle's hull as an obstacle.")
    return StageReport("docking", f"Docking: where the vehicle holds the {flow.robot.name} over the tables "
                       "(docs/docking.md)",
                       [t1], res, notes)


def plan(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """IK targets and OMPL plans of every task-graph edge, the arm's base where the docking
    stage put it (else the scenario's mount); kept in memory for the schedule."""
    scene = flow.scene
    if scene is None:
        scene = planning.build_scene(flow.robot, flow.scene_spec if flow.scene_spec is not None else s.scenario)
    task_plan = planning.plan_task_graph(jax.random.key(s.plan.seed), scene, s.plan)
    planning.write_task_graph(task_plan, out)
    flow.task_plan = task_plan
    rows, res = [], {"ik_seconds": task_plan.ik_seconds}
    for planner, p in task_plan.summary.items():
        rows.append([planner, f"{p.success}/{p.edges}", f"{p.revalidated}/{p.edges}", f"{p.shortcuts}/{p.edges}",
                     1e3 * p.median_planning_time_s, 1e3 * p.mean_planning_time_s, 1e3 * p.max_planning_time_s])
        res[f"{planner}_success"] = p.success
        res[f"{planner}_shortcuts"] = p.shortcuts
        res[f"{planner}_median_ms"] = 1e3 * p.median_planning_time_s
    table = md_table(["planner", "planned", "re-checked OK", "straight-segment shortcut", "median [ms]", "mean [ms]",
                      "max [ms]"], rows)
    n_edges = len(next(iter(task_plan.by_planner.values()), ()))
    pc = s.plan
    notes = [f"{n_edges} task-graph edges (thesis Table 5.1 / eq. 4.1 structure), budget {pc.budget_s} s per edge; "
             f"IK targets {task_plan.ik_seconds:.1f} s (mostly XLA compilation). Every path re-checked at "
             f"{pc.recheck_resolution} rad with margin 0 and time-parameterised ({pc.max_velocity} rad/s). "
             + ("The straight joint-space segment replaces the planner's path wherever it is free (`plan.straight_shortcut`"
                ", column \"straight-segment shortcut\"): fast, and the moves the planners need are the others. "
                if pc.straight_shortcut else "Each path is the planner's own, simplified. ")
             + 
             "The thesis publishes no per-edge planning times; BENCHMARKS.md has a 5 s-budget run of all three planners."]
    res["base_xyz"] = _pose(scene.T_world_base[:3, 3])
    res["T_world_base"] = scene.T_world_base.tolist()
    first = min(scene.objects)  # the arm at its first grasp: the picture of the intervention
    if first in task_plan.targets and planning.render_frame(scene, task_plan.targets[first].q_at, out / "scene.png"):
        notes.append("`plan/scene.png`: the arm at its grasp of the first object, in the planning scene.")
    return StageReport("plan", "Planning every pick-and-place move (docs/theory.md §5, thesis ch. 5.1)", [table], res, notes)


def schedule(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Cost matrix (the planning stage's metrics, else the configured source) → every solver;
    the thesis's eq. 4.1 instance beside its published times; the winner's plan."""
    key = jax.random.key(s.seed)
    task_plan = flow.task_plan
    planner = s.sched_planner or s.plan.planners[0]
    raw = task_plan.metrics[planner] if task_plan is not None else None
    compat = planning.compatibility(task_plan.scene) if task_plan is not None else None  # the scene's fits
    run = sched.run_schedule(key, s.sched, raw, note=f"planning stage metrics ({planner})", compat=compat)
    results = sched.write_schedule(run, out, plots=s.sched.plots)
    winner = run.best
    t1 = md_table(["solver", "schedule", "cost", "time [ms] (ours)", "thesis Table 5.5 [ms] (eq. 4.1 matrix)"],
                  [[sched.SOLVERS[r.solver].label, r.path_str(), r.cost, r.wall_time_s * 1e3, THESIS_SOLVER_MS.get(r.solver)]
                   for r in run.solved.values()])
    thesis = sched.solve_all(key, sched.thesis_problem(), s.sched)
    thesis_path = "-".join(map(str, sched.THESIS_EQ41_GREEDY_PATH))
    t2 = md_table(["solver", "schedule (ours)", "cost", "thesis schedule", "time [ms] (ours)", "thesis [ms]"],
                  [[sched.SOLVERS[n].label, r.path_str(), r.cost, thesis_path if n == "greedy" else None, r.wall_time_s * 1e3,
                    THESIS_SOLVER_MS.get(n)] for n, r in thesis.items()])
    res = {"source": run.note, "weights": run.weights.name, "winner": winner.solver, "winner_path": winner.path_str(),
           "winner_cost": winner.cost, "optimal_cost": run.optimal_cost,
           **{f"{n}_cost": r.cost for n, r in run.solved.items()},
           **{f"{n}_ms": r.wall_time_s * 1e3 for n, r in run.solved.items()},
           **{f"thesis_{n}_cost": r.cost for n, r in thesis.items()},
           **{f"thesis_{n}_ms": r.wall_time_s * 1e3 for n, r in thesis.items()}}
    weights_note = "" if run.weights_used else " (not used by a ready matrix)"
    notes = [f"Cost matrix: {run.note}, weights `{run.weights.name}`{weights_note} {results['weights']}. "
             f"Winner: **{winner.solver}** `{winner.path_str()}` (cost {winner.cost:.4f})."]
    if run.weights_used:
        sums = md_table(["solver", *(f"Σ N {m}" for m in sched.METRICS)],
                        [[r["solver"], *(r[f"N_{m}"] for m in sched.METRICS)] for r in run.rows])
        notes.append("Normalised metric sums along each schedule (thesis Table 5.2 layout; lower is better, "
                     "security already inverted):\n\n" + sums)
    notes.append("Thesis instance (eq. 4.1 matrix, Table 5.1 nodes), same solvers:\n\n" + t2)
    if task_plan is not None:
        flow.plan = planning.plan_for_schedule(task_plan, planner, list(winner.path), s.plan)
        flow.plan_source = "schedule/plan.json"
        planning.write_plan(flow.plan, out)
        notes.append(f"`schedule/plan.json`: the winner's moves ({planner} trajectories) with the grasp/release "
                     "steps, in the `uvms_jax.planfile` format.")
    solvers = " / ".join(sched.SOLVERS[n].label for n in s.sched.solvers)
    return StageReport("schedule", f"Schedules: cost matrix → {solvers} (docs/theory.md §5, thesis Tables 5.2, 5.5)",
                       [t1], res, notes)


def execute(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Dry-run check, then execution of the scheduled plan (or ``hw.plan``) on the simulated arm."""
    hs = s.hw
    if hs.plan is not None:
        the_plan, source = planfile.load_plan(hs.plan), hs.plan
    elif flow.plan is not None:
        the_plan, source = flow.plan, flow.plan_source
    else:
        raise ValueError("the hw stage needs a plan: run the plan and schedule stages, or set hw.plan")
    # The simulated arm's gravity and buoyancy follow the base the plan was made for.
    sim = hs.sim if the_plan.base_rpy is None else dataclasses.replace(hs.sim, base_rpy=the_plan.base_rpy)
    with progress.bar(total=len(the_plan.segments), desc="hw", unit="seg") as bar:
        try:
            run = hw.run_plan(the_plan, flow.robot, link=hs.link, config=hs.executor, sim=sim,
                              progress=lambda i, n, name: bar.update(i - bar.n))  # i: segments finished
        except hw.RunInterrupted as stop:  # the arm was told to hold: keep what it did
            hw.write_run(stop.run, out, plot=False, plan_path=source)
            raise
        if run.ok:
            bar.update(bar.total - bar.n)
    res = hw.write_run(run, out, plot=hs.plot, plan_path=source)
    # The plan as a ROS-shaped JointTrajectory: what another arm's own controller executes.
    planfile.save_plan(the_plan, out / "joint_trajectory.yaml", joint_trajectory=True, gripper=flow.robot)
    if not run.ok:
        log.warning("simulated run aborted (arm told to hold): %s", run.result.reason)
    clock = "virtual clock" if hs.link == "loopback" else "real time"
    r, c = run.result, run.check
    table = md_table(
        ["plan", "segments", "waypoints", "estimated motion [s]", "result", "gates", "max gate error [rad]",
         "max gate error [mm]", f"run time ({clock}) [s]", "wall [s]", "demands outside limits"],
        [[f"`{Path(source).name}`", c.n_segments, c.n_waypoints, c.estimated_s, r.reason, len(r.gates),
          res["max_gate_error_rad"], res["max_gate_error_mm"], r.duration_s, run.wall_s, run.sim.limit_violations]])
    notes = [f"Link: {hs.link} ({clock}); reached-gate threshold {hs.executor.gate_threshold_rad} rad "
             "(thesis 4.6: every encoder within the threshold before the next motion). The thesis validated its "
             "real-arm runs with motion capture (~2 mm); `run.csv` logs commanded vs measured states for the same "
             "comparison. Same plan on a real arm: `uvms-hw run PLAN --dry-run`, then `--udp 192.168.2.3:6789`; "
             "`joint_trajectory.yaml`: the plan as a ROS-shaped JointTrajectory for any arm's own controller."]
    if hs.plot and run.log.rows:
        notes.append(_run_video(s, flow, run.log, out, res))
    return StageReport("hw", f"Execution on the simulated {flow.robot.name} (docs/theory.md §6, thesis 4.6)", [table],
                       res, notes)


def _film_scene(s: PipelineSettings, flow: Flow) -> planning.Scene | None:
    """The scene the videos of the hw and hover stages are drawn in: the planning stage's, else
    the scenario's (the example plan was planned in the thesis cage of
    ``configs/scenario/thesis_cage.yaml``), else None."""
    if flow.task_plan is not None:
        return flow.task_plan.scene
    return planning.build_scene(flow.robot, s.scenario) if s.scenario else None


def _run_video(s: PipelineSettings, flow: Flow, run_log: hw.RunLog, out: Path, res: dict) -> str:
    """``out/run.mp4``: the measured run in the planning stage's scene, else the scenario's
    (the example plan was planned in the thesis cage of ``configs/scenario/thesis_cage.yaml``);
    returns the summary note."""
    scene = _film_scene(s, flow)
    if scene is None:
        return "No video of the run: no scene (run the plan stage or give a scenario)."
    t, q = run_log.measured(scene.robot.joint_names)
    if len(t) == 0:
        return "No video of the run: no complete measured state was logged."
    try:
        video = planning.render_run_video(scene, t, q, out / "run.mp4", fps=VIDEO_FPS, size=VIDEO_SIZE)
    except RuntimeError as e:  # no offscreen GL context on this machine
        log.warning("no video of the run: %s", e)
        return f"No video of the run: {e}."
    res["video_frames"] = video.frames
    res["video_render_s"] = video.seconds
    link = f"{out.name}/{video.path.name}"
    return (f"Video of the run: [{link}]({link}) — measured joint angles in the MuJoCo scene, {video.fps:g} fps, "
            f"{VIDEO_SIZE[0]}×{VIDEO_SIZE[1]}, {video.frames} frames, rendered offscreen in {video.seconds:.1f} s "
            "(arm only: the jaws' opening and the carried objects are not drawn).")


def hovering(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """The scheduled plan's motion with the vehicle hovering at the docked pose instead of fixed
    to it, in still water and in the configured current: how good the docking pose is if the
    vehicle only hovers there."""
    hs, scene = s.hover, s.docking.scene
    hull = vehicle_hull(scene)
    vehicle = dataclasses.replace(hs.vehicle, size=tuple(hull.size), mount_xyz=tuple(scene.mount_xyz),
                                  mount_rpy=tuple(scene.mount_rpy))
    cases = {"still water": ((0.0, 0.0, 0.0), False)}
    flowing = f"current {_pose(hs.current)} m/s"
    if any(hs.current):
        cases[flowing] = (tuple(hs.current), False)
        if hs.coordinate:
            cases[f"{flowing}, whole-body controller"] = (tuple(hs.current), True)
    runs = {}
    for label, (v, coordinate) in progress.bar(list(cases.items()), desc="hover", unit="run"):
        current = hover.CurrentSettings(velocity=v)
        if coordinate:  # the executor streams the plan's waypoints: the controller runs on HoverSim
            runs[label] = hover.run_plan_hovering(
                flow.robot, flow.plan, flow.pose, vehicle, hs.controller, current, dwell_s=hs.dwell_s,
                gripper_s=hs.gripper_s, tool_tolerance_m=hs.tool_tolerance_m,
                joint_tolerance_rad=hs.joint_tolerance_rad, control="whole_body", whole_body=hs.whole_body,
                tool_tolerance_deg=hs.tool_tolerance_deg, navigation=hs.navigation)
        else:  # the hw stage's executor and gates; its simulated arm on the hovering vehicle
            runs[label] = hover.execute_plan_hovering(
                flow.robot, flow.plan, flow.pose, vehicle, hs.controller, current, config=s.hw.executor,
                sim=s.hw.sim, tool_tolerance_m=hs.tool_tolerance_m)
    summaries = {label: r.summary() for label, r in runs.items()}
    rows = [[label, m["driver"], f"{m['status']}" + (f": {m['reason']}" if m["reason"] else ""),
             f"{m['gates_reached']}/{m['gates']}", f"{m['gates_tool_within_tolerance']}/{m['gates']}",
             1e3 * m["max_drift_m"], 1e3 * m["max_tool_error_m"], 1e3 * m["max_gate_tool_error_m"], m["max_tilt_deg"],
             m["peak_thrust_N"]] for label, m in summaries.items()]
    docked = flow.reports.get("hw")
    if docked is not None:
        g = docked.results.get("gates", "—")
        rows.insert(0, ["docked (hw stage)", "BPL executor", docked.results.get("status", ""), f"{g}/{g}", f"{g}/{g}",
                        0.0, 0.0, 0.0, 0.0, 0.0])
    table = md_table(["vehicle", "arm driven by", "result", "gates passed", "gates with the tool within "
                      f"{1e3 * hs.tool_tolerance_m:.0f} mm", "max drift [mm]", "max tool error [mm]",
                      "max tool error at a gate [mm]", "max roll/pitch [°]", "peak thrust [N]"], rows)
    main = flowing if flowing in summaries else "still water"
    res = {**summaries[main], "runs": summaries}
    if f"{flowing}, whole-body controller" in summaries:
        plain, coord = summaries[flowing], summaries[f"{flowing}, whole-body controller"]
        res["coordination_removes"] = {k: 1.0 - coord[k] / plain[k] for k in ("max_tool_error_m", "max_gate_tool_error_m")}
    _plot_hover(runs, out / "hover.png")
    if s.hw.plot:
        video_note = _hover_video(s, flow, runs[main], main, out, res)
    notes = [f"The scheduled plan on the vehicle floating at the docked pose (MuJoCo, `uvms_jax.hover`, docs/hover.md): "
             f"{len(vehicle.thrusters)} thrusters of ±{max(t.max_thrust for t in vehicle.thrusters):g} N, station "
             "keeping on x, y, z, ψ, the hull ballasted neutral and level for the arm at the plan's start. The BPL "
             "executor of the hw stage runs the plan with its settings, gates and safety checks on the simulated arm "
             "mounted on the hovering vehicle: its gates are on the encoders, which the vehicle's motion does not "
             "move, so it passes them as on a fixed base while the tool is off; the column after them counts the "
             f"gates where the tool was also within {1e3 * hs.tool_tolerance_m:.0f} mm of where the docked arm holds "
             "it at the same joint angles (tool error: the vehicle's motion, seen at the tool). "
             "The whole-body controller (docs/hover.md) keeps the tool on the plan's docked path through the "
             "vehicle–arm Jacobian (`kin.uvms`), station keeping in that task's null space, with a model-based "
             "feed-forward on the thrusters; the executor, streaming the plan's waypoints, does not do this, so that "
             f"run is on the simulator's position servos, dwelling {hs.dwell_s} s at each segment's end (its gate), "
             f"and its gates are judged on the tool's world pose (within {1e3 * hs.tool_tolerance_m:.0f} mm and "
             f"{hs.tool_tolerance_deg:g}°; servo lag included). "
             "`hover/hover.png`: drift and tool error over time."] + ([video_note] if s.hw.plot else [])
    return StageReport("hover", "Hovering instead of docked: the same motion on thrusters (docs/hover.md)", [table],
                       res, notes)


def _hover_video(s: PipelineSettings, flow: Flow, run: hover.HoverRun, label: str, out: Path, res: dict) -> str:
    """``out/hover.mp4`` in the hw video's scene, camera and frames, and ``out/hover_frame.png``
    (also at ``hover.frame_png``): the frame at the gate of the largest tool error. Returns the
    summary note."""
    scene = _film_scene(s, flow)
    if scene is None:
        return "No video of the hovering run: no scene (run the plan stage or give a scenario)."
    try:
        video = hover.write_hover_video(run, scene, out / "hover.mp4", fps=VIDEO_FPS, size=VIDEO_SIZE)
        worst = run.gate_times[np.argmax(run.gate_tool_error)] if len(run.gate_times) else run.log.time[-1]
        still = hover.hover_frame(run, scene, float(min(worst, run.log.time[-1])), size=VIDEO_SIZE)
    except RuntimeError as e:  # no offscreen GL context on this machine
        log.warning("no video of the hovering run: %s", e)
        return f"No video of the hovering run: {e}."
    from PIL import Image

    paths = [out / "hover_frame.png"] + ([Path(s.hover.frame_png)] if s.hover.frame_png else [])
    for path in paths:
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(still).save(path, optimize=True)
    res["video_frames"], res["video_render_s"] = video.frames, video.seconds
    link = f"{out.name}/{video.path.name}"
    return (f"Video of the {label} run: [{link}]({link}) — the vehicle and the arm as simulated in the hw video's "
            "scene, camera and frames (compare side by side), with the docked hull's outline (white), the tool's "
            "target path (green: where the docked arm holds it) and its path so far (red), the current (blue "
            f"arrow) and the time and the tool error at the last gate; {video.fps:g} fps, {video.frames} frames, "
            f"rendered in {video.seconds:.1f} s. `{out.name}/hover_frame.png`: the frame at the gate of the largest "
            "tool error.")


def _plot_hover(runs: dict, path: Path) -> None:
    """Drift of the vehicle and tool error over time, one line per run → PNG."""
    from uvms_jax.plotting import pyplot

    plt = pyplot()
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 5), sharex=True, layout="constrained")
    for label, r in runs.items():
        a.plot(r.log.time, 1e3 * r.drift, label=label)
        b.plot(r.log.time, 1e3 * r.tool_error, label=label)
        b.plot(r.gate_times, 1e3 * r.gate_tool_error, ".", color=b.lines[-1].get_color(), ms=4)
    a.set(ylabel="vehicle drift [mm]", title="Hovering at the docked pose")
    b.set(xlabel="time [s]", ylabel="tool error [mm] (dots: gates)")
    a.legend(fontsize=8)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _path_figures(flow: Flow, planner: str, path) -> dict:
    """Raw metrics along a schedule (no normalisation, so two scenes compare): sums of planning
    time [s], joint movement [rad] and tool path [m], the smallest clearance [m] and the largest
    joint torque [N·m]."""
    m = flow.task_plan.metrics[planner]  # (5, N, N) in sched.METRICS order
    legs = np.stack([m[:, a, b] for a, b in zip(path[:-1], path[1:])], axis=1)  # (5, legs)
    r = dict(zip(sched.METRICS, legs))
    return {"planning_time_s": float(np.sum(r["planning_time"])), "joint_movement_rad": float(np.sum(r["joint_movement"])),
            "ee_distance_m": float(np.sum(r["ee_distance"])), "min_clearance_m": float(np.min(r["security"])),
            "max_torque_Nm": float(np.max(r["max_torque"]))}


def _fixed_mount_M_a(problem: evo.ArmDockingProblem, T_world_base: np.ndarray) -> float | None:
    """M_a of the docking task with the arm's base fixed at ``T_world_base`` (no vehicle hull):
    the docking problem at the vehicle pose that puts the base there, when that pose is level
    (the docking problem's vehicle only yaws); None otherwise."""
    T = T_world_base @ np.linalg.inv(np.asarray(problem.T_vehicle_base, dtype=float))
    if not np.allclose(T[2, :3], (0, 0, 1), atol=1e-6):
        return None
    pose = np.array([*T[:3, 3], np.arctan2(T[1, 0], T[0, 0])])
    # M_a depends on the hull only through the arm's collisions with it (the world's mask); the
    # hull's own clearance enters the fitness alone. Same shapes as the docking stage's
    # problem: its compiled report serves here.
    no_hull = problem.replace(world=problem.world.without_vehicle())
    return float(evo.arm_report(no_hull, pose[None]).terms.M_a[0])


BASELINE_TITLE = "Baseline: the thesis's fixed mount against the docked arm"


def _baseline_skipped(why: str) -> StageReport:
    return StageReport("baseline", BASELINE_TITLE, [], {"skipped": why}, [f"Skipped: {why}."])


def baseline(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """The same task with the thesis's fixed cage-top mount (``baseline``), the run's arm and
    start (:func:`~uvms_jax.pipeline.baseline_scenario`): plan, schedule and run again, and
    compare with the docked arm. Skipped, with the reason in ``results["skipped"]``, where the
    arm cannot do the task from there (found before the first stage, or no valid IK target)."""
    if s.baseline is None:
        raise ValueError("the baseline stage needs a baseline scenario (`baseline.scenario`)")
    if flow.baseline_skipped is not None:
        return _baseline_skipped(flow.baseline_skipped)
    fixed = Flow(robot=flow.robot, scene_spec=planning.SceneSpec.from_mapping(baseline_scenario(s)),
                 scene=flow.baseline_scene)
    quiet = dataclasses.replace(s, hw=dataclasses.replace(s.hw, plot=False))
    stages = {}
    for name, fn in (("plan", plan), ("schedule", schedule), ("hw", execute)):
        (out / name).mkdir(parents=True, exist_ok=True)
        try:
            stages[name] = fn(quiet, out / name, fixed).results
        except ValueError as e:  # a node without a valid IK target from the fixed mount
            if name != "plan":
                raise
            why = f"arm {flow.robot.name!r} cannot do the task from the fixed mount: {e}"
            log.warning("baseline stage skipped: %s", why)
            return _baseline_skipped(why)
    planner = s.sched_planner or s.plan.planners[0]
    rows, res = [], {}
    for label, f, r in (("docked under the vehicle", flow, {k: v.results for k, v in flow.reports.items()}),
                        ("fixed cage-top mount (thesis)", fixed, stages)):
        if "schedule" not in r or f.task_plan is None:
            continue
        path = [int(v) for v in r["schedule"]["winner_path"].split("-")]
        fig = _path_figures(f, planner, path)
        if f is flow:
            M_a = r["docking"]["pose_M_a"] if "docking" in r else None
        else:
            M_a = _fixed_mount_M_a(flow.problem, f.task_plan.scene.T_world_base) if flow.problem is not None else None
        hw_r = r.get("hw", {})
        rows.append([label, ", ".join(f"{v:.3f}" for v in f.task_plan.scene.T_world_base[:3, 3]), M_a,
                     r["plan"].get(f"{planner}_success"), r["schedule"]["winner_path"], r["schedule"]["winner_cost"],
                     fig["joint_movement_rad"],
                     fig["ee_distance_m"], fig["min_clearance_m"], fig["max_torque_Nm"], hw_r.get("duration_s"),
                     hw_r.get("gates"), hw_r.get("reason")])
        res[label.split()[0]] = {"M_a": M_a, "winner_path": r["schedule"]["winner_path"], **fig,
                                 "executed_s": hw_r.get("duration_s"), "ok": hw_r.get("ok")}
    table = md_table(["arm base", "base xyz [m]", "M_a of the task", "edges planned", "schedule",
                      "cost (own scene's normalisation)", "joint movement [rad]",
                      "tool path [m]", "min clearance [m]", "max torque [N·m]", "executed [s]", "gates", "result"], rows)
    notes = []
    if len(rows) == 2:
        d, b = res["docked"], res["fixed"]
        faster = "docked" if (d["executed_s"] or np.inf) < (b["executed_s"] or np.inf) else "fixed"
        dexterous = "docked" if (d["M_a"] or 0) > (b["M_a"] or 0) else "fixed"
        notes.append(f"The **{faster}** arm finishes the task sooner ({d['executed_s']:.1f} s docked, "
                     f"{b['executed_s']:.1f} s fixed); the **{dexterous}** arm is the more dexterous over the targets "
                     f"(M_a {d['M_a']:.4f} docked, {b['M_a']:.4f} fixed; the fixed mount's M_a is the docking problem's "
                     "with the base there and no hull).")
    notes.append("Sums along each schedule of the raw metrics; the costs are normalised within each scene's own edges "
                 "(thesis eq. 4.16), so they rank schedules of one scene, not the two scenes. The baseline plans in "
                 "the thesis's cage (`configs/scenario/thesis_cage.yaml`) with the run's arm and start "
                 "(`scenario.start_q`; null: one found there).")
    return StageReport("baseline", BASELINE_TITLE, [table], res, notes)


def chain(flow: Flow, out: Path) -> str:
    """The intervention at a glance (markdown): pose → base in the scene → schedule → run, and
    the planning stage's picture of the scene (``out/plan/scene.png``)."""
    r = {k: v.results for k, v in flow.reports.items()}
    steps = []
    if "docking" in r:
        d = r["docking"]
        steps.append(f"**dock** the vehicle at x, y, z, ψ = {_pose(d['pose'])} ({d['pose_source']}, M_a "
                     f"{d['pose_M_a']:.4f})")
    if "plan" in r:
        steps.append(f"**arm base** in the planning scene at {r['plan']['base_xyz']} m; "
                     + ", ".join(f"{k.removesuffix('_success')} {v} edges" for k, v in r["plan"].items()
                                 if k.endswith("_success")))
    if "schedule" in r:
        steps.append(f"**schedule** {r['schedule']['winner_path']} ({r['schedule']['winner']}, cost "
                     f"{r['schedule']['winner_cost']:.4f})")
    if "hw" in r:
        h = r["hw"]
        steps.append(f"**run** on the simulated {flow.robot.name}: {h.get('reason')}, {h.get('gates')} gates, "
                     f"{h.get('duration_s')} s")
    picture = out / "plan" / "scene.png"
    return " → ".join(steps) + ("\n\n![the arm in the planning scene](plan/scene.png)" if picture.exists() else "")


STAGE_FNS = {"surrogate": surrogates, "docking": docking, "plan": plan, "schedule": schedule, "hw": execute,
             "hover": hovering, "baseline": baseline}
