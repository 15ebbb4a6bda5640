"""Does the demo's docking stage find the optimum? Its problem (the Bravo 7 under the vehicle
above the thesis's tables, the demo's fitness: 2 grasp alternatives, 8 IK seeds × 25
iterations), a dense reference, and the stage's search run with many seeds, each seed's best
pose against the reference. Prints one JSON object.

    # the dense reference (GPU sizes: 823 284-pose grid + 8 zoom stages of 9^4)
    .venv/bin/python benchmarks/docking_search.py --reference > benchmarks/results/docking_reference_demo_h100.json
    # the demo's docking search with seeds 0..19 against it (CPU: a few minutes per seed)
    .venv/bin/python benchmarks/docking_search.py --seeds 0 20 \\
        --reference-file benchmarks/results/docking_reference_demo_h100.json [override ...]

Overrides are the pipeline's (``configs/pipeline.yaml``), e.g. ``docking.overrides=[...]`` or
``ga.population_size=64``: the search compared is the one ``make demo`` runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import sys
import time
from pathlib import Path

import jax
import numpy as np
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from uvms_jax import evo
from uvms_jax import plan as planning
from uvms_jax.files import json_text
from uvms_jax.settings import from_mapping

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "experiments"))
from pipeline import settings_of  # noqa: E402  (the pipeline's own reading of its config)



def reference_grid() -> evo.GridSettings:
    """The dense reference's grid: ``configs/docking/preset/bravo7_tables.yaml``'s."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("docking", overrides=["docking/preset=bravo7_tables"])
    return from_mapping(evo.GridSettings, OmegaConf.to_container(cfg.grid, resolve=True), "grid")


def demo_settings(overrides: list[str]):
    """The pipeline's settings as ``make demo`` reads them, with ``overrides``."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        return settings_of(compose("pipeline", overrides=overrides))


def demo_problem(settings):
    """The demo's docking problem, built as the pipeline's docking stage builds it."""
    robot = planning.scenario_robot(settings.scenario)
    task = planning.docking_task(planning.build_scene(robot, settings.scenario), vehicle=settings.docking.scene,
                                  margin=settings.plan.margin)
    return robot, task, evo.docking_problem(settings.docking.scene, settings.docking.dtype, task, robot)


def reference(settings) -> dict:
    """Dense grid + zoom stages from its best point (the reference polish) on the demo's problem."""
    _, _, problem = demo_problem(settings)
    low, high = problem.pose_low, problem.pose_high
    per = evo.grid_periodicity(problem)
    g = reference_grid()
    t0 = time.perf_counter()  # compile the grid's and the zoom's programs once, on a 2^4 grid; the timed calls reuse them
    warm = evo.grid_search(problem, low, high, (2, 2, 2, 2), per, g.chunk_size)
    evo.refine_grid_search(problem, warm, g.refine_counts, g.refine_stages, g.refine_shrink, g.chunk_size)
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    grid = evo.grid_search(problem, low, high, g.counts, per, g.chunk_size)
    jax.block_until_ready(grid.fitness)
    grid_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    stages = evo.refine_grid_search(problem, grid, g.refine_counts, g.refine_stages, g.refine_shrink, g.chunk_size)
    zoom_s = time.perf_counter() - t0
    best = stages[-1]
    return {"fitness": float(best.fitness), "pose": np.asarray(best.x).tolist(), "grid_fitness": float(grid.fitness),
            "grid_pose": np.asarray(grid.x).tolist(), "stage_fitness": [float(s.fitness) for s in stages],
            "grid": dataclasses.asdict(g), "grid_candidates": int(np.prod(g.counts)), "grid_seconds": grid_s,
            "zoom_seconds": zoom_s,
            "compile_seconds": compile_s}


def seeds(settings_for, first: int, count: int, ref: float | None) -> dict:
    """The demo's docking search (:func:`uvms_jax.evo.run_docking`) with each seed: the best
    of its GA runs and of its grid + zoom, against ``ref``."""
    rows = []
    for seed in range(first, first + count):
        s = settings_for(seed)
        robot, task, _ = demo_problem(s)
        t0 = time.perf_counter()
        run = evo.run_docking(s.docking, task, robot)
        wall = time.perf_counter() - t0
        best = max(float(np.max(run.fitness)), run.refined_grid.fitness)
        rows.append({"seed": seed, "best": best, "ga_best": float(np.max(run.fitness)),
                     "grid_zoom_best": run.refined_grid.fitness, "coarse_grid_best": run.grid.fitness,
                     "evaluations": int(np.sum(run.evaluations)) + run.grid.candidates + run.refined_grid.candidates,
                     "wall_s": wall, "ratio": None if ref is None else best / ref})
        print(json.dumps(rows[-1]), file=sys.stderr)
    ratios = [r["ratio"] for r in rows if r["ratio"] is not None]
    return {"runs": rows, "reached_0.99": int(sum(r >= 0.99 for r in ratios)) if ratios else None,
            "ratio_min": min(ratios) if ratios else None, "ratio_median": float(np.median(ratios)) if ratios else None,
            "wall_s_median": float(np.median([r["wall_s"] for r in rows]))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reference", action="store_true", help="compute the dense reference (a GPU job)")
    ap.add_argument("--seeds", type=int, nargs=2, metavar=("FIRST", "COUNT"), help="run the demo's search per seed")
    ap.add_argument("--reference-file", type=Path, help="a --reference result to compare the seeds with")
    ap.add_argument("overrides", nargs="*", help="pipeline config overrides")
    args = ap.parse_args()
    out = {"command": " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]), "device": str(jax.devices()[0]),
           "device_kind": jax.devices()[0].device_kind, "cpu_count": os.cpu_count(), "machine": platform.machine(),
           "jax": jax.__version__}
    if args.reference:
        out["reference"] = reference(demo_settings(args.overrides))
    if args.seeds:
        ref = json.loads(args.reference_file.read_text())["reference"]["fitness"] if args.reference_file else None
        out["reference_fitness"] = ref
        out["search"] = seeds(lambda seed: demo_settings([*args.overrides, f"seed={seed}"]), *args.seeds, ref)
    print(json_text(out))


if __name__ == "__main__":
    main()
