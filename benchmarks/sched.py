"""Scheduling benchmark (uvms_jax.sched): prints one JSON object.

* Thesis instance (eq. 4.1, 10 nodes): greedy, GRASP (1000 iterations, one jitted call),
  A*, exact — wall time per call (median and min over repeats, after a warm-up; GRASP's
  compile time reported apart) and cost — next to the peer, OR-Tools routing modelled as a
  pickup-and-delivery problem (below), and the thesis's own timings (Table 5.5).
* Batch scoring throughput [schedules/s]: ``score`` on a batch of valid and shuffled
  schedules, next to a NumPy implementation of the same checks.
* 10 objects / 10 bases (two random instances: 1–3 allowed bases per object, and every base
  allowed): exact DP, GRASP (1000 iterations) and OR-Tools with two time limits; costs as
  gaps to the exact optimum.

Peer model (OR-Tools, ``pywrapcp``): one vehicle from the start to the goal; a pickup node per
object and a delivery node per allowed (object, base) pair; ``AddPickupAndDeliverySets``
with one delivery chosen per object, a load dimension of capacity one (the gripper), one
disjunction per base of cardinality one (a base holds one object), moves outside the rules
removed from the ``NextVar`` domains. Going back to the start between deliveries is folded
into the arc cost (``min(C[b, o], C[b, start] + C[start, o])``) as the exact DP does; costs
are scaled to integers (1e6). Every decoded schedule is checked with ``score``.

Run: ``.venv/bin/python benchmarks/sched.py [--repeats 50]``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time

import jax
import numpy as np

from uvms_jax import sched
from uvms_jax.files import json_text

SCALE = 1_000_000  # OR-Tools arc costs are integers
THESIS_MS = {"greedy": sched.THESIS_SOLVER_MS["greedy"], "grasp_1000": sched.THESIS_SOLVER_MS["grasp"],
             "astar": sched.THESIS_SOLVER_MS["astar"]}  # thesis Table 5.5


def timed(fn, repeats: int) -> tuple[dict, object]:
    out = fn()  # warm-up
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return {"median_ms": 1e3 * statistics.median(ts), "min_ms": 1e3 * min(ts)}, out


def ortools_solve(problem: sched.PickPlaceProblem, time_limit_s: float | None) -> dict:
    """The pickup-and-delivery peer; ``time_limit_s=None``: first solution only."""
    try:
        from ortools.constraint_solver import pywrapcp, routing_enums_pb2
    except ImportError:
        return {"time_ms": None, "cost": None, "valid": False, "reason": "ortools not installed"}

    t0 = time.perf_counter()
    mc = np.asarray(problem.move_cost)
    s, g = problem.start, problem.goal
    objs = list(problem.objects)
    pairs = [(o, b) for o, bs in problem.compat.items() for b in bs if np.isfinite(mc[o, b])]
    # routing nodes: 0 start, 1 goal, objects, then (object, base) deliveries
    node = [("start", s, None), ("goal", g, None)] + [("pick", o, None) for o in objs] + [("drop", o, b) for o, b in pairs]
    pick_cost = np.minimum(mc, mc[:, [s]] + mc[[s], :])  # base → object, perhaps via the start
    R = len(node)
    arc = np.full((R, R), -1, dtype=np.int64)  # -1: not allowed
    for i, (ki, oi, bi) in enumerate(node):
        for j, (kj, oj, bj) in enumerate(node):
            if ki == "start" and kj == "pick":
                c = mc[s, oj]
            elif ki == "pick" and kj == "drop" and oj == oi:
                c = mc[oi, bj]
            elif ki == "drop" and kj == "pick" and oj != oi:
                c = pick_cost[bi, oj]
            elif ki == "drop" and kj == "goal":
                c = mc[bi, g]
            else:
                continue
            if np.isfinite(c):
                arc[i, j] = int(round(c * SCALE))
    manager = pywrapcp.RoutingIndexManager(R, 1, [0], [1])
    routing = pywrapcp.RoutingModel(manager)
    forbidden = int(arc.max()) * R + 1  # any route with such a move costs more than any without
    big = forbidden * R  # penalty of an object left out
    cost_cb = routing.RegisterTransitCallback(
        lambda a, b: int(arc[manager.IndexToNode(a), manager.IndexToNode(b)])
        if arc[manager.IndexToNode(a), manager.IndexToNode(b)] >= 0 else forbidden
    )
    routing.SetArcCostEvaluatorOfAllVehicles(cost_cb)
    load = [0, 0] + [1] * len(objs) + [-1] * len(pairs)
    load_cb = routing.RegisterUnaryTransitCallback(lambda a: load[manager.IndexToNode(a)])
    routing.AddDimensionWithVehicleCapacity(load_cb, 0, [1], True, "gripper")
    for b in problem.bases:  # a base holds one object: at most one of its drop nodes
        drops = [manager.NodeToIndex(i) for i, (k, _, bb) in enumerate(node) if k == "drop" and bb == b]
        if len(drops) > 1:
            routing.AddDisjunction(drops, 0, 1)
    for o in objs:
        pick = routing.AddDisjunction([manager.NodeToIndex(2 + objs.index(o))], big)
        drops = [manager.NodeToIndex(i) for i, (k, oo, _) in enumerate(node) if k == "drop" and oo == o]
        drop = routing.AddDisjunction(drops, big, 1)
        routing.AddPickupAndDeliverySets(pick, drop)
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PARALLEL_CHEAPEST_INSERTION
    if time_limit_s is not None:
        params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH
        params.time_limit.FromMilliseconds(int(time_limit_s * 1000))
    sol = routing.SolveWithParameters(params)
    wall = time.perf_counter() - t0
    if sol is None:
        return {"time_ms": 1e3 * wall, "cost": None, "valid": False}
    path, prev_base = [s], None
    i = routing.Start(0)
    while not routing.IsEnd(i):
        i = sol.Value(routing.NextVar(i))
        k, o, b = node[manager.IndexToNode(i)] if not routing.IsEnd(i) else ("goal", g, None)
        if k == "pick":
            if prev_base is not None and mc[prev_base, s] + mc[s, o] < mc[prev_base, o]:
                path.append(s)
            path.append(o)
        elif k == "drop":
            path.append(b)
            prev_base = b
        elif k == "goal":
            path.append(g)
    scores = sched.score(problem, sched.as_padded_paths([path], problem.max_path_len))
    valid = int(scores.reason[0]) == sched.Reason.OK
    return {"time_ms": 1e3 * wall, "cost": sched.path_cost(problem, path) if valid else None, "valid": valid, "reason": sched.Reason(int(scores.reason[0])).name,
            "path": "-".join(map(str, path))}


def numpy_score(problem: sched.PickPlaceProblem, paths: np.ndarray) -> np.ndarray:
    """The same validity checks and cost as ``score``, in NumPy (the scoring peer)."""
    n = problem.n_nodes
    p = np.where((paths < 0) | (paths >= n), n, paths)
    mc, rule = np.asarray(problem.move_cost), np.asarray(problem.rule)
    a, b = p[:, :-1], p[:, 1:]
    moves = mc[a, b]
    counts = np.stack([(p == v).sum(axis=1) for v in range(n)], axis=1)
    kind = np.asarray(problem.kind[:n])
    bad = (
        ((paths < -1) | (paths >= n)).any(axis=1)
        | (p[:, 0] != problem.start)
        | (counts[:, problem.goal] != 1)
        | ((counts[:, kind == 1] != 1).any(axis=1))
        | ((counts[:, kind == 2] > 1).any(axis=1))
        | ~rule[a, b].all(axis=1)
        | ~np.isfinite(moves).all(axis=1)
    )
    return np.where(bad, np.inf, moves.sum(axis=1))


def scoring(problem, batch: int, repeats: int) -> dict:
    rng = np.random.default_rng(0)
    b = sched.grasp_batch(jax.random.key(0), problem)
    base = np.where(np.asarray(b.paths) == problem.n_nodes, -1, np.asarray(b.paths))
    paths = base[rng.integers(0, len(base), batch)]
    shuffle = rng.random(batch) < 0.5  # half of them invalid
    perm = rng.random(paths.shape).argsort(axis=1)
    paths[shuffle] = np.take_along_axis(paths[shuffle], perm[shuffle], axis=1)
    dev = jax.device_put(paths)
    t_jax, out = timed(lambda: jax.block_until_ready(sched.score(problem, dev)), repeats)
    t_np, ref = timed(lambda: numpy_score(problem, paths), max(3, repeats // 5))
    assert np.allclose(np.asarray(out.cost), ref, rtol=1e-5)
    return {
        "batch": batch,
        "valid_fraction": float(np.isfinite(ref).mean()),
        "schedules_per_s": batch / (t_jax["median_ms"] / 1e3),
        "schedules_per_s_best": batch / (t_jax["min_ms"] / 1e3),
        "peer_numpy_schedules_per_s": batch / (t_np["median_ms"] / 1e3),
    }


def thesis(repeats: int) -> dict:
    p = sched.thesis_problem()
    out = {}
    t0 = time.perf_counter()
    sched.grasp(jax.random.key(0), p)
    out["grasp_compile_s"] = time.perf_counter() - t0
    keys = iter(jax.random.split(jax.random.key(1), 10 * repeats + 10))
    for name, fn, reps in (
        ("greedy", lambda: sched.greedy(p), 10 * repeats),
        ("grasp_1000", lambda: sched.grasp(next(keys), p, 1000), repeats),
        ("astar", lambda: sched.astar(p), 4 * repeats),
        ("exact", lambda: sched.exact(p), 4 * repeats),
    ):
        t, s = timed(fn, reps)
        out[name] = {**t, "cost": s.cost, "path": s.path_str()}
        if name in THESIS_MS:
            out[name]["thesis_ms"] = THESIS_MS[name]
    hits = [abs(sched.grasp(jax.random.key(100 + i), p).cost - out["exact"]["cost"]) < 1e-9 for i in range(20)]
    out["grasp_1000"]["optimum_found_fraction"] = float(np.mean(hits))
    out["ortools_first_solution"] = ortools_solve(p, None)
    out["ortools_gls_1s"] = ortools_solve(p, 1.0)
    return out


def large(repeats: int) -> dict:
    res = {}
    for label, bpo in (("10x10_1to3_bases", (1, 3)), ("10x10_all_bases", (10, 10))):
        p = sched.random_problem(jax.random.key(7), 10, 10, bases_per_object=bpo)
        t_exact, ex = timed(lambda: sched.exact(p), max(2, repeats // 20))
        sched.grasp(jax.random.key(0), p)  # compile
        runs = [sched.grasp(k, p) for k in jax.random.split(jax.random.key(1), max(5, repeats // 5))]
        g_ms = [1e3 * r.wall_time_s for r in runs]
        g_cost = [r.cost for r in runs]
        r = {
            "exact": {**t_exact, "cost": ex.cost, "states": ex.info["states"]},
            "grasp_1000": {"median_ms": statistics.median(g_ms), "min_ms": min(g_ms),
                           "gap_mean": float(np.mean(g_cost) / ex.cost - 1), "gap_best": float(min(g_cost) / ex.cost - 1)},
        }
        for name, lim in (("ortools_first_solution", None), ("ortools_gls_1s", 1.0), ("ortools_gls_5s", 5.0)):
            o = ortools_solve(p, lim)
            o["gap"] = (o["cost"] / ex.cost - 1) if o["cost"] is not None else None  # None: no valid schedule
            r[name] = o
        res[label] = r
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=50)
    ap.add_argument("--batch", type=int, default=1 << 17)
    args = ap.parse_args()
    t = thesis(args.repeats)
    sc = scoring(sched.thesis_problem(), args.batch, args.repeats // 5 or 1)
    lg = large(args.repeats)
    out = {
        "command": " ".join(["python benchmarks/sched.py", *sys.argv[1:]]),
        "device": f"{platform.machine()}, {len(__import__('os').sched_getaffinity(0))} CPUs, Python {platform.python_version()}, jax {jax.__version__}",
        "thesis_instance": t,
        "scoring": sc,
        "large": lg,
        "ratios": {
            "grasp_1000_vs_thesis": t["grasp_1000"]["median_ms"] / THESIS_MS["grasp_1000"],
            "astar_vs_thesis": t["astar"]["median_ms"] / THESIS_MS["astar"],
            "grasp_1000_vs_ortools_first_solution_time_10x10_all": lg["10x10_all_bases"]["grasp_1000"]["median_ms"]
            / (lg["10x10_all_bases"]["ortools_first_solution"]["time_ms"] or float("nan")),
            "scoring_vs_numpy": sc["schedules_per_s"] / sc["peer_numpy_schedules_per_s"],
        },
    }
    print(json_text(out))


if __name__ == "__main__":
    main()
