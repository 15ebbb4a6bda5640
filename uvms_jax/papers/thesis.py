"""The thesis [T22]: Tables 5.2–5.9, A.1–A.5 and Figs 5.8–5.12, the thesis's numbers beside ours.

Our instances are the thesis cage planned here with the planners of Tables 5.2–5.4, or an
edges.csv of experiments/plan.py. An instance is a raw ``(5, n, n)`` metric array in
``sched.METRICS`` order (planning time [s], joint movement [rad], EE distance [m], min
clearance [m], max torque [N·m]), NaN where no move; the thesis prints only sums of the
min–max normalised metrics along a path (N, eq. 4.15) and their weighted sum C = Σ K·N.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import jax
import numpy as np

from uvms_jax import progress
from uvms_jax.papers._data import T22_PLANNER_TABLES, T22_SCENARIO_TABLES, T22_TABLES
from uvms_jax.papers._preset import Preset, save_figure
from uvms_jax.pipeline import md_table
from uvms_jax.plotting import pyplot

#: Thesis algorithm name → our solver name.
SOLVER_OF = {"Dijkstra": "greedy", "GRASP": "grasp", "A*": "astar"}
METRIC_LABELS = ("planning time", "joint movement", "EE distance", "security", "max torque")
#: Metric keys of a schedule row (``N_<key>``), in the order of METRIC_LABELS.
METRIC_KEYS = ("planning_time", "joint_movement", "ee_distance", "security", "max_torque")


def weights(configs: Path, name: str):
    """The weight scenario ``configs/sched/weights/<name>.yaml``: ``sched.WeightSettings``."""
    import yaml

    from uvms_jax import sched

    return sched.WeightSettings(**yaml.safe_load((configs / "sched" / "weights" / f"{name}.yaml").read_text()))


def plan_thesis_cage(configs: Path, budget_s: float):
    """The thesis cage (``configs/scenario/thesis_cage.yaml``) planned with the three planners of
    Tables 5.2–5.4 under ``configs/plan/default.yaml``, ``budget_s`` [s] per edge:
    ``uvms_jax.plan.TaskGraphPlan``."""
    import yaml

    from uvms_jax import plan as P
    from uvms_jax.settings import from_mapping

    mapping = yaml.safe_load((configs / "plan" / "default.yaml").read_text())
    mapping.update(planners=list(T22_PLANNER_TABLES), budget_s=float(budget_s), render=False)
    settings = from_mapping(P.PlanSettings, mapping, "plan")
    scenario = yaml.safe_load((configs / "scenario" / "thesis_cage.yaml").read_text())
    scene = P.build_scene(P.scenario_robot(scenario), scenario)
    return P.plan_task_graph(jax.random.PRNGKey(settings.seed), scene, settings)


@dataclasses.dataclass(frozen=True)
class Instance:
    """One planner's scheduling instance: raw ``(5, n, n)`` metrics (``sched.METRICS`` order,
    NaN = no move), where they come from, the edges attempted and how many of them are one straight
    joint-space segment (``None``: not known, e.g. read from an edges.csv)."""

    planner: str
    raw: np.ndarray
    note: str
    attempted: int | None = None
    straight: int | None = None


def thesis_instances(edges: Path | None, budget_s: float,
                     configs: Path | None = None) -> tuple[dict[str, Instance], dict[str, str], object]:
    """Per planner of ``T22_PLANNER_TABLES``, its instance: from ``edges`` (an edges.csv of
    experiments/plan.py) or, when ``None``, from planning the thesis cage of ``configs`` (the
    repository's configs/ folder) here with ``budget_s`` [s] per edge. Returns the instances,
    per planner left out why, and the ``uvms_jax.plan.TaskGraphPlan`` planned here (None when
    read from ``edges``)."""
    from uvms_jax import sched

    if edges is None:
        tp = plan_thesis_cage(configs, budget_s)
        return {pl: Instance(pl, tp.metrics[pl], f"the thesis cage planned here with {pl}, {budget_s:g} s per edge",
                             tp.summary[pl].edges, sum(len(r.plan.path) == 2 for r in tp.by_planner[pl]))
                for pl in T22_PLANNER_TABLES}, {}, tp
    out, missing = {}, {}
    for pl in T22_PLANNER_TABLES:
        try:
            out[pl] = Instance(pl, sched.read_edges_csv(edges, pl), f"our {pl} edges (`{edges.name}`)")
        except ValueError as e:  # the edges hold no rows of this planner
            missing[pl] = str(e)
    return out, missing, None


def executed_tool_paths(task_plan, run, img: Path) -> tuple[str, dict]:
    """[T22] Fig. 5.14: the optimum schedule of our RRTConnect instance (``run``, a
    ``sched.ScheduleRun``) as a plan, executed on the simulated arm over the BPL protocol; the
    planned tool path (the plan's waypoints every 0.01 rad) against the tool positions of the
    measured joint states → PNG. Returns the figure and ``{"status", "gates", "max_mm",
    "p95_mm"}``: the run's end, its gates, and the largest and 95th-percentile distance of an
    executed tool position from the planned path [mm]."""
    from uvms_jax import hw, kin
    from uvms_jax import plan as P

    scene = task_plan.scene
    path = run.solved["exact"].path if "exact" in run.solved else run.best.path
    the_plan = P.plan_for_schedule(task_plan, "RRTConnect", path)
    sim = hw.SimConfig() if the_plan.base_rpy is None else dataclasses.replace(hw.SimConfig(), base_rpy=the_plan.base_rpy)
    done = hw.run_plan(the_plan, scene.robot, link="loopback", sim=sim)
    _, q_run = done.log.measured(scene.robot.joint_names)
    q_plan = np.concatenate([P.densify(np.asarray(s.q), 0.01) for s in the_plan.segments if len(s.q)])

    def world(q):  # tool positions in the world [m]
        p = np.asarray(kin.fk(scene.robot.chain, np.asarray(q)))[:, :3, 3]
        return p @ scene.T_world_base[:3, :3].T + scene.T_world_base[:3, 3]

    planned, executed = world(q_plan), world(q_run)
    gap = np.min(np.linalg.norm(executed[:, None] - planned[None], axis=-1), axis=1) * 1e3  # (k,) [mm]
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), layout="constrained")
    for ax, (i, j, label) in zip(axes, ((0, 1, "top view: x, y"), (0, 2, "side view: x, z"))):
        ax.plot(planned[:, i], planned[:, j], "-", color="tab:blue", lw=1.2, label="planned")
        ax.plot(executed[::5, i], executed[::5, j], ".", color="tab:orange", ms=2, label="executed (simulated arm)")
        for n in scene.objects:
            c = scene.T_world_object(n)[:3, 3]
            ax.plot(c[i], c[j], "ks", ms=5, label="objects" if n == min(scene.objects) else None)
        for n in scene.bases:
            c = scene.T_world_base_top(n)[:3, 3]
            ax.plot(c[i], c[j], "g^", ms=6, label="bases" if n == min(scene.bases) else None)
        ax.set(xlabel="xyz"[i] + " [m]", ylabel="xyz"[j] + " [m]", title=label, aspect="equal")
    axes[0].legend(fontsize=8, loc="best")
    fig.suptitle(f"Fig. 5.14: schedule {'-'.join(map(str, path))} planned and executed (max deviation "
                 f"{gap.max():.1f} mm)")
    return save_figure(fig, img, "thesis_fig5_14.png"), {
        "status": done.status, "gates": len(done.result.gates), "max_mm": float(gap.max()),
        "p95_mm": float(np.percentile(gap, 95))}


def _run(inst: Instance, w, local_search: str = "deliveries", solvers=("greedy", "grasp", "astar", "exact"),
         repeats=5):
    """``sched.run_schedule`` of ``inst`` under weights ``w`` (GRASP with ``local_search``)."""
    from uvms_jax import sched

    s = sched.SchedSettings(weights=w, solvers=tuple(solvers), grasp=sched.GraspSettings(local_search=local_search),
                            timing_repeats=repeats, iterations_sweep=())
    return sched.run_schedule(jax.random.key(0), s, inst.raw, note=inst.note)


def thesis_path_sums(table: str, normalised) -> dict[str, tuple[np.ndarray, float]]:
    """Each thesis path of ``table`` on our instance (``(5, n, n)`` normalised metrics):
    algorithm → ``(5,)`` normalised metric sums and its cost Σ K·N (NaN where a move of the
    path has no metrics)."""
    from uvms_jax import sched

    out = {}
    for alg, path, K, *_ in T22_TABLES[table]:
        sums = sched.path_metric_sums(normalised, [int(v) for v in path.split("-")])
        out[alg] = (sums, float(np.dot(K, sums)))
    return out


def thesis_table(table: str, runs: dict, normalised=None) -> str:
    """One thesis table in its layout (algorithm, path, metric, K, N, C), thesis beside ours.

    ``runs``: label → ScheduleRun (ours; rows per solver). ``normalised``: ``(5, n, n)``
    normalised metrics of our instance; when given, two more columns hold the thesis's path
    scored on it (N and C)."""
    on_ours = thesis_path_sums(table, normalised) if normalised is not None else {}
    rows = []
    for alg, path, K, N, C, _ in T22_TABLES[table]:
        ours = [next((r for r in run.rows if r["solver"] == SOLVER_OF[alg]), None) for run in runs.values()]
        for m, label in enumerate(METRIC_LABELS):
            first = m == 0
            row = [alg if first else "", path if first else "", label, f"{K[m]:g}", f"{N[m]:.3f}",
                   f"{C:.3f}" if first else ""]
            if on_ours:
                sums, cost = on_ours[alg]
                row += [f"{sums[m]:.3f}", f"{cost:.3f}" if first else ""]
            for r in ours:
                if r is None:  # this run did not use the solver
                    row += ["—" if first else "", "", ""]
                    continue
                row += [r["path"] if first else "", f"{r[f'N_{METRIC_KEYS[m]}']:.3f}",
                        f"{r['cost']:.3f}" if first else ""]
            rows.append(row)
    head = ["algorithm", "thesis path", "metric", "K", "thesis N", "thesis C"]
    if on_ours:
        head += ["thesis path on ours: N", "thesis path on ours: C"]
    for lab in runs:
        head += [f"{lab}: path", f"{lab}: N", f"{lab}: C"]
    return md_table(head, rows)


def _and(words: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return " and ".join([", ".join(words[:-1]), words[-1]]) if len(words) > 1 else "".join(words)


def _returns(path: str) -> int:
    """How often a schedule goes back to the start node 0 between deliveries."""
    return path.split("-")[1:-1].count("0")


def planner_differences(table: str, run, thesis_ls) -> str:
    """The differences between a thesis table of 5.2–5.4 and ours, each with its reason
    (Markdown bullets computed from the runs)."""
    rows = {r["solver"]: r for r in run.rows}
    on_ours = thesis_path_sums(table, run.normalised)
    thesis = {r[0]: r for r in T22_TABLES[table]}
    opt = run.optimal_cost
    out = []
    for alg in ("Dijkstra", "GRASP", "A*"):
        _, path, _, _, C, _ = thesis[alg]
        r = rows[SOLVER_OF[alg]]
        if r["path"] == path:
            what = "the thesis's path"
        else:
            what = (f"another path than the thesis's, which costs {on_ours[alg][1]:.3f} on our instance "
                    f"(ours {r['cost']:.3f})")
        if alg == "Dijkstra":
            extra = (f"; it returns to the start {_returns(r['path'])} times (thesis: {_returns(path)}): with no "
                     "look-ahead the cheapest next move out of a base is at times the one home")
        else:
            ls = "" if alg == "A*" else (f", with the thesis's local search {thesis_ls.rows[0]['cost']:.3f}")
            extra = (f"; cost {r['cost']:.3f}{ls}, the exact optimum {opt:.3f}"
                     + (" (optimal)" if abs(r["cost"] - opt) < 1e-9 else ""))
        out.append(f"- **{alg}**: {what}{extra}.")
    g, a = thesis["GRASP"][4], thesis["A*"][4]
    both = all(abs(rows[k]["cost"] - opt) < 1e-9 for k in ("grasp", "astar"))
    out.append(f"- **GRASP against A***: the thesis's A* is {g - a:.3f} below its GRASP; "
               + ("ours are equal and optimal: our A* is exact and our GRASP (1000 iterations, delivery swaps) "
                  "finds the optimum of a graph this small." if both else
                  f"ours: GRASP {rows['grasp']['cost']:.3f}, A* {rows['astar']['cost']:.3f}."))
    return "\n".join(out)


def plot_sweeps(sweeps: dict, lines: dict, img: Path, name: str, title: str) -> str:
    """[T22] Figs 5.9–5.12: GRASP cost and time against iterations, per local search → PNG.

    ``lines``: solver name → (cost, median time [ms]) drawn as horizontal lines."""
    plt = pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4), layout="constrained")
    colors = {"thesis": "tab:purple", "deliveries": "tab:blue"}
    for ls, pts in sweeps.items():
        it = [p.iterations for p in pts]
        lab = "GRASP, thesis local search" if ls == "thesis" else "GRASP, our local search"
        a.plot(it, [p.cost_mean for p in pts], "o-", color=colors[ls], ms=3, label=f"{lab} (mean)")
        a.fill_between(it, [p.cost_min for p in pts], [p.cost_max for p in pts], color=colors[ls], alpha=0.15,
                       label=f"{lab} (min–max over the runs)")
        b.plot(it, [p.time_ms for p in pts], "o-", color=colors[ls], ms=3, label=lab)
    for n, style, lab in (("greedy", ("tab:red", "--"), "greedy (thesis: Dijkstra)"),
                          ("astar", ("tab:green", "-."), "A*"), ("exact", ("k", ":"), "exact (DP)")):
        if n in lines:
            a.axhline(lines[n][0], color=style[0], ls=style[1], label=lab)
            b.axhline(lines[n][1], color=style[0], ls=style[1], label=lab)
    a.set(xscale="log", xlabel="GRASP iterations", ylabel="schedule cost (Σ K·N)",
          title="Cost vs iterations (Figs 5.9, 5.10)")
    b.set(xscale="log", yscale="log", xlabel="GRASP iterations", ylabel="wall time [ms]",
          title="Time vs iterations (Figs 5.11, 5.12)")
    handles, labels = a.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8)
    fig.suptitle(title)
    return save_figure(fig, img, name)


def plot_final_costs(per_planner: dict, img: Path, xlabel: str) -> str:
    """[T22] Fig. 5.8: final cost of the three algorithms per planner, thesis beside ours → PNG."""
    plt = pyplot()
    planners = list(T22_PLANNER_TABLES)
    fig, ax = plt.subplots(figsize=(9, 4), layout="constrained")
    width = 0.13
    for k, alg in enumerate(("Dijkstra", "GRASP", "A*")):
        thesis = [next(r[4] for r in T22_TABLES[T22_PLANNER_TABLES[p]] if r[0] == alg) for p in planners]
        ours = [next((r["cost"] for r in per_planner[p].rows if r["solver"] == SOLVER_OF[alg]), np.nan)
                if p in per_planner else np.nan for p in planners]
        x = np.arange(len(planners)) + (k - 1) * 2.2 * width
        ax.bar(x - width / 2, thesis, width, color=f"C{k}", alpha=0.45, label=f"{alg}, thesis")
        ax.bar(x + width / 2, ours, width, color=f"C{k}", hatch="//", label=f"{alg}, ours")
    ax.set_xticks(np.arange(len(planners)), planners)
    ax.set(xlabel=xlabel, ylabel="final cost C (Σ K·N, equal weights)",
           title="Final costs of the three algorithms (Fig. 5.8)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    return save_figure(fig, img, "thesis_fig5_8.png")


def instance_table(instances: dict[str, Instance]) -> str:
    """Per planner: moves planned, straight ones, and the range of each raw metric (Markdown)."""
    from uvms_jax import sched

    def span(x, fmt="{:.3g}"):
        return f"{fmt.format(np.min(x))}–{fmt.format(np.max(x))}" if x.size else "—"

    rows = []
    for pl, inst in instances.items():
        raw = inst.raw
        edge = np.all(np.isfinite(raw), axis=0)
        held = edge & np.isin(np.arange(raw.shape[1]), list(sched.THESIS_COMPAT))[:, None]  # moves out of an object
        t = raw[0][edge] * 1e3
        rows.append([pl, f"{edge.sum()}" + (f" of {inst.attempted}" if inst.attempted else ""),
                     "—" if inst.straight is None else str(inst.straight),
                     f"{np.median(t):.3g} / {t.max():.3g}", span(raw[1][edge]), span(raw[2][edge]),
                     span(raw[3][edge]), f"{span(raw[4][edge & ~held])} / {span(raw[4][held])}"])
    return md_table(["planner", "moves planned", "straight segments", "planning time median / max [ms]",
                     "joint movement [rad]", "EE distance [m]", "min clearance [m]",
                     "max torque [N·m]: empty moves / holding an object"], rows)


def thesis_why(instances: dict[str, Instance], runs: dict, same_geometry: bool) -> str:
    """The reasons why Tables 5.2–5.4 differ from ours, with the numbers that show them (Markdown)."""
    from uvms_jax import sched

    if not runs:
        return ""
    run = runs.get("RRTConnect") or next(iter(runs.values()))
    inst = instances.get("RRTConnect") or next(iter(instances.values()))
    table = T22_PLANNER_TABLES[inst.planner]
    best_thesis = min(c for _, c in thesis_path_sums(table, run.normalised).values())
    bullets = ["- *The instance.* The thesis prints per-path sums of normalised metrics, never the "
               "per-move values, so its instances cannot be rebuilt. Its cage is rebuilt here from its "
               "description (the positions of the tables and the incline are our defaults), so which "
               "delivery is cheapest first is our own: on our " + inst.planner + " instance the best of the "
               f"thesis's schedules costs {best_thesis:.3f} against the optimum {run.optimal_cost:.3f} "
               "(columns \"thesis path on ours\")."]
    if same_geometry:
        straight = (f" ({inst.straight} of {inst.attempted} moves)" if inst.straight is not None else "")
        bullets.append(
            "- *The planners.* Every move of our cage is free along the straight joint-space segment"
            f"{straight}, and each planner's own path, simplified by OMPL's `simplifySolution` (no shortcut "
            "of ours: `plan.straight_shortcut` is off here), ends as that segment, so the three planners give "
            "the same paths: joint movement, EE distance, security and torque are the same in all three tables "
            "and only planning time differs. The thesis's tables show nearly the same: its A* path has "
            "N = 1.200–1.201, 2.597–2.598, 2.788–2.791 and 5.280–5.281 for those four metrics under all "
            "three planners.")
    med = [float(np.nanmedian(i.raw[0])) * 1e3 for i in instances.values()]
    dij = np.array([next(r[3] for r in T22_TABLES[t] if r[0] == "Dijkstra") for t in T22_PLANNER_TABLES.values()])
    spread = np.ptp(dij, axis=0)
    bullets.append(
        f"- *Planning time.* Ours takes milliseconds per move (medians {min(med):.2g}–{max(med):.2g} ms) and "
        "changes from run to run (OMPL's random sampling, the machine's load); min–max normalisation (eq. 4.15) "
        "stretches it to [0, 1] like any other metric, so it still moves the schedule. It is the metric "
        f"that sets the thesis's planners apart too: the same Dijkstra path has N = {dij[:, 0].min():.3f}–"
        f"{dij[:, 0].max():.3f} under its three planners, while its other four sums change by at most "
        f"{spread[1:].max():.3f}.")
    nm = run.normalised
    edge = np.all(np.isfinite(nm), axis=0)
    best = run.solved["exact"].path if "exact" in run.solved else run.best.path
    moves = len(best) - 1
    along = sched.path_metric_sums(nm, best) / moves
    a_star = next(r for r in T22_TABLES["5.2"] if r[0] == "A*")
    a_star_moves = len(a_star[1].split("-")) - 1
    thesis_along = np.array(a_star[3]) / a_star_moves
    rows = [[label, f"{np.median(nm[k][edge]):.2f}", f"{along[k]:.2f}", f"{thesis_along[k]:.2f}"]
            for k, label in enumerate(METRIC_LABELS)]
    moves_raw = np.all(np.isfinite(inst.raw), axis=0)
    torque = inst.raw[4][moves_raw]
    dear = [label for k, label in enumerate(METRIC_LABELS) if np.median(nm[k][edge]) > 0.5]
    thesis_best = min(r[4] for r in T22_TABLES[table])
    bullets.append(
        "- *Torque.* Like the thesis's, our max-torque metric counts the arm's own weight and buoyancy "
        f"besides the held object (theory §5): every move has torque ({torque.min():.1f}–{torque.max():.1f} N·m "
        "here; the held object adds less than 0.6 N·m), so torque sums grow with the number of moves in both.")
    levels = (
        "**The levels of N.** Each metric is normalised by its own minimum and maximum over all moves of "
        f"the instance, so the sums depend on where most moves lie in that range. Ours ({inst.planner}) "
        "against the thesis's, per move:\n\n"
        + md_table(["metric", "ours: median N over all moves", f"ours: mean N along our optimum ({moves} moves)",
                    f"thesis: mean N along its A* path (Table 5.2, {a_star_moves} moves)"], rows)
        + f"\n\nMost of our moves lie in the dear half of the range of {_and(dear) or 'no metric'} "
        "(median N above 0.5), which therefore weigh more in our sums than in the thesis's; our optimum "
        f"costs {run.optimal_cost:.3f} against the thesis's best {thesis_best:.3f} (Table {table}).")
    bullets.append(
        "- *The algorithms.* Our A* is optimal on every tested instance (checked against the exact DP and "
        "brute force); the thesis's is not (Table A.1: 2.164 against GRASP's 1.991; A.5: 5.242 against 4.755). "
        "Compare the rankings, which agree: greedy worst, GRASP and A* at or near the optimum.")
    return "**Why they differ, in all three tables:**\n\n" + "\n".join(bullets) + "\n\n" + levels


def _table55(timing: dict, per_planner: dict, thesis_ls_runs: dict) -> str:
    """Table 5.5: the thesis's timing beside ours on our RRTConnect instance and on eq. 4.1.

    ``timing``: (solver, local search) → (a solved schedule, median time [ms], optimal runs of 20)."""
    paper55 = {r[0]: r for r in T22_TABLES["5.5"]}

    def on_rrt(name, ls):  # path / C / ms of a solver on our RRTConnect instance (Table 5.2's runs)
        run = (thesis_ls_runs if ls == "thesis" else per_planner).get("RRTConnect")
        r = next((r for r in run.rows if r["solver"] == name), None) if run else None
        return f"{r['path']} / {r['cost']:.3f} / {r['time_ms']:.3g}" if r else "—"

    rows = []
    for label, alg, k in (("greedy (Dijkstra)", "Dijkstra", ("greedy", None)),
                          ("GRASP 1000, thesis local search", "GRASP", ("grasp", "thesis")),
                          ("GRASP 1000, our local search", None, ("grasp", "deliveries")),
                          ("A*", "A*", ("astar", None)), ("exact DP", None, ("exact", None))):
        thesis = f"{paper55[alg][1]} / {paper55[alg][4]:.3f} / {paper55[alg][5]:g}" if alg else "—"
        solved, ms, optimal = timing[k]
        rows.append([label, thesis, on_rrt(*k), f"{solved.path_str()} / {solved.cost:.4f} / {ms:.3g}",
                     f"{optimal}/20"])
    return md_table(["algorithm", "thesis (its RRTConnect instance): path / C / ms",
                     "ours (our RRTConnect instance, median of 5): path / C / ms",
                     "ours (eq. 4.1 matrix, median of 20): path / C / ms", "ours, eq. 4.1: optimal in 20 runs"], rows)


def _scenario_table(rrt: Instance, configs: Path, scen: str, table: str) -> str:
    """One weight-scenario table (5.6–5.9, A.1–A.5): the thesis's beside ours on ``rrt``."""
    run = _run(rrt, weights(configs, scen), repeats=1)
    rows = []
    for alg, path, K, N, C, _ in T22_TABLES[table]:
        r = next(r for r in run.rows if r["solver"] == SOLVER_OF[alg])
        rows.append([alg, path, " / ".join(f"{v:.3f}" for v in N), f"{C:.3f}", f"{float(np.dot(K, N)):.3f}",
                     r["path"], " / ".join(f"{r[f'N_{k}']:.3f}" for k in METRIC_KEYS), f"{r['cost']:.3f}"])
    return (f"**Table {table} — weights `{scen}`** (K = {' / '.join(f'{v:g}' for v in T22_TABLES[table][0][2])})\n\n"
            + md_table(["algorithm", "thesis path", "thesis N (5 metrics)", "thesis C", "thesis Σ K·N",
                        "our path", "our N", "our C"], rows))


def thesis_fields(p: Preset, img: Path, edges: Path | None, configs: Path) -> dict:
    """The [T22] section's tables, figures and numbers: the fields of its template
    (experiments/papers_templates/thesis.md). Our instances are the thesis cage of ``configs``
    (the repository's configs/ folder, which also holds the weight scenarios) planned here with
    the three planners (``p.plan_budget_s`` per edge), or ``edges`` (an edges.csv) when given."""
    from uvms_jax import sched

    t0 = time.perf_counter()
    instances, missing, task_plan = thesis_instances(edges, p.plan_budget_s, configs)
    t_plan = time.perf_counter() - t0
    equal = weights(configs, "equal")
    # Tables 5.2–5.4: one instance per planner.
    per_planner, thesis_ls_runs, planner_md = {}, {}, []
    for planner, table in T22_PLANNER_TABLES.items():
        if planner not in instances:
            planner_md.append(f"**Table {table} ({planner})**: not computed — {missing[planner]}")
            continue
        inst = instances[planner]
        per_planner[planner] = run = _run(inst, equal)
        thesis_ls_runs[planner] = thesis_ls = _run(inst, equal, "thesis", solvers=("grasp",))
        planner_md.append(f"**Table {table} — {planner}** (ours: {inst.note}; GRASP 1000 iterations, our local "
                          f"search and the thesis's; the exact optimum is {run.optimal_cost:.3f})\n\n"
                          + thesis_table(table, {"ours": run, "ours, thesis LS": thesis_ls}, run.normalised)
                          + "\n\n" + planner_differences(table, run, thesis_ls))
    fig58 = plot_final_costs(per_planner, img, "motion planner")
    if task_plan is not None and "RRTConnect" in per_planner:
        fig514, executed = executed_tool_paths(task_plan, per_planner["RRTConnect"], img)
        fig514_md = (f"![Fig. 5.14]({fig514})\n\nThe optimum of our RRTConnect instance, executed on the simulated "
                     f"arm over the BPL protocol: {executed['status']}, {executed['gates']} gates reached. Every "
                     f"measured tool position lies within {executed['max_mm']:.1f} mm of the planned path (95 %: "
                     f"{executed['p95_mm']:.1f} mm).")
    else:
        fig514_md = "Not computed: it needs the thesis cage planned here (no `--edges`)."
    # Metrics other than planning time that agree between the planners (same paths).
    first = next(iter(instances.values())) if instances else None
    same_geometry = first is not None and len(instances) > 1 and all(
        np.allclose(i.raw[1:], first.raw[1:], equal_nan=True, atol=1e-9) for i in instances.values())

    # Table 5.5 and Figs 5.9–5.12 on the eq. 4.1 matrix (the thesis's worked example).
    problem = sched.thesis_problem()
    key = jax.random.key(0)
    solved = {n: sched.solve(key, problem, n) for n in ("greedy", "astar", "exact")}
    timing = {}
    for name, ls in (("greedy", None), ("grasp", "deliveries"), ("grasp", "thesis"), ("astar", None),
                     ("exact", None)):
        gs = sched.GraspSettings(local_search=ls or "deliveries")
        sched.solve(key, problem, name, gs)
        runs = [sched.solve(k, problem, name, gs) for k in jax.random.split(key, 20)]
        timing[(name, ls)] = (runs[0], float(np.median([r.wall_time_s for r in runs])) * 1e3,
                              sum(r.cost <= solved["exact"].cost + 1e-9 for r in runs))
    t55 = _table55(timing, per_planner, thesis_ls_runs)
    # Figs 5.9–5.12 as the thesis ran them: on its RRTConnect instance (ours), over its
    # iteration grid (the preset's); the eq. 4.1 matrix when there is no RRTConnect instance.
    rrt_run = per_planner.get("RRTConnect")
    sweep_problem = rrt_run.problem if rrt_run else problem
    sweep_on = "our RRTConnect instance" if rrt_run else "the eq. 4.1 matrix"
    sweeps = {}
    for ls in ("thesis", "deliveries"):
        s = sched.SchedSettings(grasp=sched.GraspSettings(local_search=ls), iterations_sweep=p.grasp_sweep,
                                sweep_repeats=p.sweep_repeats)
        sweeps[ls] = sched.grasp_sweep(key, sweep_problem, s)
    if rrt_run:
        rows = {r["solver"]: r for r in rrt_run.rows}
        lines = {n: (rows[n]["cost"], rows[n]["time_ms"]) for n in ("greedy", "astar", "exact") if n in rows}
    else:
        lines = {n: (timing[(n, None)][0].cost, timing[(n, None)][1]) for n in ("greedy", "astar", "exact")}
    fig59 = plot_sweeps(sweeps, lines, img, "thesis_fig5_9_12.png",
                        f"GRASP on {sweep_on} (medians of the timed runs)")
    below500 = [q for q in sweeps["thesis"] if q.iterations < 500]

    # Tables 5.6–5.9 and A.1–A.5 on our RRTConnect instance (the thesis's planner of these tables).
    rrt = instances.get("RRTConnect")
    w_md = [_scenario_table(rrt, configs, scen, table) for scen, table in
            progress.bar(T22_SCENARIO_TABLES.items() if rrt else (), desc="weight scenarios", unit="table")]
    kn_bad = [t for t, rows in T22_TABLES.items() if any(abs(float(np.dot(r[2], r[3])) - r[4]) > 0.01 for r in rows)]
    why = thesis_why(instances, per_planner, same_geometry)
    how = (f"the edges in `{edges}`" if edges else
           f"the thesis cage (`configs/scenario/thesis_cage.yaml`) planned here with the three planners under "
           f"`configs/plan/default.yaml`, {p.plan_budget_s:g} s per edge ({t_plan:.0f} s with the IK targets); "
           "`--edges <run>/plan/edges.csv` of `experiments/plan.py` uses a saved run instead")
    return dict(
        seconds=time.perf_counter() - t0, preset=p.name, how=how, instances=instance_table(instances), fig514=fig514_md,
        # Table 5.5's runs on eq. 4.1 as data, for the summaries quoted elsewhere (README.md).
        eq41={f"{name}/{ls}" if ls else name: {"path": solved.path_str(), "cost": solved.cost, "ms": ms,
                                               "optimal_of_20": optimal}
              for (name, ls), (solved, ms, optimal) in timing.items()},
        planner_tables="\n".join(m + "\n" for m in planner_md), why=why, fig58=fig58, t55=t55,
        eq41_greedy="-".join(map(str, sched.THESIS_EQ41_GREEDY_PATH)), fig59=fig59, sweep_on=sweep_on,
        sweep_grid=f"{p.grasp_sweep[0]}, {p.grasp_sweep[1]}–{p.grasp_sweep[-1]}" if len(p.grasp_sweep) > 2 else
        ", ".join(map(str, p.grasp_sweep)), sweep_repeats=p.sweep_repeats,
        below500_min=min(q.cost_mean for q in below500), below500_max=max(q.cost_mean for q in below500),
        kn_bad=", ".join(kn_bad) or "none",
        weight_tables="\n".join(m + "\n" for m in w_md) if w_md else "Not computed: no RRTConnect instance.")
