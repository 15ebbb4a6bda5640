"""Files of a docking run: tables, JSON and figures in one output folder."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from uvms_jax.files import write_csv, write_json
from uvms_jax.evo._docking import DockingRun, GridOptimum
from uvms_jax.evo._plots import plot_convergence, plot_docked_top_view, plot_wmax
from uvms_jax.evo._settings import FIELDS


def _pose(x) -> dict:
    return dict(zip(FIELDS, np.asarray(x, dtype=float).tolist()))


def _optimum(g: GridOptimum) -> dict:
    return {"pose": _pose(np.asarray(g.pose)), "fitness": g.fitness, "Ma": g.M_a, "D": g.D}


def docking_summary(run: DockingRun) -> dict:
    """Acceptance figures of a run (the contents of results.json)."""
    s = run.settings
    references = {"grid": run.grid.fitness, "refined_grid": run.refined_grid.fitness}
    f_ga = run.fitness
    checks = list(run.pose_checks)
    summary = {
        "ga_fitness": f_ga.tolist(),
        **{f"ga_ratio_to_{k}": (f_ga / v).round(5).tolist() for k, v in references.items()},
        **{f"ga_runs_within_{s.accept_ratio}_of_{k}": int(np.sum(f_ga >= s.accept_ratio * v)) for k, v in references.items()},
        "ga_batch_seconds": run.ga_batch_seconds,
        "ga_compile_and_first_batch_seconds": run.ga_compile_seconds,
        "ga_generations": run.generations.tolist(),
        "ga_evaluations": run.evaluations.tolist(),
        "ga_evaluations_per_s": run.ga_evaluations_per_second,
        "grid_candidates_per_s": run.grid.candidates / run.grid.seconds,
        "load_average": run.load_average,
        "device": run.device,
        "certificate": certificate(run),
    }
    if run.wmax_best is not None:  # the paper's scene: where the poses lie, w_max maps
        summary |= {
            "best_pose_checks": checks,
            "all_bases_in_near_quarter": all(c["base_in_near_quarter"] for c in checks),
            "all_docking_points_in_near_quarter": all(c["docking_point_in_near_quarter"] for c in checks),
            "all_face_task_area": run.all_face_task_area,
            "zero_w_fraction": {"best": run.wmax_best.map.zero_fraction},
        }
    return summary


def certificate(run: DockingRun) -> dict:
    """The run's chosen pose and its GA's best against the run's reference search.

    A dense grid polished by zoom stages from its best point (``grid.refine_starts == 1``, e.g.
    ``docking/preset=bravo7_tables`` on a GPU) is a reference: ``ga_certified`` says whether the
    best GA run reached ``accept_ratio`` of it. A multistart search (``refine_starts > 1``, the
    demo's) is a competitor, not a reference: it certifies nothing (``ga_certified`` None)."""
    s, ref = run.settings, run.refined_grid
    dense = s.grid.refine_starts == 1
    ratio = float(np.max(run.fitness)) / ref.fitness
    return {"chosen": {"pose": _pose(run.best.pose), "fitness": run.best.fitness, "source": run.best.source},
            "reference": {"search": "dense grid + zoom" if dense else "multistart lattice + zoom (not a reference)",
                          "pose": _pose(np.asarray(ref.pose)), "fitness": ref.fitness,
                          "evaluations": run.grid.candidates + ref.candidates},
            "ga_best_ratio": ratio, "accept_ratio": s.accept_ratio,
            "ga_certified": bool(ratio >= s.accept_ratio) if dense else None}


def _write_wmax(run: DockingRun, out: Path) -> None:
    maps = {"best": run.wmax_best}
    vmax = max(float(m.map.w_max.max()) for m in maps.values())
    for name, m in maps.items():
        label = ", ".join(f"{float(v):.3f}" for v in m.pose)
        plot_wmax(m.map, f"{name.replace('_', '-')} pose [{label}]", out / f"wmax_{name}.png", vmax)
    write_json(out / "wmax.json", {
        name: {"pose": _pose(m.pose), "zero_w_fraction": m.map.zero_fraction, "Ma": m.M_a,
               "w_max_mean": float(m.map.w_max.mean()), "n_per_side": run.settings.wmax.n_per_side}
        for name, m in maps.items()
    })


def _write_arm_pose(run: DockingRun, out: Path) -> None:
    """The run's best pose of an arm scene (GA or grid search): joint solution and w per
    target, and a top view."""
    best = run.best
    pose, ik = best.pose, best.ik
    write_json(out / "best_pose.json", {
        "pose": _pose(pose), "source": best.source, "fitness": best.fitness, "Ma": float(ik.terms.M_a),
        "candidates": [{"pose": _pose(x), "fitness": float(f)} for x, f in zip(run.candidates, run.candidate_fitness)],
        "targets": [{"reached": bool(o), "w": float(wi), "q": None if not o else qi.round(5).tolist()}
                    for qi, o, wi in zip(ik.q, ik.valid, ik.w)],
    })
    plot_docked_top_view(run.problem, pose, ik.q, ik.valid, ik.w, out / "docked_top_view.png")


def write_docking(run: DockingRun, out: Path) -> dict:
    """Write a run into the folder ``out`` and return the summary.

    Files: runs.csv (one row per GA run: x, y, z, psi, fitness, Ma, generations, seconds),
    grid_optimum.json (grid optimum and its zoom refinement), cmaes.json (when CMA-ES ran),
    wmax.json (zero-w fraction, M_a and mean w_max of the best pose), wmax_best.png (its eq. 16
    map) for the paper's scene, or
    best_pose.json (IK solution and w per target, the distinct candidate poses) and
    docked_top_view.png for an arm scene,
    convergence.png, results.json.
    """
    out = Path(out)
    s = run.settings
    grid = {**_optimum(run.grid), "counts": list(s.grid.counts), "candidates": run.grid.candidates,
            "seconds": run.grid.seconds,
            "refined": {**_optimum(run.refined_grid), "candidates": run.refined_grid.candidates,
                        "seconds": run.refined_grid.seconds, "stages": list(run.refine_stage_fitness)}}
    write_json(out / "grid_optimum.json", grid)

    if run.cmaes is not None:
        c = run.cmaes
        write_json(out / "cmaes.json", {
            "runs": [{**dict(zip(FIELDS, np.asarray(x).tolist())), "fitness": float(f)} for x, f in zip(c.poses, c.fitness)],
            "seconds": c.seconds,
            "evaluations_per_run": c.evaluations_per_run,
            "ratio_to_grid": (c.fitness / run.grid.fitness).tolist(),
            "ratio_to_refined_grid": (c.fitness / run.refined_grid.fitness).tolist(),
        })

    write_csv(out / "runs.csv", [[*run.poses[r].round(6).tolist(), round(float(run.fitness[r]), 6),
                                  round(float(run.M_a[r]), 6), int(run.generations[r]), round(run.run_seconds[r], 4)]
                                 for r in range(len(run.fitness))], header=[*FIELDS, "fitness", "Ma", "generations", "seconds"])

    if run.wmax_best is not None:
        _write_wmax(run, out)
    else:
        _write_arm_pose(run, out)

    plot_convergence(list(run.histories), [] if run.cmaes is None else run.cmaes.history,
                     {"grid optimum": run.grid.fitness, "refined grid": run.refined_grid.fitness},
                     out / "convergence.png")
    summary = docking_summary(run)
    write_json(out / "results.json", summary)
    return summary
