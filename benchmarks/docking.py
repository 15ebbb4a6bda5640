"""Docking optimisation timings: GA batch vs CMA-ES (evosax) vs dense grid; prints one JSON.

  python benchmarks/docking.py                                   # CPU defaults (paper sizes)
  python benchmarks/docking.py --population 100000 --runs 1 \\
      --grid 464,464,58,8 --chunk 1048576                         # GPU: pop 1e5, grid 1e8

  python benchmarks/docking.py --scene bravo7_panel --ga bravo7 --eval-chunk none \
      --grid 11,11,11,12 --chunk 8192 --cma-runs 0                # Bravo 7, numerical IK (GPU)

Every optimiser is called once to compile and then timed ``--repeat`` times (best and
median reported). The scene and GA settings are composed from configs/docking.yaml with
``--scene`` (configs/docking/scene/*.yaml) and ``--ga`` (configs/ga/*.yaml), so the
benchmark runs the same problem as the experiment.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import jax
import numpy as np
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from uvms_jax import evo
from uvms_jax.files import json_text
from uvms_jax.settings import from_mapping


ROOT = Path(__file__).resolve().parents[1]


def _time(fn, repeat):
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
    return out, {"compile_and_first_s": first, "best_s": min(times), "median_s": statistics.median(times)}


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=7, help="independent GA runs in one batch")
    ap.add_argument("--population", type=int, default=None, help="GA population (default: config, 60)")
    ap.add_argument("--max-generations", type=int, default=None, help="default: config, 500")
    ap.add_argument("--eval-chunk", default=None, help="GA fitness-cache chunk (default: config; 'none' = off)")
    ap.add_argument("--grid", default="81,81,16,12", help="grid points per x,y,z,ψ (product = candidates)")
    ap.add_argument("--chunk", type=int, default=16384, help="grid candidates per jitted chunk")
    ap.add_argument("--cma-runs", type=int, default=7)
    ap.add_argument("--cma-population", type=int, default=16)
    ap.add_argument("--cma-generations", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dtype", default="float32")
    ap.add_argument("--skip", default="", help="comma list of parts to skip: ga,grid,cmaes")
    ap.add_argument("--scene", default="paper", help="configs/docking/scene/<name>.yaml")
    ap.add_argument("--ga", default="paper", help="configs/ga/<name>.yaml")
    return ap


def _ga_part(args, problem, ga_parts, n_points: int) -> dict:
    """The GA's ``args.runs`` runs in one batch, timed."""
    codec, ga, params = ga_parts
    keys = jax.random.split(jax.random.key(0), args.runs)
    res, t = _time(lambda: evo.run_ga_batch(keys, problem, codec, ga, params), args.repeat)
    evals = int(np.sum(res.evaluations))
    return {
        "runs": args.runs,
        "population": ga.population_size,
        "max_generations": ga.max_generations,
        "eval_chunk": ga.eval_chunk,
        "generations": np.asarray(res.generations).tolist(),
        "evaluations": np.asarray(res.evaluations).tolist(),
        "best_fitness": np.asarray(res.best_fitness).tolist(),
        **t,
        "evaluations_per_s": evals / t["best_s"],
        "ik_targets_per_s": evals * n_points / t["best_s"],
    }


def _grid_part(args, problem, n_points: int) -> dict:
    """The dense grid, compiled on a tiny grid, then timed once on the full one (it is long on
    a CPU; the compiled search does not depend on the grid size)."""
    counts = tuple(int(c) for c in args.grid.split(","))
    low, high = problem.pose_low, problem.pose_high
    periodic = evo.grid_periodicity(problem)
    t0 = time.perf_counter()
    jax.block_until_ready(evo.grid_search(problem, low, high, (2, 2, 2, 2), periodic, args.chunk))
    t_compile = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = jax.block_until_ready(evo.grid_search(problem, low, high, counts, periodic, args.chunk))
    t = {"compile_and_tiny_grid_s": t_compile, "best_s": time.perf_counter() - t0}
    n = int(np.prod(counts))
    return {
        "counts": list(counts),
        "candidates": n,
        "chunk": args.chunk,
        "best_fitness": float(res.fitness),
        "pose": np.asarray(res.x).tolist(),
        **t,
        "candidates_per_s": n / t["best_s"],
        "ik_targets_per_s": n * n_points / t["best_s"],
    }


def _cmaes_part(args, problem) -> dict:
    """CMA-ES's ``args.cma_runs`` runs, timed."""
    ckeys = jax.random.split(jax.random.key(1), args.cma_runs)
    res, t = _time(
        lambda: evo.run_cmaes(ckeys, problem, problem.pose_low, problem.pose_high,
                              args.cma_population, args.cma_generations, 0.3),
        args.repeat,
    )
    evals = args.cma_runs * args.cma_population * args.cma_generations
    return {
        "runs": args.cma_runs,
        "population": args.cma_population,
        "generations": args.cma_generations,
        "best_fitness": np.asarray(res.best_fitness).tolist(),
        **t,
        "evaluations_per_s": evals / t["best_s"],
    }


def main() -> None:
    args = _parser().parse_args()
    skip = set(filter(None, args.skip.split(",")))

    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("docking", overrides=[f"docking/scene@scene={args.scene}", f"ga={args.ga}"])
    settings = from_mapping(evo.DockingSettings, OmegaConf.to_container(cfg, resolve=True))
    scene, g = settings.scene, settings.ga
    eval_chunk = (None if args.eval_chunk in ("none", "None") else int(args.eval_chunk)) if args.eval_chunk else g.eval_chunk
    g = dataclasses.replace(g, population_size=args.population or g.population_size,
                            max_generations=args.max_generations or g.max_generations, eval_chunk=eval_chunk)
    problem = evo.docking_problem(scene, args.dtype)
    ga_parts = evo.make_ga(g, problem)
    arm = isinstance(problem, evo.ArmDockingProblem)
    # IK targets per evaluation: control points (closed form), or tool poses × seeds (numerical).
    n_points = int(problem.T_world_tool.shape[0] * problem.seeds.shape[0]) if arm else int(problem.p_control.shape[0])
    report = {
        "benchmark": "docking",
        "command": " ".join(["python benchmarks/docking.py", *sys.argv[1:]]),
        "device": str(jax.devices()[0]),
        "device_kind": jax.devices()[0].device_kind,
        "platform": platform.machine(),
        "cpu_count": os.cpu_count(),
        "affinity_cpus": len(os.sched_getaffinity(0)),
        "jax": jax.__version__,
        "dtype": args.dtype,
        "scene": args.scene,
        "ik_targets_per_evaluation": n_points,
        **({"ik_iterations": problem.iterations} if arm else {}),
        "load_average_start": os.getloadavg(),
    }
    if "ga" not in skip:
        report["ga"] = _ga_part(args, problem, ga_parts, n_points)
    if "grid" not in skip:
        report["grid"] = _grid_part(args, problem, n_points)
    if "cmaes" not in skip and args.cma_runs > 0:
        report["cmaes"] = _cmaes_part(args, problem)
    if "ga" in report and "cmaes" in report:
        report["ga_over_cmaes_evaluations_per_s"] = report["ga"]["evaluations_per_s"] / report["cmaes"]["evaluations_per_s"]
    report["load_average_end"] = os.getloadavg()
    print(json_text(report))

if __name__ == "__main__":
    main()
