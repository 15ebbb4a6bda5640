"""Pick-and-place scheduling experiment (SPEC §5; thesis Tables 5.2–5.9, A.1–A.5, Figs 5.9–5.12).

Writes into the Hydra run directory:
  table.md, table.csv     Table-5.2-like: solver, path, cost, per-metric normalised sums, time
  results.json            source, weights, per-solver path/cost/time, GRASP sweep (for gathering)
  grasp_sweep.csv         GRASP cost and time versus iterations
  grasp_iterations.png    cost and time versus iterations, with greedy / A* / exact lines
  route.png               the best schedule drawn over the nodes
  schedule_edges.json     the moves of the best schedule (src, dst, action, object)

  python experiments/schedule.py
  python experiments/schedule.py sched/source=synthetic sched/weights=security
  python experiments/schedule.py --multirun sched/source=synthetic sched/weights=equal,speed,security
"""

from __future__ import annotations

import csv
import json
import logging
import math
from pathlib import Path

import hydra
import jax
import matplotlib
import numpy as np
from hydra.core.hydra_config import HydraConfig
from hydra.utils import to_absolute_path
from omegaconf import DictConfig

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from uvms_jax import sched  # noqa: E402

log = logging.getLogger(__name__)
CSV_METRICS = ("planning_time_s", "joint_movement", "ee_distance", "min_clearance", "max_torque")


def load_source(cfg: DictConfig, weights: list[float]):
    """``(problem, normalised metrics or None, note)`` from ``sched.source``."""
    src = cfg.sched.source
    compat = sched.THESIS_COMPAT if src.compat is None else {int(k): tuple(v) for k, v in src.compat.items()}
    if src.kind == "matrix":
        if src.matrix == "thesis_eq41":
            cost = np.array(sched.THESIS_EQ41)
        else:
            path = Path(to_absolute_path(src.matrix))
            cost = np.load(path) if path.suffix == ".npy" else np.genfromtxt(path, delimiter=",")
        problem = sched.PickPlaceProblem.from_matrix(cost, compat, start=src.start, goal=src.goal)
        return problem, None, "ready cost matrix: weights not used"
    if src.kind == "synthetic":
        layout = sched.PickPlaceProblem.from_matrix(_full_graph(compat), compat)
        raw = sched.random_metrics(jax.random.key(src.seed), layout, object_mass_kg=src.object_mass_kg)
        nm = sched.normalise_metrics(raw)
        problem = sched.PickPlaceProblem.from_matrix(sched.cost_matrix(nm, weights), compat)
        return problem, nm, f"synthetic metrics (seed {src.seed})"
    if src.kind == "edges_csv":
        raw = read_edges_csv(Path(to_absolute_path(src.path)), src.planner, src.n_nodes)
        goal = raw.shape[1] - 1 if src.goal is None else src.goal
        if src.mirror_goal:
            raw = sched.mirror_goal(raw, src.start, goal)
        nm = sched.normalise_metrics(raw)
        problem = sched.PickPlaceProblem.from_matrix(sched.cost_matrix(nm, weights), compat, src.start, goal)
        return problem, nm, f"{src.path} ({src.planner})"
    raise ValueError(f"unknown sched.source.kind {src.kind!r}: use matrix, synthetic or edges_csv")


def _full_graph(compat) -> np.ndarray:
    """A placeholder matrix (all moves 1) that only fixes the node layout."""
    n = 2 + len(compat) + len({b for bs in compat.values() for b in bs})
    return np.ones((n, n))


def read_edges_csv(path: Path, planner: str, n_nodes: int | None) -> np.ndarray:
    """Raw ``(5, n, n)`` metrics from a planner's ``edges.csv`` (failed plans → NaN)."""
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["planner"] == planner]
    if not rows:
        raise ValueError(f"{path}: no rows for planner {planner!r}")
    src = np.array([int(r["src"]) for r in rows])
    dst = np.array([int(r["dst"]) for r in rows])
    ok = np.array([r["success"].strip().lower() in ("1", "true", "yes") for r in rows])
    vals = np.array([[float(r[c]) if r[c] not in ("", "nan") else np.nan for c in CSV_METRICS] for r in rows])
    vals[~ok] = np.nan
    n = int(max(src.max(), dst.max()) + 1) if n_nodes is None else int(n_nodes)
    return sched.metric_tensor(src, dst, vals, n)


def solve_all(cfg: DictConfig, problem, key) -> dict[str, sched.Schedule]:
    """Each configured solver, timed ``timing_repeats`` times after a warm-up (median)."""
    g = grasp_kwargs(cfg)
    fns = {
        "greedy": lambda k: sched.greedy(problem),
        "grasp": lambda k: sched.grasp(problem, k, **g),
        "astar": lambda k: sched.astar(problem),
        "exact": lambda k: sched.exact(problem),
    }
    out = {}
    for name in cfg.sched.solvers:
        if name not in fns:
            raise ValueError(f"unknown solver {name!r}; choose from {sched.SOLVERS}")
        fns[name](key)  # warm-up (GRASP compiles here)
        runs = [fns[name](k) for k in jax.random.split(key, cfg.sched.timing_repeats)]
        best = runs[0]
        t = float(np.median([r.wall_time_s for r in runs]))
        out[name] = sched.Schedule(best.path, best.cost, t, name, dict(best.info))
        log.info("%-6s %-28s cost %.4f  %.4f ms", name, best.path_str(), best.cost, t * 1e3)
    return out


def grasp_kwargs(cfg: DictConfig, iterations: int | None = None) -> dict:
    g = cfg.sched.grasp
    kw = {"iterations": int(iterations or g.iterations)}
    if g.alphas is not None:
        kw["alphas"] = tuple(float(a) for a in g.alphas)
    if g.neighbourhood is not None:
        kw["neighbourhood"] = int(g.neighbourhood)
    if g.rounds is not None:
        kw["rounds"] = int(g.rounds)
    return kw


def grasp_sweep(cfg: DictConfig, problem, key) -> list[dict]:
    """GRASP cost (mean, min, max over repeats) and median time per iteration count."""
    rows = []
    for it in cfg.sched.iterations_sweep:
        kw = grasp_kwargs(cfg, it)
        sched.grasp(problem, key, **kw)  # compile this iteration count
        runs = [sched.grasp(problem, k, **kw) for k in jax.random.split(jax.random.fold_in(key, it), cfg.sched.sweep_repeats)]
        costs = [r.cost for r in runs]
        rows.append({
            "iterations": int(it),
            "cost_mean": float(np.mean(costs)),
            "cost_min": float(np.min(costs)),
            "cost_max": float(np.max(costs)),
            "time_ms": float(np.median([r.wall_time_s for r in runs]) * 1e3),
        })
        log.info("GRASP %5d it: cost %.4f (min %.4f)  %.3f ms", it, rows[-1]["cost_mean"], rows[-1]["cost_min"], rows[-1]["time_ms"])
    return rows


def table_rows(solved, nm, weights) -> list[dict]:
    rows = []
    for name, s in solved.items():
        row = {"solver": name, "path": s.path_str(), "cost": s.cost, "time_ms": s.wall_time_s * 1e3}
        sums = sched.path_metric_sums(nm, s.path) if (nm is not None and s.feasible) else [math.nan] * 5
        for m, k, v in zip(sched.METRICS, weights, sums):
            row[f"K_{m}"] = k
            row[f"N_{m}"] = float(v)
        rows.append(row)
    return rows


def write_table(out: Path, rows: list[dict], note: str) -> None:
    with open(out / "table.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = [f"Source: {note}", "", "| solver | path | metric | K | N_metric | C_final | time [ms] |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        for i, m in enumerate(sched.METRICS):
            n = r[f"N_{m}"]
            head = (r["solver"], r["path"]) if i == 0 else ("", "")
            tail = (f"{r['cost']:.4f}", f"{r['time_ms']:.4f}") if i == 0 else ("", "")
            n_txt = "—" if math.isnan(n) else f"{n:.3f}"
            lines.append(f"| {head[0]} | {head[1]} | {m} | {r[f'K_{m}']:.3g} | {n_txt} | {tail[0]} | {tail[1]} |")
    (out / "table.md").write_text("\n".join(lines) + "\n")


def plot_sweep(out: Path, rows: list[dict], solved) -> None:
    it = [r["iterations"] for r in rows]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    a.plot(it, [r["cost_mean"] for r in rows], "o-", label="GRASP (mean)")
    a.fill_between(it, [r["cost_min"] for r in rows], [r["cost_max"] for r in rows], alpha=0.2, label="GRASP (min–max)")
    b.plot(it, [r["time_ms"] for r in rows], "o-", label="GRASP")
    for name, style in (("greedy", "r--"), ("astar", "g--"), ("exact", "k:")):
        if name in solved:
            a.axhline(solved[name].cost, color=style[0], ls=style[1:], label=name)
            b.axhline(solved[name].wall_time_s * 1e3, color=style[0], ls=style[1:], label=name)
    a.set(xscale="log", xlabel="GRASP iterations", ylabel="schedule cost", title="Cost vs iterations (Figs 5.9–5.10)")
    b.set(xscale="log", yscale="log", xlabel="GRASP iterations", ylabel="wall time [ms]", title="Time vs iterations (Figs 5.11–5.12)")
    a.legend()
    b.legend()
    fig.tight_layout()
    fig.savefig(out / "grasp_iterations.png", dpi=120)
    plt.close(fig)


def plot_route(out: Path, problem, schedule: sched.Schedule, greedy: sched.Schedule | None) -> None:
    """Schematic layout: start/goal left, objects in the middle column, bases on the right."""
    pos = {problem.start: (0.0, 0.5), problem.goal: (0.0, -0.5)}
    for k, o in enumerate(problem.objects):
        pos[o] = (1.0, 1.5 - 3.0 * k / max(problem.n_objects - 1, 1))
    for k, b in enumerate(problem.bases):
        pos[b] = (2.0, 1.5 - 3.0 * k / max(problem.n_bases - 1, 1))
    names = sched.THESIS_NODE_NAMES if problem.n_nodes == len(sched.THESIS_NODE_NAMES) else None
    fig, ax = plt.subplots(figsize=(7, 5))
    for v, (x, y) in pos.items():
        ax.plot(x, y, "o", ms=20, color="lightsteelblue")
        ax.annotate(str(v), (x, y), ha="center", va="center")
        if names:
            ax.annotate(names[v], (x, y - 0.22), ha="center", fontsize=7)
    for s, style, label in ((greedy, ("tab:red", 0.15, "--"), "greedy"), (schedule, ("tab:blue", -0.15, "-"), schedule.solver)):
        if s is None or not s.feasible:
            continue
        for i, (a, b) in enumerate(zip(s.path[:-1], s.path[1:])):
            ax.annotate("", xy=pos[b], xytext=pos[a],
                        arrowprops={"arrowstyle": "->", "color": style[0], "ls": style[2],
                                    "connectionstyle": f"arc3,rad={style[1]}", "shrinkA": 12, "shrinkB": 12})
        ax.plot([], [], color=style[0], ls=style[2], label=f"{label}: {s.path_str()} ({s.cost:.3f})")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), fontsize=8)
    ax.set_axis_off()
    ax.set_title("Chosen route")
    fig.tight_layout()
    fig.savefig(out / "route.png", dpi=120)
    plt.close(fig)


def run(cfg: DictConfig, out: Path) -> dict:
    """The whole experiment for one config; files go to ``out``. Returns results.json's dict."""
    out.mkdir(parents=True, exist_ok=True)
    w = cfg.sched.weights
    weights = [float(w[m]) for m in sched.METRICS]
    key = jax.random.key(cfg.seed)
    problem, nm, note = load_source(cfg, weights)
    if nm is None:
        log.warning("%s; the weights %s are ignored", note, w.name)
    solved = solve_all(cfg, problem, key)
    best = min(solved.values(), key=lambda s: s.cost)
    rows = table_rows(solved, nm, weights)
    write_table(out, rows, note)
    sweep = grasp_sweep(cfg, problem, key) if cfg.sched.iterations_sweep else []
    if sweep:
        with open(out / "grasp_sweep.csv", "w", newline="") as f:
            wr = csv.DictWriter(f, fieldnames=list(sweep[0]))
            wr.writeheader()
            wr.writerows(sweep)
    edges = [e._asdict() for e in sched.schedule_edges(problem, best.path)]
    (out / "schedule_edges.json").write_text(json.dumps(edges, indent=1))
    results = {
        "source": note,
        "weights_name": w.name,
        "weights": dict(zip(sched.METRICS, weights)),
        "weights_used": nm is not None,
        "optimal_cost": solved["exact"].cost if "exact" in solved else None,
        "solvers": {r["solver"]: r for r in rows},
        "grasp_sweep": sweep,
        "jax": jax.__version__,
    }
    (out / "results.json").write_text(json.dumps(results, indent=1))
    if cfg.sched.plots:
        if sweep:
            plot_sweep(out, sweep, solved)
        plot_route(out, problem, best, solved.get("greedy"))
    log.info("results in %s", out)
    return results


@hydra.main(version_base="1.3", config_path="../configs", config_name="schedule")
def main(cfg: DictConfig) -> None:
    run(cfg, Path(HydraConfig.get().runtime.output_dir))


if __name__ == "__main__":
    main()
