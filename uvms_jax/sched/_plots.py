"""Figures of a scheduling run: GRASP versus iterations, and the chosen route."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

from uvms_jax.plotting import pyplot, save_figure
from uvms_jax.sched._problem import PickPlaceProblem
from uvms_jax.sched._schedule import Schedule
from uvms_jax.sched._solvers import SOLVERS
from uvms_jax.sched._thesis import THESIS_NODE_NAMES


def plot_sweep(out: Path, sweep: Sequence, solved: Mapping[str, Schedule]) -> None:
    """``grasp_iterations.png``: GRASP cost and time versus iterations (thesis Figs 5.9–5.12),
    with each solved solver that has a line style (:class:`~uvms_jax.sched.Solver`) as a
    horizontal line. ``sweep``: ``SweepPoint``s."""
    plt = pyplot()
    it = [r.iterations for r in sweep]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    a.plot(it, [r.cost_mean for r in sweep], "o-", label="GRASP (mean)")
    a.fill_between(it, [r.cost_min for r in sweep], [r.cost_max for r in sweep], alpha=0.2, label="GRASP (min–max)")
    b.plot(it, [r.time_ms for r in sweep], "o-", label="GRASP")
    for name, s in solved.items():
        style = SOLVERS[name].line if name in SOLVERS else None
        if style:
            a.axhline(s.cost, color=style[0], ls=style[1:], label=SOLVERS[name].label)
            b.axhline(s.wall_time_s * 1e3, color=style[0], ls=style[1:], label=SOLVERS[name].label)
    a.set(xscale="log", xlabel="GRASP iterations", ylabel="schedule cost", title="Cost vs iterations (Figs 5.9–5.10)")
    b.set(xscale="log", yscale="log", xlabel="GRASP iterations", ylabel="wall time [ms]", title="Time vs iterations (Figs 5.11–5.12)")
    handles, labels = a.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=len(labels), fontsize=8)
    save_figure(fig, out / "grasp_iterations.png", dpi=120)


def plot_route(out: Path, problem: PickPlaceProblem, schedule: Schedule, greedy: Schedule | None) -> None:
    """``route.png``: schematic layout (start/goal left, objects in the middle column, bases
    on the right) with the chosen schedule and the greedy one drawn as arrows."""
    plt = pyplot()
    pos = {problem.start: (0.0, 0.5), problem.goal: (0.0, -0.5)}
    for k, o in enumerate(problem.objects):
        pos[o] = (1.0, 1.5 - 3.0 * k / max(problem.n_objects - 1, 1))
    for k, b in enumerate(problem.bases):
        pos[b] = (2.0, 1.5 - 3.0 * k / max(problem.n_bases - 1, 1))
    names = THESIS_NODE_NAMES if problem.n_nodes == len(THESIS_NODE_NAMES) else None
    fig, ax = plt.subplots(figsize=(7, 5), layout="constrained")
    for v, (x, y) in pos.items():
        ax.plot(x, y, "o", ms=20, color="lightsteelblue")
        ax.annotate(str(v), (x, y), ha="center", va="center")
        if names:
            ax.annotate(names[v], (x, y - 0.22), ha="center", fontsize=7)
    for s, style, label in ((greedy, ("tab:red", 0.15, "--"), "greedy"), (schedule, ("tab:blue", -0.15, "-"), schedule.solver)):
        if s is None or not s.feasible:
            continue
        for a, b in zip(s.path[:-1], s.path[1:]):
            ax.annotate("", xy=pos[b], xytext=pos[a],
                        arrowprops={"arrowstyle": "->", "color": style[0], "ls": style[2],
                                    "connectionstyle": f"arc3,rad={style[1]}", "shrinkA": 12, "shrinkB": 12})
        ax.plot([], [], color=style[0], ls=style[2], label=f"{label}: {s.path_str()} ({s.cost:.3f})")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), fontsize=8)
    ax.set_axis_off()
    ax.set_title("Chosen route")
    save_figure(fig, out / "route.png", dpi=120, bbox_inches="tight")
