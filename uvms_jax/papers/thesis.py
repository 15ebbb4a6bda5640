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

from uvms_jax import hw, kin, progress, sched
from uvms_jax import plan as P
from uvms_jax.papers._data import T22_PLANNER_TABLES, T22_SCENARIO_TABLES, T22_TABLES
from uvms_jax.papers._preset import Preset, join_and, save_figure
from uvms_jax.plotting import pyplot
from uvms_jax.settings import from_mapping, read_yaml
from uvms_jax.text import md_table

#: Thesis algorithm name → our solver name.
SOLVER_OF = {"Dijkstra": "greedy", "GRASP": "grasp", "A*": "astar"}
METRIC_LABELS = ("planning time", "joint movement", "EE distance", "security", "max torque")
#: Metric keys of a schedule row (``N_<key>``), in the order of METRIC_LABELS.
METRIC_KEYS = ("planning_time", "joint_movement", "ee_distance", "security", "max_torque")


def weights(configs: Path, name: str):
    """The weight scenario ``configs/sched/weights/<name>.yaml``: ``sched.WeightSettings``."""
    return sched.WeightSettings(**read_yaml(configs / "sched" / "weights" / f"{name}.yaml"))


def plan_thesis_cage(configs: Path, budget_s: float):
    """The thesis cage (``configs/scenario/thesis_cage.yaml``) planned with the three planners of
    Tables 5.2–5.4 under ``configs/plan/default.yaml``, ``budget_s`` [s] per edge:
    ``uvms_jax.plan.TaskGraphPlan``."""
    mapping = read_yaml(configs / "plan" / "default.yaml")
    mapping.update(planners=list(T22_PLANNER_TABLES), budget_s=float(budget_s), render=False)
    settings = from_mapping(P.PlanSettings, mapping, "plan")
    scenario = read_yaml(configs / "scenario" / "thesis_cage.yaml")
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
    scene = task_plan.scene
    path = run.solved["exact"].path if "exact" in run.solved else run.best.path
    the_plan = P.plan_for_schedule(task_plan, "RRTConnect", path)
    sim = hw.SimSettings() if the_plan.base_rpy is None else hw.SimSettings(base_rpy=the_plan.base_rpy)
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
    s = sched.SchedSettings(weights=w, solvers=tuple(solvers), grasp=sched.GraspSettings(local_search=local_search),
                            timing_repeats=repeats, iterations_sweep=())
    return sched.run_schedule(jax.random.key(0), s, inst.raw, note=inst.note)


def thesis_path_sums(table: str, normalised) -> dict[str, tuple[np.ndarray, float]]:
    """Each thesis path of ``table`` on our instance (``(5, n, n)`` normalised metrics):
    algorithm → ``(5,)`` normalised metric sums and its cost Σ K·N (NaN where a move of the
    path has no metrics)."""
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


def _returns(path: str) -> int:
    """How often a schedule goes back to the start node 0 between deliveries."""
    return path.split("-")[1:-1].count("0")


def planner_differences(table: str, run) -> str:
    """Per algorithm of a thesis table of 5.2–5.4 against ours (Markdown table): the same
    schedule or not, returns to the start, our cost against the exact optimum, and the thesis's
    cost above its own A*."""
    rows = {r["solver"]: r for r in run.rows}
    thesis = {r[0]: r for r in T22_TABLES[table]}
    opt = run.optimal_cost
    out = []
    for alg in ("Dijkstra", "GRASP", "A*"):
        _, path, _, _, C, _ = thesis[alg]
        r = rows[SOLVER_OF[alg]]
        optimal = " (optimal)" if abs(r["cost"] - opt) < 1e-9 else ""
        out.append([alg, "yes" if r["path"] == path else "no", f"{_returns(r['path'])} / {_returns(path)}",
                    f"{r['cost']:.3f} / {opt:.3f}{optimal}", f"{C - thesis['A*'][4]:+.3f}"])
    return md_table(["algorithm", "our schedule is the thesis's", "returns to the start: ours / thesis",
                     "ours: C / exact optimum", "thesis: C − its A*'s C"], out)


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


def why_fields(instances: dict[str, Instance], runs: dict) -> dict:
    """The numbers behind "why Tables 5.2–5.4 differ from ours" (the ``why_*`` fields of the
    template): the RRTConnect instance (else the first) against the thesis's tables."""
    if not runs:
        raise ValueError("no planner's scheduling instance was computed: nothing to compare with Tables 5.2-5.4")
    run = runs.get("RRTConnect") or next(iter(runs.values()))
    inst = instances.get("RRTConnect") or next(iter(instances.values()))
    table = T22_PLANNER_TABLES[inst.planner]
    thesis = {t: {r[0]: r for r in T22_TABLES[t]} for t in T22_TABLES}
    # Moves whose geometric metrics (all but planning time) agree under every planner: the same path.
    moves = np.all(np.isfinite(inst.raw), axis=0)
    same = np.all([np.all(np.isclose(i.raw[1:], inst.raw[1:], atol=1e-9), axis=0) for i in instances.values()], axis=0)
    a_star = np.array([thesis[t]["A*"][3] for t in T22_PLANNER_TABLES.values()])
    dij = np.array([thesis[t]["Dijkstra"][3] for t in T22_PLANNER_TABLES.values()])
    med = [float(np.nanmedian(i.raw[0])) * 1e3 for i in instances.values()]
    nm = run.normalised
    edge = np.all(np.isfinite(nm), axis=0)
    best = run.solved["exact"].path if "exact" in run.solved else run.best.path
    along = sched.path_metric_sums(nm, best) / (len(best) - 1)
    a_star_moves = len(thesis["5.2"]["A*"][1].split("-")) - 1
    thesis_along = np.array(thesis["5.2"]["A*"][3]) / a_star_moves
    rows = [[label, f"{np.median(nm[k][edge]):.2f}", f"{along[k]:.2f}", f"{thesis_along[k]:.2f}"]
            for k, label in enumerate(METRIC_LABELS)]
    torque = inst.raw[4][moves]
    dear = [label for k, label in enumerate(METRIC_LABELS) if np.median(nm[k][edge]) > 0.5]
    return dict(
        why_planner=inst.planner, why_table=table,
        why_best_thesis=min(c for _, c in thesis_path_sums(table, run.normalised).values()),
        why_optimal=run.optimal_cost,
        why_straight="—" if inst.straight is None else f"{inst.straight} of {inst.attempted}",
        why_same_moves=f"{int(np.sum(same & moves))} of {int(moves.sum())}",
        why_thesis_a_star_n=", ".join(f"{lo:.3f}–{hi:.3f}" for lo, hi in
                                      zip(a_star[:, 1:].min(axis=0), a_star[:, 1:].max(axis=0))),
        why_time_ms=f"{min(med):.2g}–{max(med):.2g}",
        why_dijkstra_time_n=f"{dij[:, 0].min():.3f}–{dij[:, 0].max():.3f}",
        why_dijkstra_other=float(np.ptp(dij, axis=0)[1:].max()),
        why_torque=f"{torque.min():.1f}–{torque.max():.1f}",
        why_a1=f"{thesis['A.1']['A*'][4]:.3f} against GRASP's {thesis['A.1']['GRASP'][4]:.3f}",
        why_a5=f"{thesis['A.5']['A*'][4]:.3f} against GRASP's {thesis['A.5']['GRASP'][4]:.3f}",
        why_levels=md_table(["metric", "ours: median N over all moves",
                             f"ours: mean N along our optimum ({len(best) - 1} moves)",
                             f"thesis: mean N along its A* path (Table 5.2, {a_star_moves} moves)"], rows),
        why_dear=join_and(dear) or "no metric",
        why_thesis_best=min(r[4] for r in T22_TABLES[table]),
    )


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


def _eq41_timing(key, problem: sched.PickPlaceProblem, optimum: float) -> dict:
    """Table 5.5's runs on the eq. 4.1 matrix: per (solver, GRASP local search or None), the
    first of 20 runs (after a warm-up), their median time [ms] and how many reach ``optimum``."""
    timing = {}
    for name, ls in (("greedy", None), ("grasp", "deliveries"), ("grasp", "thesis"), ("astar", None),
                     ("exact", None)):
        gs = sched.GraspSettings(local_search=ls or "deliveries")
        sched.solve(key, problem, name, gs)
        runs = [sched.solve(k, problem, name, gs) for k in jax.random.split(key, 20)]
        timing[(name, ls)] = (runs[0], float(np.median([r.wall_time_s for r in runs])) * 1e3,
                              sum(r.cost <= optimum + 1e-9 for r in runs))
    return timing


def thesis_fields(p: Preset, img: Path, edges: Path | None, configs: Path) -> dict:
    """The [T22] section's tables, figures and numbers: the fields of its template
    (experiments/papers_templates/thesis.md). Our instances are the thesis cage of ``configs``
    (the repository's configs/ folder, which also holds the weight scenarios) planned here with
    the three planners (``p.plan_budget_s`` per edge), or ``edges`` (an edges.csv) when given."""
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
                          + "\n\n" + planner_differences(table, run))
    fig58 = plot_final_costs(per_planner, img, "motion planner")
    if task_plan is not None and "RRTConnect" in per_planner:
        fig514, executed = executed_tool_paths(task_plan, per_planner["RRTConnect"], img)
        fig514_md = (f"![Fig. 5.14]({fig514})\n\nThe optimum of our RRTConnect instance, executed on the simulated "
                     f"arm over the BPL protocol: {executed['status']}, {executed['gates']} gates reached. Every "
                     f"measured tool position lies within {executed['max_mm']:.1f} mm of the planned path (95 %: "
                     f"{executed['p95_mm']:.1f} mm).")
    else:
        fig514_md = "Not computed: it needs the thesis cage planned here (no `--edges`)."

    # Table 5.5 and Figs 5.9–5.12 on the eq. 4.1 matrix (the thesis's worked example).
    problem = sched.thesis_problem()
    key = jax.random.key(0)
    solved = {n: sched.solve(key, problem, n) for n in ("greedy", "astar", "exact")}
    timing = _eq41_timing(key, problem, solved["exact"].cost)
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
        planner_tables="\n".join(m + "\n" for m in planner_md), **why_fields(instances, per_planner), fig58=fig58, t55=t55,
        eq41_greedy="-".join(map(str, sched.THESIS_EQ41_GREEDY_PATH)), fig59=fig59, sweep_on=sweep_on,
        sweep_grid=f"{p.grasp_sweep[0]}, {p.grasp_sweep[1]}–{p.grasp_sweep[-1]}" if len(p.grasp_sweep) > 2 else
        ", ".join(map(str, p.grasp_sweep)), sweep_repeats=p.sweep_repeats,
        below500_min=min(q.cost_mean for q in below500), below500_max=max(q.cost_mean for q in below500),
        kn_bad=", ".join(kn_bad) or "none",
        weight_tables="\n".join(m + "\n" for m in w_md) if w_md else "Not computed: no RRTConnect instance.")
