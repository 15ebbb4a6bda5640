"""The docking stage: where the vehicle holds the arm over the tables (``evo.run_docking``, and
``surrogate.dock_with_map`` where the surrogate stage learned a map); its pose puts the arm's
base into the planning scene (``plan.docked_scene``)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from uvms_jax import evo, surrogate
from uvms_jax import plan as planning
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.pipeline.stages._flow import Flow, docking_problem, rounded
from uvms_jax.text import md_table

__all__ = ["run"]


def run(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Docking GA (+ grid reference) of the vehicle over the scenario's task; with a learned
    map, the GA on it too; the chosen pose puts the arm's base into the planning scene."""
    problem = docking_problem(s, flow)
    dock = evo.run_docking(s.docking, flow.task, flow.robot)
    evo.write_docking(dock, out)
    best = int(np.argmax(dock.fitness))
    rows = [[f"analytic GA run {i + 1}", *rounded(p), float(f), float(m), int(e)]
            for i, (p, f, m, e) in enumerate(zip(dock.poses, dock.fitness, dock.M_a, dock.evaluations))]
    g = s.docking.grid
    search = "grid + zoom" if g.refine_starts == 1 else f"grid + zoom from {g.refine_starts} starts"
    rows.append([search, *rounded(dock.refined_grid.pose), dock.refined_grid.fitness, dock.refined_grid.M_a,
                 dock.grid.candidates + dock.refined_grid.candidates])
    res = {"ga_best_fitness": float(dock.fitness[best]), "ga_best_M_a": float(dock.M_a[best]),
           "ga_ratio_to_grid_min": float(dock.ga_ratio_to_refined_grid.min()),
           "ga_batch_seconds": dock.ga_batch_seconds,
           "grid_fitness": dock.refined_grid.fitness, "ga_evaluations": int(np.sum(dock.evaluations))}
    # The analytic optimisers' best: the GA runs or the grid search, whichever scores higher
    # (on a small CPU budget the GA can miss the narrow region that reaches every target).
    pose, source, pose_M_a, best_fitness = dock.best.pose, dock.best.source, dock.best.M_a, dock.best.fitness
    notes = [f"{len(dock.fitness)} GA runs in one jitted batch: {dock.ga_batch_seconds:.1f} s after compilation "
             f"({dock.ga_evaluations_per_second:.0f} evaluations/s); GA / grid search "
             f"{dock.ga_ratio_to_refined_grid.min():.3f}–{dock.ga_ratio_to_refined_grid.max():.3f}. The grid search: "
             f"{dock.grid.candidates} poses of a coarse lattice, then {len(dock.refine_stage_fitness)} zoom stages "
             f"({dock.refined_grid.candidates} poses) from "
             + ("its best point" if g.refine_starts == 1 else
                f"the {g.refine_starts} best distinct points of the lattice and the GA runs")
             + f" ({dock.grid.seconds + dock.refined_grid.seconds:.1f} s). Fitness: eq. 15 "
             f"(a·M_a − b·D in Wd), M_a = min over the {problem.n_groups} targets of the best w over each target's "
             f"alternatives and IK seeds."]
    if flow.reach is not None:
        md = surrogate.dock_with_map(problem, flow.reach, s.docking.ga, s.docking.n_runs, s.seed)
        rows += [[f"map candidate {i + 1} (analytic)", *rounded(p), float(f), "", ""]
                 for i, (p, f) in enumerate(zip(md.candidates[:3], md.candidate_fitness[:3]))]
        rows.append(["map + analytic refinement", *rounded(md.pose), md.fitness, md.M_a, md.analytic_evaluations])
        # The analytic route's evaluations: the GA runs', the lattice's and the zoom stages'.
        analytic_n = int(np.sum(dock.evaluations)) + dock.grid.candidates + dock.refined_grid.candidates
        ratio = analytic_n / md.analytic_evaluations
        analytic_s = dock.ga_batch_seconds / float(np.sum(dock.evaluations))  # per pose, in the GA batch
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
                         f"(M_a = 0 at the {source}'s best {rounded(pose)}): enlarge the GA (ga.population_size, "
                         "ga.max_generations) or change the pose box (docking scene pose_low / pose_high)")
    flow.pose = np.asarray(pose, dtype=float)
    flow.T_world_vehicle, flow.T_world_base, flow.scene_spec = planning.docked_scene(s.scenario, problem, flow.pose)
    res.update({"pose": flow.pose.tolist(), "pose_source": source, "pose_M_a": pose_M_a,
                "base_xyz": rounded(flow.T_world_base[:3, 3])})
    t1 = md_table(["run", "x [m]", "y [m]", "z [m]", "ψ [rad]", "fitness (eq. 15)", "M_a (eq. 1)", "evaluations"], rows)
    notes.append(f"Chosen: the {source}'s best pose {rounded(flow.pose)} → the arm's base at "
                 f"{rounded(flow.T_world_base[:3, 3])} m in the planning scene, with the vehicle's hull as an "
                 "obstacle.")
    return StageReport("docking", f"Docking: where the vehicle holds the {flow.robot.name} over the tables "
                       "(docs/docking.md)",
                       [t1], res, notes)
