"""The dexterity paper [D16]: Tables 3–5 and the design figures, for the paper's Jacobian form
(spatial, eq. 6) and ours (geometric), from two runs of :func:`uvms_jax.surrogate.run_surrogates`."""

from __future__ import annotations

import logging
import time
from pathlib import Path

import jax
import numpy as np

from uvms_jax import kin
from uvms_jax.papers._data import D16_NETWORKS, D16_TABLE3
from uvms_jax.papers._preset import Preset, save_figure
from uvms_jax.pipeline import md_table
from uvms_jax.plotting import pyplot

log = logging.getLogger(__name__)
#: Jacobian form (``index_form.jacobian``) → its label in the report.
FORMS = {"spatial": "paper's form (spatial J, eq. 6)", "geometric": "our form (geometric J)"}
NETWORKS = ("ffbn_w", "ffbn_kci", "rbfn_w", "rbfn_kci")


def _label(name: str) -> str:
    """``"ffbn_kci"`` → ``"FFBN-KCI"``, ``"rbfn_w"`` → ``"RBFN-w"`` (the paper's names)."""
    kind, index = name.split("_")
    return f"{kind.upper()}-{'w' if index == 'w' else 'KCI'}"


def _fmt(v) -> str:
    """A Table 3 cell: "—" for a parameter that does not apply."""
    return "—" if v is None else (f"{v:g}" if isinstance(v, float) else str(v))


def surrogate_runs(p: Preset) -> dict:
    """``run_surrogates`` for both Jacobian forms with the preset's sizes: form → SurrogateRun."""
    from uvms_jax import surrogate
    from uvms_jax.settings import from_mapping

    runs = {}
    for form in FORMS:
        t0 = time.perf_counter()
        cfg = {**p.surrogate, "index_form": {"jacobian": form}}
        settings = from_mapping(surrogate.SurrogateSettings, cfg)
        runs[form] = surrogate.run_surrogates(jax.random.key(settings.seed), kin.uvms12(), settings)
        log.info("surrogates (%s form) in %.0f s", form, time.perf_counter() - t0)
    return runs


def plot_designs(runs: dict, img: Path) -> str:
    """[D16] Figs 8, 10, 12, 14: design loops of the four networks, both forms → PNG."""
    plt = pyplot()
    from matplotlib.ticker import MaxNLocator

    figure_of = {"ffbn_w": "Fig. 10", "ffbn_kci": "Fig. 14", "rbfn_w": "Fig. 8", "rbfn_kci": "Fig. 12"}
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), layout="constrained")
    styles = {"spatial": ("tab:blue", "o-"), "geometric": ("tab:orange", "s--")}
    for ax, name in zip(axes.ravel(), NETWORKS):
        for form, run in runs.items():
            if name not in run.designs:
                continue
            steps = run.designs[name].steps
            xs = [s.size for s in steps] if name.startswith("ffbn") else [s.spread for s in steps]
            ax.semilogy(xs, [s.test_error for s in steps], styles[form][1], color=styles[form][0], ms=3,
                        label=FORMS[form])
        goal = next(iter(runs.values())).settings.ffbn.error_goal
        ax.axhline(goal, color="r", ls=":", label=f"E = {goal:g}")
        if name.startswith("ffbn"):
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
            ax.set_xlabel("hidden neurons")
        else:
            ax.set_xlabel("spread [normalised input units]")
        ax.set(ylabel="max |(T − S)/T| (eq. 21)", title=f"{_label(name)} design ({figure_of[name]})")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3)
    return save_figure(fig, img, "surrogate_designs.png")


def plot_trainings(runs: dict, img: Path) -> str:
    """[D16] Figs 9, 11, 13, 15: training mse of each selected network, both forms → PNG."""
    plt = pyplot()
    from matplotlib.ticker import MaxNLocator

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
    for ax, kind in zip(axes, ("ffbn", "rbfn")):
        for form, run in runs.items():
            for name, d in run.designs.items():
                if name.startswith(kind):
                    ax.semilogy(np.arange(len(d.history)), d.history, ls="-" if form == "spatial" else "--",
                                label=f"{_label(name)}, {form}")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set(xlabel="epoch" if kind == "ffbn" else "added unit", ylabel="training mse [index units²]",
               title=f"{kind.upper()} training (Figs {'11, 15' if kind == 'ffbn' else '9, 13'})")
        ax.legend(loc="upper right", fontsize=7)
    return save_figure(fig, img, "surrogate_training.png")


def _design_table(s) -> str:
    """Table 3, the paper's design parameters beside ours (settings ``s``)."""
    ffbn, rbfn, n_test = s.ffbn, s.rbfn, s.data.n_test
    ours = {"ffbn_w": (ffbn.error_goal, ffbn.target_mse.w, None, ffbn.max_hidden.w, ffbn.max_epochs, None, n_test),
            "ffbn_kci": (ffbn.error_goal, ffbn.target_mse.kci, None, ffbn.max_hidden.kci, ffbn.max_epochs, None,
                         n_test),
            "rbfn_w": (rbfn.error_goal, None, rbfn.target_mse.w, rbfn.max_centres.w, None, rbfn.spread_max, n_test),
            "rbfn_kci": (rbfn.error_goal, None, rbfn.target_mse.kci, rbfn.max_centres.kci, None, rbfn.spread_max,
                         n_test)}
    return md_table(["network", "E", "E_mse", "E_th", "L_iter (units)", "L_epochs", "L_s", "T", "training samples"],
                    [[f"{n} (paper / ours)", *(f"{_fmt(a)} / {_fmt(b)}" for a, b in zip(D16_TABLE3[n], ours[n])),
                      f"— / {s.data.n_train[n.split('_')[1]]}"] for n in D16_TABLE3])


def _results_table(runs: dict) -> str:
    """The networks designed per form: units (and spread) and max test error."""
    rows = []
    for name in NETWORKS:
        paper = D16_NETWORKS[name]
        unit_p = f"{paper.get('hidden_units', '—')}" + (f", spread {paper['spread']}" if "spread" in paper else "")
        row = [_label(name), unit_p]
        for form in FORMS:
            n = runs[form].networks[name]
            size = f"{n['hidden_units']}" + (f", spread {n['spread']:.1f}" if n["spread"] is not None else "")
            row += [size + ("" if n["met_goal"] else " (goal not met)"), f"{100 * n['max_rel_test_error']:.2f} %"]
        rows.append(row)
    return md_table(["network", "paper units", "spatial: units", "spatial: max error", "geometric: units",
                     "geometric: max error"], rows)


def _operations_table(runs: dict) -> str:
    """Table 4, operations per evaluation: the paper's counts, ours, and XLA's for the analytic index."""
    rows = [[_label(name), D16_NETWORKS[name]["operation_count"],
             *(runs[f].networks[name]["operation_count"] for f in FORMS)] for name in NETWORKS]
    for index in ("w", "kci"):
        rows.append([f"analytic {index}", D16_NETWORKS[f"analytic_{index}"]["operation_count"],
                     *(f"{runs[f].analytic[index]['xla_flops_per_sample']:.0f} XLA flops" for f in FORMS)])
    return md_table(["", "paper", "ours, spatial", "ours, geometric"], rows)


def _timing_table(runs: dict, batches: list[str]) -> str:
    """Table 5, run time per batch size (as strings) and speed-up over the analytic index."""
    rows = []
    for name in NETWORKS:
        idx = name.split("_")[1]
        paper_s, analytic_s = D16_NETWORKS[name]["seconds_1000"], D16_NETWORKS[f"analytic_{idx}"]["seconds_1000"]
        row = [_label(name), f"{paper_s * 1e3:.1f} ms ({analytic_s / paper_s:.0f}×)"]
        for form in FORMS:
            tm = runs[form].networks[name]["timing"]
            row.append(" / ".join(f"{tm[b]['network_s'] * 1e3:.3g} ms ({tm[b]['speedup']:.1f}×)" for b in batches))
        rows.append(row)
    for index in ("w", "kci"):
        row = [f"analytic {index} (fused kernel)", f"{D16_NETWORKS[f'analytic_{index}']['seconds_1000'] * 1e3:.0f} ms"]
        for form in FORMS:
            tm = runs[form].analytic[index]["timing"]
            row.append(" / ".join(f"{tm[b]['seconds'] * 1e3:.3g} ms" for b in batches))
        rows.append(row)
    return md_table(["", "paper, 1000 inputs (speed-up)", f"ours, spatial: {' / '.join(batches)} inputs (speed-up)",
                     f"ours, geometric: {' / '.join(batches)} inputs (speed-up)"], rows)


def dexterity_fields(p: Preset, img: Path) -> dict:
    """The [D16] section's tables, figures and numbers: the fields of its template
    (experiments/papers_templates/dexterity.md)."""
    t0 = time.perf_counter()
    runs = surrogate_runs(p)
    seconds = time.perf_counter() - t0
    s = next(iter(runs.values())).settings
    ranges = {f: runs[f].datasets["kci"] for f in FORMS if "kci" in runs[f].datasets}
    fig_d, fig_t = plot_designs(runs, img), plot_trainings(runs, img)
    kci_sp = runs["spatial"].networks["ffbn_kci"]
    if kci_sp["met_goal"]:
        ffbn_kci = f"reached the 2 % goal with {kci_sp['hidden_units']} neurons"
    else:
        ffbn_kci = (f"did not reach 2 % within {s.ffbn.max_hidden.kci} neurons "
                    f"(best {100 * kci_sp['max_rel_test_error']:.1f} %)")
    sizes = ("uses the paper's sizes (configs/surrogate.yaml)" if not p.surrogate else
             f"shrinks the run (overrides of configs/surrogate.yaml: `{p.surrogate}`)")
    return dict(
        seconds=seconds, cpu_count=next(iter(runs.values())).device["cpu_count"], preset=p.name, sizes=sizes,
        t3=_design_table(s), results=_results_table(runs),
        kci_spatial_min=ranges["spatial"]["y_min"], kci_spatial_max=ranges["spatial"]["y_max"],
        kci_geometric_min=ranges["geometric"]["y_min"], kci_geometric_max=ranges["geometric"]["y_max"],
        ffbn_kci=ffbn_kci, fig_designs=fig_d, fig_training=fig_t, t4=_operations_table(runs),
        t5=_timing_table(runs, [str(b) for b in s.timing.batches]),
        # The same numbers as data, for the summaries quoted elsewhere (README.md).
        networks={form: {name: {"units": r.networks[name]["hidden_units"], "met_goal": r.networks[name]["met_goal"],
                                "max_rel_test_error": r.networks[name]["max_rel_test_error"],
                                "speedup": {b: r.networks[name]["timing"][b]["speedup"]
                                            for b in r.networks[name]["timing"]}}
                         for name in NETWORKS} for form, r in runs.items()})
