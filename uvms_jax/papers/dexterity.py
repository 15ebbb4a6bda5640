"""The dexterity paper [D16]: Tables 3–5 and the design figures, for the paper's Jacobian form
(spatial, eq. 6) and ours (geometric), from two runs of :func:`uvms_jax.surrogate.run_surrogates`."""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path

import jax
import numpy as np

from uvms_jax import kin, surrogate
from uvms_jax.papers._data import D16_NETWORKS, D16_TABLE3
from uvms_jax.papers._preset import Preset, save_figure
from uvms_jax.plotting import pyplot
from uvms_jax.settings import from_mapping
from uvms_jax.text import cell, md_table

log = logging.getLogger(__name__)
#: Jacobian form (``index_form.jacobian``) → its label in the report.
FORMS = {"spatial": "paper's form (spatial J, eq. 6)", "geometric": "our form (geometric J)"}
NETWORKS = ("ffbn_w", "ffbn_kci", "rbfn_w", "rbfn_kci")


def _label(name: str) -> str:
    """``"ffbn_kci"`` → ``"FFBN-KCI"``, ``"rbfn_w"`` → ``"RBFN-w"`` (the paper's names)."""
    kind, index = name.split("_")
    return f"{kind.upper()}-{'w' if index == 'w' else 'KCI'}"


def surrogate_runs(p: Preset) -> dict:
    """``run_surrogates`` for both Jacobian forms with the preset's sizes: form → SurrogateRun."""
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
                    [[f"{n} (paper / ours)", *(f"{cell(a, 6)} / {cell(b, 6)}" for a, b in zip(D16_TABLE3[n], ours[n])),
                      f"— / {s.data.n_train[n.split('_')[1]]}"] for n in D16_TABLE3])


def _network_summary(n: dict) -> dict:
    """A network's entry of the record: size, test error, operation counts, and per batch size its
    evaluations/s and speed-up over the analytic index."""
    return {"units": n["hidden_units"], "spread": n["spread"], "met_goal": n["met_goal"],
            "max_rel_test_error": n["max_rel_test_error"], "operation_count": n["operation_count"],
            "xla_flops_per_sample": n["xla_flops_per_sample"],
            "speedup": {b: t["speedup"] for b, t in n["timing"].items()},
            "per_s": {b: t["network_per_s"] for b, t in n["timing"].items()}}


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
                     *(_flops(runs[f].analytic[index]["xla_flops_per_sample"]) for f in FORMS)])
    return md_table(["", "paper", "ours, spatial", "ours, geometric"], rows)


def _flops(count: float | None) -> str:
    return "not counted by XLA" if count is None else f"{count:.0f} XLA flops"


def _time(seconds: float) -> str:
    """A run time to 3 digits, in ms below a second and in s above."""
    return f"{seconds * 1e3:.3g} ms" if seconds < 1 else f"{seconds:.3g} s"


def _ratio(speedup: float) -> str:
    """A speed-up; two decimals below 1, so that a network slower than the index never reads 1.0×."""
    return f"{speedup:.2f}×" if speedup < 1 else f"{speedup:.1f}×"


def _timing_table(runs: dict, batches: list[str]) -> str:
    """Table 5, run time per batch size (as strings) and speed-up over the analytic index."""
    rows = []
    for name in NETWORKS:
        idx = name.split("_")[1]
        paper_s, analytic_s = D16_NETWORKS[name]["seconds_1000"], D16_NETWORKS[f"analytic_{idx}"]["seconds_1000"]
        row = [_label(name), f"{paper_s * 1e3:.1f} ms ({analytic_s / paper_s:.0f}×)"]
        for form in FORMS:
            tm = runs[form].networks[name]["timing"]
            row.append(" / ".join(f"{_time(tm[b]['network_s'])} ({_ratio(tm[b]['speedup'])})" for b in batches))
        rows.append(row)
    for index in ("w", "kci"):
        row = [f"analytic {index} (fused kernel)", f"{D16_NETWORKS[f'analytic_{index}']['seconds_1000'] * 1e3:.0f} ms"]
        for form in FORMS:
            tm = runs[form].analytic[index]["timing"]
            row.append(" / ".join(_time(tm[b]['seconds']) for b in batches))
        rows.append(row)
    return md_table(["", "paper, 1000 inputs (speed-up)", f"ours, spatial: {' / '.join(batches)} inputs (speed-up)",
                     f"ours, geometric: {' / '.join(batches)} inputs (speed-up)"], rows)


def _ratios(run, name: str, batches: list[str]) -> str:
    """``"0.4× / 0.1×"``: a network's speed over the analytic index's, per batch size."""
    return " / ".join(_ratio(run.networks[name]['timing'][b]['speedup']) for b in batches)


def _rbfn_speed(runs: dict, batches: list[str]) -> str:
    """One sentence per RBFN: its speed as a multiple of the analytic index's at each batch size
    of Table 5, both forms, and where that is slower (< 1×) or faster, in both forms or in one."""
    def at(sizes: list[str]) -> str:
        return "every batch size" if len(sizes) == len(batches) else f"{' and '.join(sizes)} inputs"

    sentences = []
    for name in ("rbfn_w", "rbfn_kci"):
        index = "w" if name.endswith("_w") else "KCI"
        faster = {f: [b for b in batches if runs[f].networks[name]["timing"][b]["speedup"] >= 1] for f in FORMS}
        in_both = [b for b in batches if all(b in faster[f] for f in FORMS)]
        in_neither = [b for b in batches if not any(b in faster[f] for f in FORMS)]
        verdicts = [("slower than {} at " + at(in_neither)) if in_neither else "",
                    ("faster than {} at " + at(in_both)) if in_both else ""]
        verdicts += [f"faster than {{}} only with the {f} form, at {at(only)}"
                     for f in FORMS if (only := [b for b in faster[f] if b not in in_both])]
        # The first verdict names the analytic index; the later ones refer back to it.
        clauses = [v.format("it" if i else "the analytic index") for i, v in enumerate(v for v in verdicts if v)]
        sentences.append(f"{_label(name)} is {', and '.join(clauses)}: it runs at {_ratios(runs['spatial'], name, batches)} "
                         f"the analytic {index}'s speed at {' / '.join(batches)} inputs with the spatial form "
                         f"and {_ratios(runs['geometric'], name, batches)} with the geometric form.")
    return " ".join(sentences)


def size_search_fields(record: dict, name: str) -> dict:
    """The FFBN-KCI size search at the paper's data size, as the template quotes it, from the
    record of ``benchmarks/surrogate_sizes.py`` (``record``, the JSON it prints) saved as
    ``name`` (a path relative to the repository)."""
    goal = 100 * record["error_goal"]
    if record["met_goal"]:
        size = record["smallest_size_meeting_goal"]
        error = next(st["test_error"] for st in record["steps"] if st["size"] == size)
        result = f"reached {goal:g} % first at {size} neurons ({100 * error:.2f} %)"
    else:
        tried, limit = record["largest_size_tried"], record["max_hidden"]
        stopped = ("" if record["finished"] or tried >= limit
                   else f" (the run was stopped there, short of L_iter = {limit})")
        parts = _parts(record)  # sizes skipped by coarser steps: only those tried are claimed
        span = f"at any size tried up to {tried} neurons" if parts else f"within {tried} neurons"
        result = (f"did not reach {goal:g} % {span}{stopped}{parts}; "
                  f"best {100 * record['best_error']:.2f} % at {record['best_size']} neurons")
    paper = record["error_at_paper_units"]
    if paper is not None:
        result += f", {100 * paper:.2f} % at the paper's {record['paper_units']}"
    devices = list(dict.fromkeys(part["device"] for part in record.get("parts", [record])))
    return {"sizes_file": name, "sizes_command": record["command"], "sizes_device": ", then ".join(devices),
            "sizes_jacobian": record["jacobian"], "sizes_n_train": record["n_train"], "sizes_n_test": record["n_test"],
            "sizes_result": result}


def _parts(record: dict) -> str:
    """Which sizes a search resumed in coarser steps tried, e.g. " (sizes 1–49, then 54–99 in
    steps of 5)"; "" for one loop in steps of 1."""
    parts = record.get("parts")
    if not parts or len(parts) == 1 and parts[0]["step"] == 1:
        return ""
    loop = [st["size"] for st in record["steps"] if st["loop"] == "design loop"]
    spans = []
    for part, end in zip(parts, [p["from"] for p in parts[1:]] + [math.inf]):
        last = max(s for s in loop if part["from"] <= s < end)
        spans.append(f"{part['from']}–{last}" + (f" in steps of {part['step']}" if part["step"] > 1 else ""))
    return " (sizes " + ", then ".join(spans) + ")"


def dexterity_fields(p: Preset, img: Path) -> dict:
    """The [D16] section's tables, figures and numbers computed in this run: the fields of its
    template (experiments/papers_templates/dexterity.md) but the size search's
    (:func:`size_search_fields`)."""
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
        seconds=seconds, preset=p.name, sizes=sizes,
        t3=_design_table(s), results=_results_table(runs),
        kci_spatial_min=ranges["spatial"]["y_min"], kci_spatial_max=ranges["spatial"]["y_max"],
        kci_geometric_min=ranges["geometric"]["y_min"], kci_geometric_max=ranges["geometric"]["y_max"],
        ffbn_kci=ffbn_kci, fig_designs=fig_d, fig_training=fig_t, t4=_operations_table(runs),
        t5=_timing_table(runs, [str(b) for b in s.timing.batches]),
        rbfn_speed=_rbfn_speed(runs, [str(b) for b in s.timing.batches]),
        # The same numbers as data, for the summaries quoted elsewhere (README.md, BENCHMARKS.md).
        networks={form: {name: _network_summary(r.networks[name]) for name in NETWORKS} for form, r in runs.items()},
        analytic={form: {index: {"xla_flops_per_sample": a["xla_flops_per_sample"],
                                 "per_s": {b: t["per_second"] for b, t in a["timing"].items()}}
                         for index, a in r.analytic.items()} for form, r in runs.items()},
        index_ranges={form: {index: [d["y_min"], d["y_max"]] for index, d in r.datasets.items()}
                      for form, r in runs.items()})
