"""Planning benchmark (uvms_jax.plan): planning time per edge per planner over the thesis task
graph, and validity checks per second — single calls, the OMPL callback, and batched calls.

Prints one JSON object. ``.venv/bin/python benchmarks/plan.py [--planners RRTConnect PRM]``
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import jax
import numpy as np
import yaml

from uvms_jax import plan as P

SCENARIO = Path(__file__).parents[1] / "configs" / "scenario" / "thesis_cage.yaml"


def _rate(fn, n: int) -> float:
    t = time.perf_counter()
    fn()
    return n / (time.perf_counter() - t)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--planners", nargs="+", default=list(P.PLANNERS))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--checks", type=int, default=20000)
    args = ap.parse_args()
    jax.config.update("jax_enable_x64", True)
    P.seed_ompl(args.seed)
    scene = P.build_scene(yaml.safe_load(SCENARIO.read_text()))
    checker = P.CollisionChecker(scene)
    t0 = time.perf_counter()
    targets = P.pick_place_targets(jax.random.PRNGKey(args.seed), scene, checker, n_seeds=P.IkSettings().n_seeds)
    ik_s = time.perf_counter() - t0

    Q = np.random.default_rng(args.seed).uniform(checker.lower, checker.upper, (args.checks, 6))
    valid = checker.state_validator()
    checks = {
        "single_is_valid_per_s": _rate(lambda: [checker.is_valid(q) for q in Q], len(Q)),
        "ompl_callback_per_s": _rate(lambda: [valid(q) for q in Q], len(Q)),
        "batched_is_valid_per_s": _rate(lambda: checker.is_valid_batch(Q), len(Q)),
        "batched_clearance_per_s": _rate(lambda: checker.clearance_batch(Q), len(Q)),
        "valid_fraction_uniform": float(checker.is_valid_batch(Q).mean()),
    }
    edges = P.task_edges(scene)
    per_planner = {}
    for planner in args.planners:
        times, ok, reval = {}, 0, 0
        for src, dst in edges:
            r = P.plan_edge(scene, checker, targets, src, dst, planner)
            times[f"{src}->{dst}"] = round(r.plan.planning_time_s, 5)
            ok += r.success
            reval += r.revalidated
        t = np.array(list(times.values()))
        per_planner[planner] = {"success": ok, "revalidated": reval, "edges": len(edges),
                                "median_s": float(np.median(t)), "mean_s": float(t.mean()), "max_s": float(t.max()),
                                "per_edge_s": times}
    print(json.dumps({
        "device": f"{platform.machine()} CPU, Python {platform.python_version()}",
        "ik_targets_s_incl_compile": round(ik_s, 2),
        "validity_checks": {k: round(v, 3) if isinstance(v, float) else v for k, v in checks.items()},
        "planning": per_planner,
    }, indent=1))


if __name__ == "__main__":
    main()
