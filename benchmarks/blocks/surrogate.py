"""Report blocks of surrogates: the networks against the analytic index, sizes, roofline."""

from __future__ import annotations

from uvms_jax.text import md_table
from blocks._format import H100_BANDWIDTH, _batch, _load, _rate, _reproduction

__all__ = ["surrogate_networks", "surrogate_sizes", "surrogate_paper_sizes_cpu", "surrogate_paper_sizes_h100", "surrogate_roofline"]


def surrogate_networks() -> str:
    """The networks ``make papers`` designed and timed, both Jacobian forms, from its record."""
    from uvms_jax.papers import D16_NETWORKS, join_and

    rec = _reproduction()
    dx = rec["sections"]["surrogate"]
    batches = list(dx["networks"]["geometric"]["ffbn_w"]["per_s"])
    label = {"ffbn_w": "FFBN-w", "ffbn_kci": "FFBN-KCI", "rbfn_w": "RBFN-w", "rbfn_kci": "RBFN-KCI"}
    forms = {"geometric": "geometric J (ours)", "spatial": "spatial J (paper eq. 6)"}
    rows = []
    for form, form_label in forms.items():
        for name, n in dx["networks"][form].items():
            size = str(n["units"]) + ("" if n["spread"] is None else f", spread {n['spread']:.1f}")
            error = f"{100 * n['max_rel_test_error']:.2f} %" + ("" if n["met_goal"] else " (goal not met)")
            rows.append([label[name], form_label, size, error, str(n["operation_count"]),
                         f"{n['xla_flops_per_sample']:.0f}"]
                        + [f"{_rate(n['per_s'][b])} ({n['speedup'][b]:.1f}×)" for b in batches])
        for index, a in dx["analytic"][form].items():
            rows.append([f"analytic {'w' if index == 'w' else 'KCI'}", form_label, "–", "–", f"paper: {D16_NETWORKS[f'analytic_{index}']['operation_count']}",
                         f"{a['xla_flops_per_sample']:.0f}"] + [_rate(a["per_s"][b]) for b in batches])
    ranges = dx["index_ranges"]
    paper = (f"FFBN-w {D16_NETWORKS['ffbn_w']['hidden_units']}, FFBN-KCI {D16_NETWORKS['ffbn_kci']['hidden_units']}, "
             f"RBFN-w {D16_NETWORKS['rbfn_w']['hidden_units']} units, RBFN-KCI spread "
             f"{D16_NETWORKS['rbfn_kci']['spread']}, {D16_NETWORKS['rbfn_kci']['hidden_units']} units")
    return (f"`make papers` (`{dx['command']}`; {dx['device']}), "
            f"recorded in docs/reproduction.json; its §2 has the "
            f"design parameters. Evaluations/s at {join_and([_batch(int(b)) for b in batches])} inputs, speed-up "
            "over the analytic index of the same quantity and form in brackets; XLA flops per sample from XLA's cost "
            "analysis of each jitted function on the CPU:\n\n"
            + md_table(["network", "Jacobian", "units", "max rel. test error", "ops (paper convention)",
                      "XLA flops/sample"] + [f"{_batch(int(b))} inputs/s" for b in batches], rows)
            + f"\n\n(Paper: {paper}.) Over the sampled window w ∈ [{ranges['geometric']['w'][0]:.2f}, "
              f"{ranges['geometric']['w'][1]:.2f}] in both forms; KCI ∈ [{ranges['geometric']['kci'][0]:.3f}, "
              f"{ranges['geometric']['kci'][1]:.3f}] with the geometric J and [{ranges['spatial']['kci'][0]:.3f}, "
              f"{ranges['spatial']['kci'][1]:.3f}] with the spatial J.\n")


def surrogate_sizes() -> str:
    """FFBN-KCI per Jacobian form (docs/theory.md): ``make papers``' run and the size search at the
    training-set size of configs/surrogate.yaml (its result file, quoted through docs/reproduction.json)."""
    rec = _reproduction()
    dx = rec["sections"]["surrogate"]
    preset = dx["preset"]
    geo, kci = dx["networks"]["geometric"]["ffbn_kci"], dx["index_ranges"]["geometric"]["kci"]
    return (f"`make papers` (preset \"{preset}\"): with the geometric Jacobian KCI spans {kci[0]:.2f}–{kci[1]:.2f} and "
            f"FFBN-KCI {'meets' if geo['met_goal'] else 'misses'} the 2 % goal with {geo['units']} units "
            f"({100 * geo['max_rel_test_error']:.2f} %); with the spatial form it {dx['ffbn_kci']}. With "
            f"{dx['sizes_n_train']} training samples (ours; the paper gives no training-set size; `{dx['sizes_file']}`) the paper's loop on the spatial form "
            f"{dx['sizes_result']}.\n")


def surrogate_paper_sizes_cpu() -> str:
    """Networks of the paper's sizes with random weights against the analytic index, CPU."""
    return _surrogate_paper_sizes("surrogate_paper_sizes_cpu.json", "2-core CPU")


def surrogate_paper_sizes_h100() -> str:
    """The same on the GPU (the analytic index there is the Pallas kernel of ``indices``)."""
    return _surrogate_paper_sizes("surrogate_paper_sizes_h100.json", _load("surrogate_paper_sizes_h100.json")["device"])


def _surrogate_paper_sizes(name: str, device: str) -> str:
    d = _load(name)
    names = ("analytic_w", "ffbn_w", "rbfn_w", "analytic_kci", "ffbn_kci", "rbfn_kci")
    rows = [[_batch(int(b))] + [_rate(r[n]["per_second"]) + (f" ({r[n]['speedup_vs_analytic']:.1f}×)"
                                                            if "speedup_vs_analytic" in r[n] else "") for n in names]
            for b, r in d["results"].items()]
    g, u = d["grid"], d["hidden_units"]
    return (f"`{d['command']}` ({device}, jax {d['jax']}; `benchmarks/results/{name}`; {d['networks']}: FFBN-w {u['ffbn_w']}, FFBN-KCI "
            f"{u['ffbn_kci']}, RBFN-w {u['rbfn_w']}, RBFN-KCI {u['rbfn_kci']} units; the cost of a network does not "
            "depend on its weights), evaluations/s:\n\n"
            + md_table(["batch", "analytic w", "FFBN-w", "RBFN-w", "analytic KCI", "FFBN-KCI", "RBFN-KCI"], rows)
            + f"\n\nGrid of {_batch(g['points'])} points, same run: analytic w {_rate(g['analytic_w_stored']['per_second'])}/s; "
              f"FFBN-w stored {_rate(g['ffbn_w_stored']['per_second'])}/s ({g['ffbn_w_stored']['speedup_vs_analytic']:.1f}×), "
              f"from grid index {_rate(g['ffbn_w_from_grid_index']['per_second'])}/s "
              f"({g['ffbn_w_from_grid_index']['speedup_vs_analytic']:.1f}×).\n")


def surrogate_roofline() -> str:
    """Where FFBN-w and the analytic w sit against the H100's memory bandwidth, from the
    paper-size run on it (``surrogate_paper_sizes_h100.json``)."""
    d = _load("surrogate_paper_sizes_h100.json")
    g = d["grid"]
    stored, analytic, index = (g[k]["per_second"] for k in ("ffbn_w_stored", "analytic_w_stored", "ffbn_w_from_grid_index"))
    # A stored sample is a row of 12 float32 joints in and one float32 out; from a grid index, an
    # int32 index in and the float32 out.
    row, from_index = 12 * 4 + 4, 4 + 4
    return (f"Reading (roofline, the same run): from a stored batch of {_batch(g['points'])} FFBN-w reaches "
            f"{_rate(stored)}/s, {stored / analytic:.1f}× the analytic w: each sample moves a {row - 4}-byte row of "
            f"joints in and 4 bytes out, {stored * row / 1e12:.1f} TB/s, {100 * stored * row / H100_BANDWIDTH:.0f} % of "
            f"the H100's {H100_BANDWIDTH / 1e12:.2f} TB/s. That is near the ceiling for any evaluator of a stored "
            f"12-joint float32 batch, and the analytic kernel, which keeps its few thousand operations per sample in "
            f"registers and is compute-bound at {_rate(analytic)}/s, sits {stored / analytic:.1f}× below it: on stored "
            f"configurations no network gets much further. With the configuration made in the program "
            f"({from_index} bytes per sample, {index * from_index / 1e12:.1f} TB/s at {_rate(index)}/s) the bound is the "
            f"network's own arithmetic, which grows with its units: the paper's {d['hidden_units']['ffbn_w']} units "
            f"reach {index / analytic:.1f}× the analytic w.\n")
