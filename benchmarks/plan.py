"""Planning benchmark (uvms_jax.plan): the thesis task graph planned with every planner, side by
side in one process on the query path (``PlanSettings.checker = "query"``: :func:`plan_query` on
the scene as a world, compiled RRT-Connect, the other planners in OMPL on the same compiled
checker) and with OMPL on the scene's two motion checkers — MuJoCo state by state (OMPL's own
motion checks) and the compiled sphere checker (one call per motion, MuJoCo confirming
rejections) — plus validity checks per second.

Per checker and planner: planning time per edge (median, mean, max), edges planned and
re-checked (every path is re-checked with MuJoCo at margin 0 either way), the wall time of the
whole graph (planning, time parameterisation, re-check, metrics) and where it goes: seconds in
each step of :func:`uvms_jax.plan.plan_edge` (``steps_s``: the planner's solve and
simplification, the MuJoCo re-check, time parameterisation, trajectory check, metrics,
clearance; ``other`` is the rest). ``graph_wall_s`` sums the planners' graph times per checker.
Compilation (Numba, XLA) and the query path's checkers (one per context: the world, the held
object's spheres, MuJoCo's model; ``query_checkers_s``) are made in a warm-up before any timing
and reported apart. Writes one JSON object to ``--out`` and prints it.

    .venv/bin/python benchmarks/plan.py [--planners RRTConnect PRM] [--checkers query spheres]
        [--params '{"BKPIECE1": {"range": 1.0}}'] [--out benchmarks/results/plan_cpu.json]
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import dataclasses
import functools
import json
import sys
import platform
import time
from pathlib import Path

import jax
import numpy as np
import yaml

from uvms_jax import plan as P
from uvms_jax.files import json_text, write_json
from uvms_jax.plan import _collision, _spheres, _tasks

# The steps of plan_edge, as (namespace, attribute, label); the planners' time (plan_motion or
# plan_scene_query) includes the re-check, reported apart and subtracted. The clearance is either
# MuJoCo's at every sample or the sphere checker's min_clearance (which calls MuJoCo's
# single-state clearance, not the batch).
_STEPS = ((_collision.CollisionChecker, "path_is_valid", "recheck_mujoco"), (_tasks, "plan_motion", "plan"),
          (_tasks, "plan_scene_query", "plan"),
          (_tasks, "time_parameterize", "time_parameterize"), (_tasks, "check_trajectory", "check_trajectory"),
          (_tasks, "trajectory_metrics", "metrics"), (_collision.CollisionChecker, "clearance_batch", "clearance"),
          (_spheres.SphereChecker, "min_clearance", "clearance"))

SCENARIO = Path(__file__).parents[1] / "configs" / "scenario" / "thesis_cage.yaml"


def _rate(fn, n: int) -> float:
    t = time.perf_counter()
    fn()
    return n / (time.perf_counter() - t)


@contextlib.contextmanager
def _timed_steps(acc: dict[str, float]):
    """Add the seconds spent in each of :data:`_STEPS` to ``acc`` while inside."""
    saved = []
    for owner, name, label in _STEPS:
        fn = getattr(owner, name)
        saved.append((owner, name, fn))

        def timed(*a, _fn=fn, _label=label, **k):
            t = time.perf_counter()
            try:
                return _fn(*a, **k)
            finally:
                acc[_label] += time.perf_counter() - t

        setattr(owner, name, functools.wraps(fn)(timed))
    try:
        yield acc
    finally:
        for owner, name, fn in saved:
            setattr(owner, name, fn)


def _graph(scene, checker, fast, targets, edges, planner, settings) -> dict:
    """Plan every edge with one planner; per-edge planning times, the graph's wall time and
    its split over the steps of plan_edge."""
    times, ok, reval = {}, 0, 0
    acc: dict[str, float] = collections.defaultdict(float)
    t0 = time.perf_counter()
    with _timed_steps(acc):
        for src, dst in edges:
            r = P.plan_edge(scene, checker, targets, src, dst, planner, settings, fast=fast)
            times[f"{src}->{dst}"] = round(r.plan.planning_time_s * 1e3, 3)
            ok += r.success
            reval += r.revalidated
    wall = time.perf_counter() - t0
    steps = {"plan": acc["plan"] - acc["recheck_mujoco"]}
    steps |= {label: acc[label] for _, _, label in _STEPS if label != "plan"}  # labels may repeat
    steps["other"] = wall - sum(steps.values())
    t = np.array(list(times.values()))
    return {"success": ok, "revalidated": reval, "edges": len(edges), "median_ms": float(np.median(t)),
            "mean_ms": float(t.mean()), "max_ms": float(t.max()), "graph_wall_s": round(wall, 3),
            "steps_s": {k: round(v, 3) for k, v in steps.items()}, "per_edge_ms": times}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--planners", nargs="+", default=list(P.PLANNERS))
    ap.add_argument("--checkers", nargs="+", default=list(P.CHECKERS), choices=P.CHECKERS)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--checks", type=int, default=20000)
    ap.add_argument("--params", type=json.loads, default={},
                    help='planner parameters as JSON, e.g. \'{"BKPIECE1": {"range": 1.0}}\' (default: OMPL\'s)')
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "plan_cpu.json")
    args = ap.parse_args()
    jax.config.update("jax_enable_x64", True)
    P.seed_ompl(args.seed)
    settings = P.PlanSettings(planners=tuple(args.planners), planner_params=args.params)
    scenario = yaml.safe_load(SCENARIO.read_text())
    scene = P.build_scene(P.scenario_robot(scenario), scenario)
    checker = P.CollisionChecker(scene, margin=settings.margin, clearance_max=settings.clearance_max)
    t0 = time.perf_counter()
    fast = P.SphereChecker(checker)
    fast.spheres_free(np.asarray(scene.spec.start_q)[None], P.Context())  # Numba: compile or load its cache
    numba_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    targets = P.pick_place_targets(jax.random.PRNGKey(args.seed), scene, checker, settings.ik)
    ik_s = time.perf_counter() - t0
    edges = P.task_edges(scene)
    t0 = time.perf_counter()
    contexts = {P.edge_endpoints(scene, targets, src, dst)[2] for src, dst in edges}
    query = {ctx: P.scene_checker(scene, ctx, settings.margin) for ctx in contexts}
    query_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    for planner in args.planners:  # warm-up: Numba and XLA compiles, first OMPL calls
        for name in args.checkers:
            for src, dst in edges[:: max(1, len(edges) // 6)]:
                P.plan_edge(scene, checker, targets, src, dst, planner, dataclasses.replace(settings, checker=name),
                            fast=fast if name == "spheres" else None)
    warmup_s = time.perf_counter() - t0

    Q = np.random.default_rng(args.seed).uniform(checker.lower, checker.upper, (args.checks, len(checker.lower)))
    ctx = P.Context()
    valid = checker.state_validator(Q.shape[1], ctx)
    checks = {
        "mujoco_single_is_valid_per_s": _rate(lambda: [checker.is_valid(q, ctx) for q in Q], len(Q)),
        "mujoco_ompl_callback_per_s": _rate(lambda: [valid(q) for q in Q], len(Q)),
        "mujoco_batched_is_valid_per_s": _rate(lambda: checker.is_valid_batch(Q, ctx), len(Q)),
        "spheres_one_call_per_state_per_s": _rate(lambda: fast.spheres_free(Q, ctx), len(Q)),
        "query_batched_states_free_per_s": _rate(lambda: query[ctx].states_free(Q), len(Q)),
        "valid_fraction_uniform": float(checker.is_valid_batch(Q, ctx).mean()),
    }
    per_checker = {}
    for name in args.checkers:
        f = fast if name == "spheres" else None
        n0 = (fast.n_motions, fast.n_states, fast.n_confirmed)
        t0 = time.perf_counter()
        runs = {planner: _graph(scene, checker, f, targets, edges, planner, dataclasses.replace(settings, checker=name))
                for planner in args.planners}
        per_checker[name] = {"graph_all_planners_wall_s": round(time.perf_counter() - t0, 3),
                             "graph_wall_s": {p: r["graph_wall_s"] for p, r in runs.items()}, "planners": runs}
        if f is not None:
            per_checker[name]["motions"] = fast.n_motions - n0[0]
            per_checker[name]["samples_checked"] = fast.n_states - n0[1]
            per_checker[name]["rejections_confirmed_by_mujoco"] = fast.n_confirmed - n0[2]
    record = {
        "command": " ".join(["python benchmarks/plan.py", *sys.argv[1:]]),
        "device": f"{platform.machine()} CPU, Python {platform.python_version()}",
        "planner_params": settings.planner_params,
        "straight_shortcut": settings.straight_shortcut,
        "budget_s": settings.budget_s,
        "ik_targets_s_incl_compile": round(ik_s, 2),
        "numba_compile_or_cache_load_s": round(numba_s, 2),
        "query_checkers_s": round(query_s, 2),
        "warmup_s": round(warmup_s, 2),
        "validity_checks": {k: round(v, 3) if isinstance(v, float) else v for k, v in checks.items()},
        "checkers": per_checker,
    }
    write_json(args.out, record)
    print(json_text(record))


if __name__ == "__main__":
    main()
