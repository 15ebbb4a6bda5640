"""Docking with the learned map against the analytic docking search, in the same run: the
demo's problem (``make demo``: the Bravo 7 under the vehicle above the thesis's tables, 2 grasp
alternatives, 8 IK seeds × 25 iterations) and the demo's settings, per seed.

Per seed: the arm's map (``surrogate.run_reach_map``, the surrogate stage), the docking stage's
analytic search (``evo.run_docking``: GA runs, lattice, zoom stages) and the map's route
(``surrogate.dock_with_map``). The loss of optimum is 1 − the map route's analytic fitness /
the analytic search's best; the evaluation ratio is the analytic search's vehicle-pose
evaluations / the map route's (its candidates and refinement steps). The map is the arm's, not
the task's, and is not in that ratio; ``amortised_ratio`` counts it too, its tool poses in
vehicle-pose evaluations of this task (k tool poses each). The dense reference optimum of the
problem (``benchmarks/results/docking_reference_demo_h100.json``) is given alongside.

Prints one JSON object (``--out`` also rewrites it after every seed, so a stopped run keeps the
seeds it finished).

    PYTHONPATH=. python benchmarks/docking_map.py --seeds 0 3 --out benchmarks/results/docking_map_cpu.json
    PYTHONPATH=. python benchmarks/docking_map.py --device gpu --seeds 0 10 --out benchmarks/results/docking_map_h100.json

Usage: python benchmarks/docking_map.py [--device cpu|gpu] [--seeds FIRST COUNT] [--out FILE] [override ...]
(overrides are the pipeline's, configs/pipeline.yaml, e.g. ``reach.refine_iterations=12``).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

from uvms_jax.files import json_text, write_json

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "benchmarks" / "results" / "docking_reference_demo_h100.json"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--device", default="cpu", help="JAX platform: cpu, gpu/cuda (default cpu)")
    ap.add_argument("--seeds", type=int, nargs=2, default=(0, 3), metavar=("FIRST", "COUNT"),
                    help="the pipeline's seed (map, GA keys, lattice shift) for each run (default 0 3)")
    ap.add_argument("--out", type=Path, default=None, help="also write the record here after every seed")
    ap.add_argument("overrides", nargs="*", help="pipeline config overrides")
    args = ap.parse_args()
    os.environ["JAX_PLATFORMS"] = {"gpu": "cuda"}.get(args.device, args.device)

    import jax
    import numpy as np

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from docking_search import demo_problem, demo_settings

    from uvms_jax import evo, surrogate

    device = jax.devices()[0]
    record = {"benchmark": "docking_map", "command": " ".join(["python benchmarks/docking_map.py", *sys.argv[1:]]),
              "device": device.device_kind, "platform": device.platform, "cpu_count": os.cpu_count(),
              "python": platform.python_version(), "jax": jax.__version__,
              "reference_fitness": json.loads(REFERENCE.read_text())["reference"]["fitness"], "runs": []}
    for seed in range(args.seeds[0], args.seeds[0] + args.seeds[1]):
        s = demo_settings([*args.overrides, f"seed={seed}"])
        robot, task, problem = demo_problem(s)
        k = int(problem.group.shape[0])
        t0 = time.perf_counter()
        reach = surrogate.run_reach_map(problem, s.reach)
        map_wall = time.perf_counter() - t0
        t0 = time.perf_counter()
        analytic = evo.run_docking(s.docking, task, robot)
        analytic_wall = time.perf_counter() - t0
        t0 = time.perf_counter()
        md = surrogate.dock_with_map(problem, reach, s.docking.ga, s.docking.n_runs, seed)
        map_route_wall = time.perf_counter() - t0
        n_analytic = int(np.sum(analytic.evaluations)) + analytic.grid.candidates + analytic.refined_grid.candidates
        best = analytic.best.fitness
        record["runs"].append({
            "seed": seed, "analytic_best": best, "analytic_source": analytic.best.source,
            "analytic_evaluations": n_analytic, "analytic_wall_s": analytic_wall,
            "map_route_fitness": md.fitness, "map_route_M_a": md.M_a, "map_route_pose": md.pose.tolist(),
            "map_route_analytic_evaluations": md.analytic_evaluations, "map_route_map_evaluations": md.map_evaluations,
            "map_route_seconds": md.seconds, "map_route_wall_s": map_route_wall,
            "best_candidate_fitness": float(np.max(md.candidate_fitness)),
            "loss_of_optimum": 1.0 - md.fitness / best, "evaluation_ratio": n_analytic / md.analytic_evaluations,
            "map_tool_poses": s.reach.n_samples, "map_vehicle_pose_equivalents": s.reach.n_samples / k,
            "amortised_ratio": n_analytic / (md.analytic_evaluations + s.reach.n_samples / k),
            "map_test_rmse_w": reach.test["rmse_w"], "map_test_w_std": reach.test["w_std"],
            "map_analytic_seconds": reach.analytic_seconds, "map_train_seconds": reach.train_seconds,
            "map_wall_s": map_wall, "ratio_to_reference": md.fitness / record["reference_fitness"]})
        runs = record["runs"]
        loss, ratio = [r["loss_of_optimum"] for r in runs], [r["evaluation_ratio"] for r in runs]
        record["summary"] = {"seeds": len(runs), "loss_max": max(loss), "loss_median": float(np.median(loss)),
                             "ratio_min": min(ratio), "ratio_median": float(np.median(ratio)),
                             "met": int(sum(lo <= 0.02 and ra >= 50 for lo, ra in zip(loss, ratio)))}
        print(json.dumps(runs[-1]), file=sys.stderr)
        if args.out:
            write_json(args.out, record)
    print(json_text(record))


if __name__ == "__main__":
    main()
