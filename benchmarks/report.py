"""The quoted figures of README.md, BENCHMARKS.md and docs/ (theory, docking, hover), generated from
benchmarks/results/ and docs/reproduction.json.

Each generated block sits between ``<!-- report:NAME -->`` and ``<!-- /report:NAME -->`` in one
of :data:`DOCUMENTS`, and is written by the function of that name below from the JSON files
that the benchmark scripts print or a pipeline run writes (``results.json`` of ``make demo``,
copied as ``demo_cpu.json``; the command that wrote a file is named next to its block). So a
figure in a block always has a file and a command behind it, and
``tests/test_benchmarks_report.py`` fails when a block no longer matches its files.

Every other number in the prose of these documents carries a source marker
(``benchmarks/sources.py``; docs/design.md, "Numbers and their sources").

Usage: python benchmarks/report.py            # rewrite the blocks
       python benchmarks/report.py --check    # exit 1 naming the blocks that are out of date
                                              # and the prose numbers without a source
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path

from uvms_jax.text import md_table

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
DOCUMENTS = (ROOT / "README.md", ROOT / "BENCHMARKS.md", ROOT / "docs" / "theory.md", ROOT / "docs" / "docking.md",
             ROOT / "docs" / "hover.md", ROOT / "docs" / "planning.md")
BLOCK = re.compile(r"(<!-- report:(?P<name>[a-z0-9_]+) -->\n)(?P<body>.*?)(<!-- /report:(?P=name) -->)", re.S)


def _load(name: str) -> dict:
    return json.loads((RESULTS / name).read_text())


def _rate(v: float) -> str:
    """``2.50e7`` style: three significant digits, no '+' or leading zero in the exponent."""
    mantissa, exponent = f"{v:.2e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _sci(v: float) -> str:
    """``2.4e-6`` style: two significant digits, no '+' or leading zero in the exponent."""
    mantissa, exponent = f"{v:.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _batch(n: int) -> str:
    mantissa, exponent = f"{n:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def kin_indices_cpu() -> str:
    d = _load("kin_indices_uvms12_cpu.json")
    rows = [[_batch(r["batch"]), _rate(r["uvms_jax_w_per_s"]), _rate(r["gram_w_per_s"]), _rate(r["peer_w_per_s"]),
             f"{r['w_speedup']:.0f}", _rate(r["uvms_jax_kci_per_s"]), _rate(r["gram_kci_per_s"]),
             _rate(r["peer_kci_per_s"]), f"{r['kci_speedup']:.1f}"] for r in d["results"]]
    b7 = _load("kin_indices_bravo7_cpu.json")["results"][0]
    return (f"**2-core CPU ({d['machine']}), jax {d['jax']}, torch {d['torch']}**, 12-DOF UVMS\n"
            f"(`python benchmarks/kin_indices.py --batches 1e3,1e5`):\n\n"
            + md_table(["batch", "w/s", "w/s (Gram)", "peer w/s", "w speed-up", "KCI/s", "KCI/s (Gram)",
                      "peer KCI/s", "KCI speed-up"], rows)
            + "\n\nThe Bravo 7 alone (`--urdf uvms_jax/robot/descriptions/bravo7.urdf --tip tool --batches 1e5`):\n"
            f"w {_rate(b7['uvms_jax_w_per_s'])}/s (Gram {_rate(b7['gram_w_per_s'])}), "
            f"KCI {_rate(b7['uvms_jax_kci_per_s'])}/s (Gram {_rate(b7['gram_kci_per_s'])}),\n"
            f"{b7['w_speedup']:.0f}× and {b7['kci_speedup']:.1f}× the peer.\n")


def kin_indices_accuracy() -> str:
    rows = []
    for label, name in (("Bravo 7 (CPU)", "kin_indices_bravo7_cpu.json"), ("UVMS-12 (CPU)", "kin_indices_uvms12_cpu.json"),
                        ("UVMS-12 (H200)", "kin_indices_uvms12_h200.json")):
        a = _load(name)["accuracy"]
        s = a["median_sigma_min_near_singular"]
        rows.append([label, f"{s:.1e}" if s < 0.01 else f"{s:.2f}"]
                    + [f"{a[k]:.1e}" for k in ("uvms_jax_w_max_abs_err", "gram_w_max_abs_err",
                                                "uvms_jax_kci_max_abs_err", "gram_kci_max_abs_err")])
    cpu = _load("kin_indices_uvms12_cpu.json")["results"] + _load("kin_indices_bravo7_cpu.json")["results"]
    w = [r["uvms_jax_w_per_s"] / r["gram_w_per_s"] - 1 for r in cpu]
    k = [r["uvms_jax_kci_per_s"] / r["gram_kci_per_s"] - 1 for r in cpu]
    uvms = _load("kin_indices_uvms12_cpu.json")["accuracy"]["gram_w_max_abs_err"]
    return (md_table(["chain (device)", "median σ_min of the near-singular poses", "w: J factored", "w: Gram",
                    "KCI: J factored", "KCI: Gram"], rows)
            + f"\n\n(The UVMS is never singular — its vehicle's six DOF keep J at full rank — but its large σ1\n"
            f"alone costs the Gram form {uvms:.1e}.) On the CPU, factoring J changes w's rate by "
            f"{min(w):+.0%} to {max(w):+.0%} against the Gram form and KCI's by {min(k):+.0%} to {max(k):+.0%}.\n")


def kin_indices_gpu() -> str:
    d = _load("kin_indices_uvms12_h200.json")
    peer = lambda r, k: _rate(r[k]) if k in r else "—"  # noqa: E731  (the peer stops at 1e6)
    rows = [[_batch(r["batch"]), _rate(r["uvms_jax_w_per_s"]), _rate(r["gram_w_per_s"]), _rate(r["uvms_jax_xla_w_per_s"]),
             peer(r, "peer_w_per_s"), _rate(r["uvms_jax_kci_per_s"]), _rate(r["gram_kci_per_s"]),
             _rate(r["uvms_jax_xla_kci_per_s"]), peer(r, "peer_kci_per_s")] for r in d["results"]]
    last = d["results"][-1]
    best_peer = max(r.get("peer_w_per_s", 0.0) for r in d["results"])
    kci_diff = max(r["kernel_vs_xla_max_abs_diff_kci"] for r in d["results"])
    w_same = all(r["kernel_vs_xla_max_abs_diff_w"] == 0 for r in d["results"])
    return (md_table(["batch", "w/s (kernel)", "w/s (Gram kernel)", "w/s (XLA)", "peer w/s", "KCI/s (kernel)",
                    "KCI/s (Gram kernel)", "KCI/s (XLA)", "peer KCI/s"], rows)
            + f"\n\nThe kernel and the XLA path give {'the same w to the bit' if w_same else 'w within round-off'} "
            f"and KCI within {kci_diff:.1e}. At {_batch(last['batch'])}, w runs at **{_rate(last['uvms_jax_w_per_s'])}/s**, "
            f"{last['uvms_jax_w_per_s'] / last['gram_w_per_s']:.0%} of the Gram form's rate and "
            f"{last['uvms_jax_w_per_s'] / last['uvms_jax_xla_w_per_s']:.1f}× the XLA fusion, and KCI at "
            f"{_rate(last['uvms_jax_kci_per_s'])}/s, {last['uvms_jax_kci_per_s'] / last['gram_kci_per_s']:.0%} of the Gram "
            f"form's. The kernel's w at {_batch(last['batch'])} is {last['uvms_jax_w_per_s'] / best_peer:.0f}× the peer's best, "
            f"{_rate(best_peer)} w/s.\n")


def demo() -> str:
    d = _load("demo_cpu.json")
    sur, dock, pl, sch, hw, base = (d[k] for k in ("surrogate", "docking", "plan", "schedule", "hw", "baseline"))
    t = d["stage_seconds"]
    same = [name for name in ("exact", "astar", "grasp") if abs(sch[f"{name}_cost"] - sch["winner_cost"]) < 1e-9]
    label = {"exact": "exact", "astar": "A*", "grasp": "GRASP"}
    x, y, z = pl["base_xyz"]
    docked, fixed = base["docked"], base["fixed"]
    rows = [
        ["surrogate", f"map learned from {sur['n_train_samples']} tool poses in the arm's base frame "
                      f"({sur['n_test_samples']} held out); held-out RMSE of w {sur['rmse_w']:.4f} (largest w "
                      f"{sur['w_range']:.3f})", f"{t['surrogate']:.1f}"],
        ["docking", f"GA runs: best {dock['ga_best_fitness']:.3f} (M_a {dock['ga_best_M_a']:.4f}), worst "
                    f"{dock['ga_ratio_to_grid_min'] * dock['grid_fitness']:.2f}; multistart grid search: **{dock['grid_fitness']:.3f} "
                    f"(M_a {dock['pose_M_a']:.4f})**, chosen ({dock['pose_source']}); the map's route (its GA "
                    f"proposes, the analytic fitness confirms and refines): {dock['map_best_fitness']:.3f}, a loss of "
                    f"optimum of {dock['map_loss_of_optimum']:.2%} with {dock['map_analytic_evaluations']} analytic "
                    f"evaluations against the analytic search's {dock['analytic_evaluations']} "
                    f"({dock['map_evaluation_ratio']:.0f}× fewer)", f"{t['docking']:.1f}"],
        ["plan", f"arm base at ({x:.3f}, {y:.3f}, {z:.3f}) m under the docked vehicle; {pl['RRTConnect_success']} edges "
                 f"planned and re-checked by MuJoCo, median RRTConnect {pl['RRTConnect_median_ms']:.1f} ms",
         f"{t['plan']:.1f}"],
        ["schedule", f"{' = '.join(label[n] for n in same)}: {sch['winner_path']}, cost {sch['winner_cost']:.3f} "
                     f"(greedy {sch['greedy_cost']:.3f}; costs are normalised over this run's metrics, planning times "
                     "included, so they and the winner move from run to run)", f"{t['schedule']:.1f}"],
        ["hw", f"{hw['status']} on the simulated arm: {hw['gates']} gates within 0.01 rad (max "
               f"{hw['max_gate_error_rad']:.3g} rad), {hw['duration_s']} s of simulated time, "
               f"{hw['sim']['limit_violations']} demands outside the limits, `run.mp4`", f"{t['hw']:.1f}"],
        ["baseline", f"the thesis's cage-top mount: M_a {fixed['M_a']:.4f} (docked: {docked['M_a']:.4f}), completed in "
                     f"{fixed['executed_s']} s (docked: {docked['executed_s']} s)", f"{t['baseline']:.1f}"],
    ]
    if "hover" in d:
        def run(label, m):
            return (f"{label} ({m['driver']}): {m['status']}, {m['gates_reached']}/{m['gates']} gates passed, the tool "
                    f"within 10 mm at {m['gates_tool_within_tolerance']}, drift ≤ {1e3 * m['max_drift_m']:.0f} mm, tool "
                    f"≤ {1e3 * m['max_tool_error_m']:.0f} mm, tilt ≤ {m['max_tilt_deg']:.1f}°, thrust ≤ "
                    f"{m['peak_thrust_N']:.0f} N")
        runs = d["hover"]["runs"]
        rows.insert(-1, ["hover", "the plan executed with the vehicle hovering at the docked pose on thrusters; "
                         + "; ".join(run(label, m) for label, m in runs.items()), f"{t['hover']:.1f}"])
    change = fixed["executed_s"] / docked["executed_s"] - 1
    return (f"Pipeline {d['total_seconds']:.1f} s (compilation cache warm):\n\n"
            + md_table(["stage", "result", "wall [s]"], rows)
            + f"\n\nSo the docked arm is more dexterous over the targets (M_a {docked['M_a'] / fixed['M_a'] - 1:+.0%}), and the "
            f"fixed mount's run is\n{abs(change):.0%} {'shorter' if change < 0 else 'longer'}: from the cage top the arm's "
            f"tool travels {fixed['ee_distance_m']:.1f} m against {docked['ee_distance_m']:.1f} m docked.\n")


def docking_search() -> str:
    ref_file = "docking_reference_demo_h100.json"
    ref, d = _load(ref_file)["reference"], _load("docking_search_demo_cpu.json")
    s = d["search"]
    runs = s["runs"]
    g = ref["grid"]
    rows = [[str(r["seed"]), f"{r['best']:.4f}", f"{r['ratio']:.4f}", f"{r['ga_best']:.3f}", f"{r['coarse_grid_best']:.3f}",
             f"{r['grid_zoom_best']:.4f}", str(r["evaluations"]), f"{r['wall_s']:.0f}"] for r in runs]
    first, last = runs[0]["seed"], runs[-1]["seed"]
    return (f"Dense reference on an **{_load(ref_file)['device_kind']}** (`python benchmarks/docking_search.py "
            f"--reference`):\na {' × '.join(map(str, g['counts']))} grid ({ref['grid_candidates']:,} poses, "
            f"{ref['grid_seconds']:.1f} s) reaching {ref['grid_fitness']:.4f}, then {g['refine_stages']} zoom stages of "
            f"{g['refine_counts'][0]}^4 ({ref['zoom_seconds']:.1f} s): **{ref['fitness']:.4f}**.\n\n"
            f"The demo's docking stage on the **2-core CPU** ({d['machine']}, jax {d['jax']}), seeds {first}–{last}\n"
            f"(`python benchmarks/docking_search.py --seeds {first} {len(runs)} --reference-file "
            f"benchmarks/results/{ref_file}`): **{s['reached_0.99']} of {len(runs)}** reach ≥ 0.99 of the reference "
            f"(ratio {s['ratio_min']:.4f} at worst, median {s['ratio_median']:.4f}), each with "
            f"{min(r['evaluations'] for r in runs):,}–{max(r['evaluations'] for r in runs):,} evaluations in "
            f"{s['wall_s_median']:.0f} s (median, compilation cache warm).\n\n"
            + md_table(["seed", "best", "best / reference", "GA runs' best", "lattice's best", "after zoom",
                      "evaluations", "wall [s]"], rows)
            + "".join(f"\n\nSeed {r['seed']} misses: its lattice's best scores {r['coarse_grid_best']:.3f} and its GA runs' "
                      f"{r['ga_best']:.3f} (eq. 15 is −b·D where a target is out of reach): no start lies in the optimum's "
                      f"basin, and the zoom stages climb only to {r['best']:.3f}."
                      for r in runs if r["ratio"] < 0.99) + "\n")


def hover_mjx() -> str:
    rows = []
    for name in ("hover_mjx_cpu.json", "hover_mjx_h100.json"):
        d = _load(name)
        where = "2-core CPU" if d["device"]["platform"] == "cpu" else d["device"]["device_kind"]
        cpu = d["cpu_mujoco_hoversim"]["steps_per_s"]
        for r in d["mjx"]:
            rows.append([where, str(r["batch"]), f"{r['compile_s']:.1f}", f"{r['run_s']:.3f}", _rate(r["env_steps_per_s"]),
                         _rate(r["scenarios_per_s"]), f"{r['env_steps_per_s'] / cpu:.0f}×"])
    gpu, cpu_file = _load("hover_mjx_h100.json"), _load("hover_mjx_cpu.json")
    return (f"`{cpu_file['command']}` (2-core CPU, jax {cpu_file['versions']['jax']}) and `{gpu['command']}` "
            f"({gpu['device']['device_kind']}, jax {gpu['versions']['jax']}); {gpu['physics_steps_per_scenario']} "
            f"physics steps of {gpu['model']['physics_dt_s'] * 1e3:g} ms per scenario on the GPU "
            f"({gpu['simulated_s']:g} s simulated), float32. CPU MuJoCo (`HoverSim`, one thread, the same model and "
            f"motion): {_rate(cpu_file['cpu_mujoco_hoversim']['steps_per_s'])} steps/s here, "
            f"{_rate(gpu['cpu_mujoco_hoversim']['steps_per_s'])} on the GPU machine's CPU (MuJoCo's C step alone, "
            f"without our buoyancy and control: {_rate(cpu_file['cpu_mujoco_mj_step_only']['steps_per_s'])} and "
            f"{_rate(gpu['cpu_mujoco_mj_step_only']['steps_per_s'])}); the last column is the batch against `HoverSim` "
            "on the same machine.\n\n"
            + md_table(["device", "scenarios", "compile [s]", "run [s]", "env-steps/s", "scenarios/s", "vs CPU MuJoCo"],
                     rows) + "\n")


def hover_robustness() -> str:
    d = _load("hover_robustness_cpu.json")
    poses = d["per_pose"]
    names = ["docked pose" if p["docked"] else f"candidate {k}" for k, p in enumerate(poses)]
    listing = "; ".join(f"{n}: ({', '.join(f'{v:.3f}' for v in p['pose'])}), fitness {p['fitness']:.3f}"
                        for n, p in zip(names, poses))
    rows = [[f"{r['speed_m_s']:.1f}"] + [f"{p['per_speed'][i]['gate_share_worst']:.2f} / "
                                         f"{1e3 * p['per_speed'][i]['max_tool_error_m']:.0f}" for p in poses]
            for i, r in enumerate(poses[0]["per_speed"])]
    left = "".join(f" Left out: ({', '.join(f'{v:.3f}' for v in p['pose'])}), fitness {p['fitness']:.3f}: from there "
                   f"the tool follows {p['path_share_followed']:.0%} of the path continuously." for p in d["left_out"])
    return (f"`{d['command']}` (the run of `benchmarks/results/demo_cpu.json`; 2-core CPU, jax {d['jax']}): "
            f"{len(poses)} poses × {d['currents']} currents = {d['scenarios']} scenarios, {d['simulated_s']:.0f} s "
            f"each, {d['gates']} gates, in one MJX call ({d['compile_s']:.1f} s compile, {d['run_s']:.1f} s run). "
            f"Poses [x, y, z, ψ]: {listing}.{left}\n\n"
            + md_table(["current [m/s]"] + [f"{n}: gates reached (worst direction) / worst tool error [mm]" for n in names],
                     rows) + "\n")


def _reproduction() -> dict:
    """The record of ``make papers`` (docs/reproduction.json)."""
    return json.loads((ROOT / "docs" / "reproduction.json").read_text(encoding="utf-8"))


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


#: The H100 SXM's memory bandwidth, its datasheet figure [B/s].
H100_BANDWIDTH = 3.35e12


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


def scale_out() -> str:
    """The docking grid on one device against all local devices (``benchmarks/shard.py``), one
    row per result file ``shard_*.json``."""
    rows = []
    for f in sorted(RESULTS.glob("shard_*.json")):
        d = json.loads(f.read_text())
        n = len(d["devices"])
        where = (f"{n} fake devices of a 2-core CPU (API check only)" if d["device_kind"] == "cpu"
                 else f"{n}× {d['device_kind']} (one host)")
        rows.append([f"{where}, jax {d['jax']}", f"`{d['command']}`", _batch(d["candidates"]),
                     f"{d['single_s']:.3g} s ({_rate(d['single_per_s'])}/s)",
                     f"{d['sharded_s']:.3g} s ({_rate(d['sharded_per_s'])}/s)", f"{d['speedup']:.2f}×",
                     "yes" if d["same_optimum"] else "**no**"])
    return md_table(["devices", "command", "candidates", "single device", "sharded", "speed-up", "same optimum"], rows) + "\n"


#: The H100 and H200 issue 132 SMs × 128 FP32 lanes at 1.98 GHz (datasheet boost clock) [instructions/s].
HOPPER_FP32 = 132 * 128 * 1.98e9
#: The H200's memory bandwidth, its datasheet figure [B/s].
H200_BANDWIDTH = 4.8e12


def kin_roofline() -> str:
    """Where the GPU kernel of w sits against the H200's ceilings: the expression's operation
    count (``kin_operations_uvms12.json``) and the kernel's rate (``kin_indices_uvms12_h200.json``)."""
    ops = _load("kin_operations_uvms12.json")["indices"]["w"]["arithmetic"]
    big = max(_load("kin_indices_uvms12_h200.json")["results"], key=lambda r: r["batch"])
    rate = big["uvms_jax_w_per_s"]
    adds = ops["add"] + ops["sub"]
    # A multiply-add fuses into one instruction, so the expression needs at least as many FP32
    # instructions as its larger kind; sin, cos and square roots cost more and are left out.
    instructions = max(ops["mul"], adds)
    compute, memory = HOPPER_FP32 / instructions, H200_BANDWIDTH / (12 * 4 + 4)
    return (f"Roofline (w, UVMS-12, float32; `benchmarks/results/kin_operations_uvms12.json`, written by "
            f"`python benchmarks/kin_operations.py`): the traced expression has {ops['mul']} multiplies, {adds} adds "
            f"and subtractions, {ops['sin']} sin + {ops['cos']} cos, {ops['sqrt']} square roots and {ops['div']} "
            f"divisions, so at least {instructions} FP32 instructions once multiply-adds fuse. The H200 issues "
            f"132 SMs × 128 lanes × 1.98 GHz = {_rate(HOPPER_FP32)} FP32 instructions/s: a compute ceiling near "
            f"**{_rate(compute)} w/s**; memory moves 52 B per evaluation (12 joint values in, w out), a bandwidth "
            f"ceiling near **{_rate(memory)} w/s** at its {H200_BANDWIDTH / 1e12:.1f} TB/s. At {_batch(big['batch'])} the "
            f"kernel's {_rate(rate)} w/s is {100 * rate / compute:.0f} % of the compute ceiling, so it is compute-bound.\n")


def hover_vehicle() -> str:
    """The hovering vehicle's derived figures (docs/hover.md), from ``benchmarks/hover_vehicle.py``."""
    d = _load("hover_vehicle.json")
    e, v, p = d["largest_effort"], d["steady_speed_m_s"], d["poles_rad_s"]

    def poles(roots):
        out = []
        for re_, im in roots:
            if im < 0:
                continue
            out.append(f"{re_:.2g} ± {im:.2g}j" if im > 0 else f"{re_:.2g}")
        return ", ".join(out).replace("-", "−")

    limits = sorted(set(d["thrust_limit_n"]))
    return (f"`{d['command']}` (`benchmarks/results/hover_vehicle.json`):\n\n"
            + md_table(["figure", "value"], [
                ["thrust configuration matrix", f"rank {d['thrust_matrix_rank']}, {d['thrusters']} thrusters of "
                                                f"±{'/'.join(f'{x:g}' for x in limits)} N"],
                ["largest pure effort", f"surge {e['surge']:.0f} N, sway {e['sway']:.0f} N, heave {e['heave']:.0f} N, "
                                        f"yaw {e['yaw']:.0f} N·m"],
                ["steady speed at that effort against the hull's own drag",
                 f"surge {v['surge']:.2f} m/s, sway {v['sway']:.2f} m/s, heave {v['heave']:.2f} m/s"],
                ["hydrostatic restoring moment of the hull", f"{d['restoring_moment_nm_per_rad']:.0f} N·m per radian of roll or pitch"],
                [f"rigid vehicle, the {d['arm'].replace('bravo7', 'Bravo 7')} held at mid-range",
                 f"{d['mass_kg']:.1f} kg, {d['yaw_inertia_kg_m2']:.1f} kg·m² about z"],
                ["station-keeping poles, no drag", f"{poles(p['translation'])} rad/s in each translation; "
                                                   f"{poles(p['yaw'])} rad/s in yaw"]]) + "\n")


def _minutes(seconds: float) -> str:
    return f"{int(seconds // 60)} min {round(seconds % 60):02d} s"


def test_suite() -> str:
    """CI's run in a fresh clone (``benchmarks/test_suite.py``): setup, the fast suite, the slow one."""
    d = _load("test_suite_cpu.json")
    t = d["targets"]
    fast, slow = t["test"], t["test-slow"]
    return (f"On the {d['cpu_count']}-core machine, from a fresh clone of commit {d['commit'][:7]} "
            f"(`{d['command']}`, `benchmarks/results/test_suite_cpu.json`): `make setup` {_minutes(t['setup']['seconds'])}, "
            f"then the {fast['passed']} fast tests {_minutes(fast['seconds'])} and the {slow['passed']} slow ones "
            f"{_minutes(slow['seconds'])} ({slow.get('skipped', 0)} skipped: GPU only), compiling everything; load "
            f"average {d['load_average_start'][0]:.1f} at the start.\n")


def test_suite_isa() -> str:
    """The fast suite with XLA's CPU code held to an older instruction set (``--isa``)."""
    d = _load("test_suite_avx_cpu.json")
    t = d["targets"]["test"]
    failed = f", {t['failed']} failed" if t.get("failed") else ""
    return (f"With XLA's CPU code generation held to AVX (`XLA_FLAGS={d['xla_flags']}`; `{d['command']}`, "
            f"`benchmarks/results/test_suite_avx_cpu.json`), from a fresh clone of commit {d['commit'][:7]}: the "
            f"{t['passed']} fast tests passed{failed} in {_minutes(t['seconds'])}, as with XLA's default code path.\n")


def docking_certify() -> str:
    """A certified docking run of the demo's fitness on a GPU (docs/docking.md), from its
    ``summary.json`` kept as ``docking_certify_demo_h100.json``."""
    d = _load("docking_certify_demo_h100.json")
    s, c = d["summary"], d["summary"]["certificate"]
    ref = c["reference"]
    ratios = [f / ref["fitness"] for f in s["ga_fitness"]]
    return (f"On an {d['device']} (jax {d['jax']}; `benchmarks/results/docking_certify_demo_h100.json`): the reference "
            f"{ref['fitness']:.4f} ({ref['search']}, {_int(ref['evaluations'])} poses, the grid at "
            f"{_int(s['grid_candidates_per_s'])} poses/s), and {len(ratios)} GA runs at "
            f"{_int(s['ga_evaluations_per_s'])} evaluations/s whose bests reach {_range(ratios)} of it "
            f"({sum(r >= c['accept_ratio'] for r in ratios)} of {len(ratios)} ≥ {c['accept_ratio']:g}): "
            f"`ga_certified: {str(c['ga_certified']).lower()}` (best {c['ga_best_ratio']:.4f}).\n")


def kin_summary() -> str:
    """The kinematics line of README.md's results, from the indices benchmark's files."""
    cpu = next(r for r in _load("kin_indices_uvms12_cpu.json")["results"] if r["batch"] == 100000)
    gpu = _load("kin_indices_uvms12_h200.json")  # measured on an H200 (the file records no device kind)
    last = gpu["results"][-1]
    best_peer = max(r.get("peer_w_per_s", 0.0) for r in gpu["results"])
    b7 = _load("kin_indices_bravo7_cpu.json")["accuracy"]
    return (f"- **Kinematics and indices** ([theory §1–2](docs/theory.md#1-kinematics)): w of the 12-DOF UVMS\n"
            f"  at batch 1e5 {_rate(cpu['uvms_jax_w_per_s'])}/s on the CPU ({cpu['w_speedup']:.0f}× pytorch-kinematics); "
            f"{_rate(last['uvms_jax_w_per_s'])}/s at {_batch(last['batch'])} on an\n  H200 "
            f"(one Pallas kernel; {last['uvms_jax_w_per_s'] / last['uvms_jax_xla_w_per_s']:.1f}× the XLA fusion, "
            f"{last['uvms_jax_w_per_s'] / best_peer:.0f}× the peer's best). w and KCI factor J itself, so\n"
            f"  near the Bravo 7's singular poses float32 w stays within {_sci(b7['uvms_jax_w_max_abs_err'])} of the largest "
            f"w of float64\n  singular values, where factoring `J Jᵀ` was off by {_sci(b7['gram_w_max_abs_err'])}. FK and "
            "Jacobian of imported arms\n  match pytorch-kinematics within 1e-6 (float64) on the Bravo 7, seven real arms'\n"
            "  URDFs (example-robot-data) and the Reach Alpha 5 (tests/kin).\n")


def papers() -> str:
    """The papers' summary of README.md, from the record of ``make papers`` (docs/reproduction.json)."""
    from uvms_jax.papers import D16_NETWORKS, T22_TABLES

    rec = _reproduction()["sections"]
    dk, dx, th = rec["docking"], rec["surrogate"], rec["thesis"]
    # The paper's Jacobian (spatial form, eq. 6) leads; ours (geometric) follows.
    nets, ours = dx["networks"]["spatial"], dx["networks"]["geometric"]
    batches = sorted(nets["ffbn_w"]["speedup"], key=int)

    def speedups(name):  # "4.2× / 19× / 0.26×", one per batch size
        return " / ".join(f"{r:.2f}×" if r < 1 else f"{r:.1f}×" if r < 10 else f"{r:.0f}×"
                          for r in (nets[name]["speedup"][b] for b in batches))

    def net(name, of=nets):
        n = of[name]
        return f"{n['units']} units, {100 * n['max_rel_test_error']:.2f} %" + ("" if n["met_goal"] else " (goal not met)")

    t55 = {r[0]: r for r in T22_TABLES["5.5"]}
    eq = th["eq41"]
    return (
        f"- **Docking** ([theory §3](docs/theory.md#3-docking-optimisation), paper Tables 3–4, Figs 9–10): "
        f"our {dk['ga_runs']} GA\n"
        f"  poses lie on an edge of the quarter nearest the start (x or y within 1 cm of 0), the paper's near its "
        f"diagonal; the paper's poses face the task centre "
        f"within\n  {dk['heading_min']:.0f}–{dk['heading_max']:.0f}° of the bearing, ours do not "
        f"({dk['ga_heading_min']:.0f}–{dk['ga_heading_max']:.0f}°: with the tool yaw tied to the heading, M_a hardly "
        f"depends on ψ\n  and the distance term sets it; with ψ fixed towards the centre our fitness is "
        f"{dk['facing_loss']:.1f} % lower). Zero-w share of the\n  task area: our optimum {dk['zero_ours']:.1f} %, the "
        f"ill-placed pose {dk['zero_ill']:.1f} % (paper's Figs 9–10: \"a quite small area\", a large one). The paper's\n"
        f"  M_a (0.134–0.181) is out of reach of the arm as stated: it exceeds the largest w of any 6 × 6 Jacobian of\n"
        f"  that arm ({dk['bound']:.4f}), and under our frames every Table 3 pose has M_a = 0 (the far corner lies "
        f"beyond l1 + l2);\n  our GA runs' M_a is {dk['ga_m_min']:.4f}–{dk['ga_m_max']:.4f}. The readings tried "
        "and Table 4 by FK are in docs/reproduction.md.\n"
        f"- **Surrogates** ([theory §4](docs/theory.md#4-surrogates), paper Tables 4–5), with the paper's Jacobian "
        f"(spatial form, eq. 6):\n  FFBN-w {net('ffbn_w')}; "
        f"FFBN-KCI {net('ffbn_kci')}; RBFN-w {net('rbfn_w')} (paper: {D16_NETWORKS['ffbn_w']['hidden_units']}, "
        f"{D16_NETWORKS['ffbn_kci']['hidden_units']}, {D16_NETWORKS['rbfn_w']['hidden_units']} units; all < 2 %); "
        f"against the project's fastest\n  analytic path (the fused `indices.manipulability_of` / `kci_of` kernel, "
        f"same run,\n  preset \"{dx['preset']}\", {dx['device']}), at {' / '.join(_batch(int(b)) for b in batches)} "
        f"inputs, the FFBN runs at {speedups('ffbn_w')} its speed for w and {speedups('ffbn_kci')} for KCI,\n  "
        f"RBFN-w at {speedups('rbfn_w')} and RBFN-KCI at {speedups('rbfn_kci')} (the paper timed Matlab LU/SVD "
        f"on the symbolic Jacobian and gives one time per network type; above 1e5 inputs both sides ran in chunks "
        f"through `lax.map`, which slows each chunk several-fold: BENCHMARKS.md, Surrogates). FFBN-KCI {dx['ffbn_kci']} in that run; "
        f"with\n  {dx['sizes_n_train']} training samples (ours; the paper gives no training-set size; "
        f"`{dx['sizes_file']}`) it {dx['sizes_result']}. "
        f"With our\n  geometric Jacobian KCI ignores the vehicle's joints and FFBN-KCI needs {net('ffbn_kci', ours)}.\n"
        f"- **Scheduling** ([theory §5](docs/theory.md#5-pick-and-place-scheduling), thesis Table 5.5, eq. 4.1): greedy "
        f"gives the\n  thesis's schedule {eq['greedy']['path']} / {eq['greedy']['cost']:.4f} in "
        f"{eq['greedy']['ms']:.3g} ms (thesis {t55['Dijkstra'][5]:g} ms on its own instance); GRASP\n  (1000 "
        f"iterations, {eq['grasp/deliveries']['ms']:.3g} ms; thesis {t55['GRASP'][5]:g} ms), A* ({eq['astar']['ms']:.3g} ms; "
        f"thesis {t55['A*'][5]:g} ms) and the exact DP find the\n  optimum {eq['exact']['cost']:.4f}. With the thesis's "
        f"own local search (`sched.grasp.local_search=thesis`) GRASP(1000)\n  finds it in "
        f"{eq['grasp/thesis']['optimal_of_20']} of 20 runs.\n")


#: benchmarks/docking_fitness.py's variants, as the tables name them.
FITNESS_VARIANTS = {"kernels": "IK kernel + collision kernel (the library's GPU path)",
                    "ik kernel": "IK kernel, XLA collision test", "cholesky": "XLA, written-out Cholesky (the library's CPU path)",
                    "lu": "XLA, LU solve"}


def docking_fitness() -> str:
    """The demo's docking fitness per batch and variant (``benchmarks/docking_fitness.py``: each
    file's variants timed in one process), and the GPU path's arithmetic against the H100's
    compute ceiling."""
    names = ("docking_fitness_cpu.json", "docking_fitness_h100.json")
    rows = []
    for name in names:
        d = _load(name)
        device = d["device"] if d["platform"] == "gpu" else f"{d['cpus']}-core CPU"
        for variant, runs in d["variants"].items():
            rows += [[device, _int(r["batch"]), FITNESS_VARIANTS[variant], _sci(r["poses_per_s"]), f"{r['compile_s']:.0f}",
                      f"{r['fitness_sum']:.9g}"] for r in runs]
    cpu, gpu = (_load(n) for n in names)
    kernels, ik = gpu["variants"]["kernels"][-1], gpu["variants"]["ik kernel"][-1]
    chol, lu = cpu["variants"]["cholesky"][-1], cpu["variants"]["lu"][-1]
    flops = kernels["dls_flops_per_pose"] + gpu["collision_flops_per_pose"]
    ceiling = 2 * HOPPER_FP32  # XLA counts a multiply-add as two flops
    return (" and ".join(f"`{_load(n)['command']}`" for n in names) + f" (jax {gpu['jax']} on the GPU). At "
            f"{_int(kernels['batch'])} poses on the {gpu['device']} the library's path runs "
            f"**{_sci(kernels['poses_per_s'])} poses/s**, {kernels['poses_per_s'] / ik['poses_per_s']:.2f}× the IK kernel "
            f"with XLA's collision test (the path before the collision kernel) in the same process, with the same "
            f"fitness sum. A pose costs {kernels['dls_flops_per_pose'] / 1e6:.2f} Mflop of DLS iterations and "
            f"{gpu['collision_flops_per_pose'] / 1e6:.2f} Mflop of collision tests (XLA's count of the same arithmetic "
            f"on the GPU), so the kernels achieve {flops * kernels['poses_per_s'] / 1e12:.1f} TFLOP/s: "
            f"{100 * flops * kernels['poses_per_s'] / ceiling:.0f} % of the H100's {ceiling / 1e12:.0f} TFLOP/s FP32 ceiling "
            f"(132 SMs × 128 lanes × 1.98 GHz, a multiply-add as two flops), which bounds the fitness near "
            f"{_sci(ceiling / flops)} poses/s. On the CPU at {_int(chol['batch'])} poses the written-out Cholesky runs "
            f"{chol['poses_per_s'] / lu['poses_per_s']:.2f}× the LU solve.\n\n"
            + md_table(["device", "batch", "variant", "poses/s", "compile [s]", "fitness sum"], rows) + "\n\n"
            + "\n".join(_fitness_stages(_load(n)) for n in names))


def _fitness_stages(d: dict) -> str:
    """Where the fitness's time goes (``stages`` of a docking_fitness record), one paragraph."""
    st = d["stages"]["seconds"]
    ik, fk, hit, whole = st["ik"], st["ik + fk + reach test"], st["ik + fk + collision test"], st["fitness"]
    device = d["device"] if d["platform"] == "gpu" else f"{d['cpus']}-core CPU"
    return (f"Where the time goes, {device} at {_int(d['stages']['batch'])} poses (each piece compiled alone, "
            f"the library's path): the IK {1e3 * ik:.1f} ms ({1e3 * st['ik, 1 iteration']:.1f} ms with one "
            f"iteration), with the forward kinematics and reach test {1e3 * fk:.1f} ms, with the collision test "
            f"instead {1e3 * hit:.1f} ms, with w instead {1e3 * st['ik + w']:.1f} ms; the whole fitness "
            f"{1e3 * whole:.1f} ms: the IK {100 * ik / whole:.0f} %, the collision test {100 * (hit - fk) / whole:.0f} %.\n")


def _int(n: float) -> str:
    """``2 430 252``: a whole number with spaces between thousands."""
    return f"{round(n):,}".replace(",", " ")


def _range(values, fmt: str = ".4f") -> str:
    lo, hi = min(values), max(values)
    return f"{lo:{fmt}}" if f"{lo:{fmt}}" == f"{hi:{fmt}}" else f"{lo:{fmt}}–{hi:{fmt}}"


def docking_ga() -> str:
    """The paper's docking problem: the GA batch, the dense grid and CMA-ES (evosax) on the CPU and
    on a GPU, from ``benchmarks/docking.py``'s result files."""
    files = ("docking_cpu.json", "docking_h100.json")
    cpu, *gpus = (_load(f) for f in files)

    def ga_row(d):
        g = d["ga"]
        return (f"GA, {g['runs']} run{'s' * (g['runs'] > 1)} × {_int(g['population'])} in one call "
                f"({_range(g['generations'], 'd')} generations; {_int(sum(g['evaluations']))} evaluations"
                + (f", fitness cache of {g['eval_chunk']}" if g["eval_chunk"] else ", no cache") + ")")

    def t(part):
        return f"{part['best_s']:.3g} s ({part['median_s']:.3g} s)" if "median_s" in part else f"{part['best_s']:.3g} s"

    def grid_row(d):
        g = d["grid"]
        return (f"grid search, {_int(g['candidates'])} candidates ({' × '.join(map(str, g['counts']))}), "
                f"chunks of {_int(g['chunk'])}")

    def cma_row(d):
        c = d["cmaes"]
        return f"CMA-ES (evosax), {c['runs']} runs × {_int(c['population'])} × {c['generations']} generations"

    rows = []
    for d in (cpu, *gpus):
        label = "2-core CPU" if d is cpu else d["device_kind"]
        g, gr, c = d["ga"], d["grid"], d["cmaes"]
        rows += [[label, ga_row(d), t(g), f"{_rate(g['evaluations_per_s'])} evaluations/s", f"{g['compile_and_first_s']:.0f} s"],
                 [label, grid_row(d), t(gr), f"{_rate(gr['candidates_per_s'])} candidates/s",
                  f"{gr['compile_and_tiny_grid_s']:.0f} s"],
                 [label, cma_row(d), t(c), f"{_rate(c['evaluations_per_s'])} evaluations/s", f"{c['compile_and_first_s']:.0f} s"]]
    # The optimum of the paper's problem: the grid of `make papers` (docs/reproduction.json), finer
    # than the CPU's grid, which the GA runs beat.
    optimum = _reproduction()["sections"]["docking"]["grid_best"]
    ratios = [f / optimum for f in cpu["ga"]["best_fitness"]]
    on = lambda parts: " and ".join(parts)  # noqa: E731
    return (f"Commands: `{cpu['command']}` (2-core {cpu['platform']} CPU, jax {cpu['jax']}, load average "
            f"{cpu['load_average_start'][0]:.1f} at the start) and "
            + on(f"`{d['command']}` ({d['device_kind']}, jax {d['jax']})" for d in gpus)
            + "; files " + ", ".join(f"`benchmarks/results/{f}`" for f in files) + ". Times after compilation, best "
            "of the repeats (median in brackets).\n\n"
            + md_table(["device", "what", "time", "rate", "compile + first call"], rows)
            + f"\n\nGA against CMA-ES, evaluations/s: {cpu['ga_over_cmaes_evaluations_per_s']:.2f}× on the CPU, "
            + on(f"{d['ga_over_cmaes_evaluations_per_s']:.2f}× on the {d['device_kind']}" for d in gpus)
            + f". On the CPU the {cpu['ga']['runs']} GA runs reach "
              f"{_range(ratios, '.3f')} of the optimum {optimum:.4f} (the grid of `make papers`, docs/reproduction.json; "
              f"{sum(r >= 0.99 for r in ratios)} of {len(ratios)} ≥ 0.99); the "
              f"{_int(cpu['grid']['candidates'])}-candidate grid above finds {cpu['grid']['best_fitness']:.4f}, "
              f"CMA-ES {max(cpu['cmaes']['best_fitness']):.4f}. The paper's 1e8-candidate grid takes "
            + on(f"{d['grid']['best_s']:.2f} s on the {d['device_kind']}" for d in gpus) + ". " + _grid_chunks())


def _grid_chunks() -> str:
    """The paper's 1e8 grid in chunks of several sizes on a GPU: compile time and search time."""
    d = _load("docking_grid_chunks_h100.json")
    runs = [(_int(r["chunk"]), r["grid"]["compile_and_tiny_grid_s"], r["grid"]["best_s"]) for r in d["runs"]]
    return (f"In chunks of {', '.join(c for c, _, _ in runs[:-1])} and {runs[-1][0]} candidates it compiles (with a "
            f"2⁴ grid's call) in {', '.join(f'{t:.0f}' for _, t, _ in runs)} s and searches the grid in "
            f"{', '.join(f'{t:.2f}' for _, _, t in runs)} s on the {d['device_kind']} (`{d['command']}`, "
            f"`benchmarks/results/docking_grid_chunks_h100.json`).\n")


def docking_panel() -> str:
    """The Bravo 7 docked beside a panel (numerical IK), from ``experiments/docking.py
    docking/preset=bravo7``'s outputs on a GPU."""
    d = _load("docking_panel_h100.json")
    s, g = d["summary"], d["grid_optimum"]
    b = d["best_pose"]
    p = b["pose"]
    w = [t["w"] for t in b["targets"] if t["reached"]]
    return (f"{d['device_kind']}, jax {d['jax']}, float32, `{d['command']}` (`benchmarks/results/docking_panel_h100.json`): "
            f"the 7 GA runs in one call {s['ga_batch_seconds']:.1f} s after compilation "
            f"({s['ga_compile_and_first_batch_seconds']:.0f} s with it), {_range(s['ga_generations'], 'd')} generations, "
            f"{_int(sum(s['ga_evaluations']))} evaluations, **{_int(s['ga_evaluations_per_s'])} evaluations/s**; the grid's "
            f"{_int(g['candidates'])} candidates ({' × '.join(map(str, g['counts']))}) {g['seconds']:.0f} s "
            f"({_int(s['grid_candidates_per_s'])} candidates/s), its {len(g['refined']['stages'])} zoom stages "
            f"({_int(g['refined']['candidates'])} candidates) {g['refined']['seconds']:.0f} s with their compilation.\n\n"
            + md_table(["reference", "fitness", "GA / reference, 7 runs", "runs ≥ 0.99"],
                     [[f"grid {' × '.join(map(str, g['counts']))}", f"{g['fitness']:.4f}",
                       ", ".join(f"{r:.3f}" for r in s["ga_ratio_to_grid"]), str(s["ga_runs_within_0.99_of_grid"])],
                      [f"grid + {len(g['refined']['stages'])} zoom stages", f"{g['refined']['fitness']:.4f}",
                       ", ".join(f"{r:.3f}" for r in s["ga_ratio_to_refined_grid"]),
                       str(s["ga_runs_within_0.99_of_refined_grid"])]])
            + f"\n\nThe chosen pose ({b['source']}), x = {p['x']:.3f} m, y = {p['y']:.3f} m, z = {p['z']:.3f} m, "
              f"ψ = {math.degrees(p['psi']):.1f}°, reaches {len(w)} of {len(b['targets'])} panel poses with w "
              f"{min(w):.4f}–{max(w):.4f} (M_a = {b['Ma']:.4f}).\n")


def docking_map() -> str:
    # The CPU run first, then any GPU's.
    files = sorted((f.name for f in RESULTS.glob("docking_map_*.json")), key=lambda n: (n != "docking_map_cpu.json", n))
    out, rows = [], []
    for name in files:
        d = _load(name)
        device = f"{d['cpu_count']}-core CPU" if d["platform"] == "cpu" else d["device"]
        sm = d["summary"]
        out.append(f"**{device}** (jax {d['jax']}; `{d['command']}`): in **{sm['met']} of {sm['seeds']}** seeds the map's "
                   f"route loses ≤ 2 % of the analytic search's optimum with ≥ 50× fewer analytic evaluations: loss "
                   f"{100 * sm['loss_max']:.2f} % at worst (median {100 * sm['loss_median']:.2f} %), evaluation ratio "
                   f"{sm['ratio_min']:.0f}× at least (median {sm['ratio_median']:.0f}×).")
        for r in d["runs"]:
            rows.append([device, str(r["seed"]), f"{r['analytic_best']:.4f}", str(r["analytic_evaluations"]),
                         f"{r['best_candidate_fitness']:.3f}", f"{r['map_route_fitness']:.4f}",
                         f"{r['ratio_to_reference']:.4f}", str(r["map_route_analytic_evaluations"]),
                         f"{100 * r['loss_of_optimum']:.2f} %", f"{r['evaluation_ratio']:.0f}×",
                         f"{r['amortised_ratio']:.1f}×", f"{r['analytic_wall_s']:.0f} / {r['map_route_wall_s']:.0f}"])
    d = _load(files[0])
    r0 = d["runs"][0]
    return ("\n\n".join(out) + f" The map: {r0['map_tool_poses']} tool poses, what "
            f"{r0['map_vehicle_pose_equivalents']:.0f} docking evaluations of this task cost; the amortised ratio counts "
            f"them in one run. Reference: {d['reference_fitness']:.4f} (dense grid + zoom, "
            f"`benchmarks/results/docking_reference_demo_h100.json`).\n\n"
            + md_table(["device", "seed", "analytic search: best", "its evaluations", "map: best candidate (analytic)",
                      "map route: refined (analytic)", "/ reference", "its analytic evaluations", "loss of optimum",
                      "evaluation ratio", "amortised ratio (map counted)", "wall [s] analytic / map route"], rows) + "\n")


def docking_collision() -> str:
    """docs/docking.md's one world: docking's JAX collision test against the planner's sphere
    checker and MuJoCo, its size and its cost beside the link capsules it replaced, per arm."""
    rows, cost = [], []
    for name, arm in (("docking_collision_demo_cpu.json", "Bravo 7"), ("docking_collision_panda_cpu.json", "Panda")):
        d = _load(name)
        a, w, b = d["agreement"], d["world"], d["batch"]
        rows.append([arm, f"`{d['command']}`", f"{a['configurations']:,}".replace(",", " "),
                     f"{100 * a['jax_free']:.1f} / {100 * a['spheres_free']:.1f} / {100 * a['mujoco_free']:.1f}",
                     f"{100 * a['agree_spheres']:.2f}", f"{100 * a['agree_mujoco']:.2f}",
                     f"{a['jax_collision_spheres_free']} / {a['jax_collision_mujoco_free']}",
                     f"{a['jax_free_spheres_collision'] + a['jax_free_mujoco_collision']}"])
        cost.append([arm, str(w["spheres_per_row"]), f"{w['sphere_pairs_per_row']:,}".replace(",", " "),
                     f"{b['poses']} × {b['tool_poses']} × {b['seeds']} = {b['configurations']:,}".replace(",", " "),
                     f"{d['capsules']['run_s']:.3f}", f"{d['spheres']['run_s']:.3f}",
                     f"{d['spheres_over_capsules_time']:.1f}×", f"{d['fitness']['run_s']:.2f}",
                     f"{d['host']['load_average'][0]:.1f}"])
    return (md_table(["arm", "command (2-core CPU)", "configurations", "free: JAX / spheres / MuJoCo [%]",
                    "agrees with spheres [%]", "agrees with MuJoCo [%]", "JAX collision where spheres / MuJoCo free",
                    "JAX free where either collides"], rows) + "\n\n"
            + md_table(["arm", "spheres per target", "sphere pairs per target", "batch (poses × tool poses × seeds)",
                      "capsules [s]", "world [s]", "world / capsules", "whole fitness call [s]",
                      "load average (shared CPU)"], cost) + "\n"
            + _mesh_cost(_load("docking_collision_demo_cpu.json"), _load("docking_collision_panda_cpu.json"))
            + _mjx(_load("docking_collision_demo_cpu.json")))


def _mesh_cost(bravo: dict, panda: dict) -> str:
    w, v = panda["world"], bravo["world"]
    return (f"\nThe Panda's mesh links make {w['spheres_per_row'] / v['spheres_per_row']:.0f} times the Bravo 7's "
            f"spheres and {w['sphere_pairs_per_row'] / v['sphere_pairs_per_row']:.0f} times its sphere pairs: its world "
            f"takes {100 * panda['fitness']['collision_share_of_time']:.0f} % of its fitness call.\n")


def _mjx(d: dict) -> str:
    """MJX collision of the Bravo 7's docked MuJoCo scene, when the run measured it."""
    if "mjx" not in d:
        return ""
    m = d["mjx"]
    per_config = (m["run_s"] / m["configurations"]) / (d["spheres"]["run_s"] / d["batch"]["configurations"])
    return (f"\nMJX collision of the same MuJoCo scene (one vehicle pose, the base fixed): {m['run_s']:.2f} s for "
            f"{m['configurations']} configurations after a {m['compile_s']:.0f} s compilation, {per_config:.0f} times "
            "the world's time per configuration on this CPU (and it would need the base as a moving body for docking).\n")


def hw_runner() -> str:
    d = _load("hw_cpu.json")
    c, r, st = d["codec"], d["round_trip"], d["stream"]
    rows = [
        ["encode POSITION packets [packets/s]", f"{c['encode_packets_per_s']:,} (table CRC-8 from the `crc` library + `cobs`)",
         f"{c['peer_encode_packets_per_s']:,} (`crc.Calculator.checksum` per packet + `cobs`)", f"{c['encode_ratio']}×"],
        ["decode stream, MTU-sized chunks [packets/s]", f"{c['decode_packets_per_s']:,} (`PacketReader.feed`)",
         f"{c['peer_decode_packets_per_s']:,} (split + `cobs.decode` + `Calculator.checksum`)", f"{c['decode_ratio']}×"],
        ["REQUEST POSITION+VELOCITY → 14 answers (14 datagrams, one packet each), simulator in its own process "
         "(`uvms-hw sim`), UDP loopback", f"p50 {r['bravo7_sim_process']['p50_ms']} ms, p99 {r['bravo7_sim_process']['p99_ms']} ms",
         f"bare UDP echo thread: p50 {r['peer_udp_echo']['p50_ms']} ms, p99 {r['peer_udp_echo']['p99_ms']} ms",
         f"{r['p50_ratio']}× (p50)"],
        ["same, simulator as a thread of the client process (as `uvms-hw run --sim`)",
         f"p50 {r['bravo7_sim_thread']['p50_ms']} ms, p99 {r['bravo7_sim_thread']['p99_ms']} ms", "", ""],
        [f"state stream at {st['stream_hz']} Hz from `uvms-hw sim` (heartbeat, `Bravo7.stream_state`)",
         f"{st['streamed']['states_per_s']} states/s, {st['streamed']['packets_sent_per_state']} packets sent per state",
         f"polling (`read_state`) as fast as it goes: {st['polled']['states_per_s']} states/s, "
         f"{st['polled']['packets_sent_per_state']} request per state", ""],
    ]
    return (f"`{d['command']}` ({d['device']}; `benchmarks/results/hw_cpu.json`):\n\n"
            + md_table(["what", "project", "peer", "ratio"], rows) + "\n")


def hw_acceptance() -> str:
    d = _load("hw_acceptance_cpu.json")

    def run(r):
        res, sim = r["result"], r["result"].get("sim") or {}
        return (f"{res['status']}, {res['gates']} gates, max gate error {res['max_gate_error_rad']:.5f} rad / "
                f"{res['max_gate_error_mm']:.2f} mm, {res['duration_s']:.1f} s, {res['rejected_states']} rejected states"
                + (f", {sim['dropped']} datagrams dropped and {sim['corrupted']} corrupted by the simulator, "
                   f"{res['link_timeouts']} tick timeouts, {sim['limit_violations']} demands outside the limits"
                   if sim.get("dropped") else ""))
    clean, lossy = d["runs"]
    return (f"`{clean['command']}` and `{lossy['command']}` (real time, the two runs side by side on the 2-core CPU; "
            f"`benchmarks/results/hw_acceptance_cpu.json`): {run(clean)}; with loss and corruption: {run(lossy)}.\n")


def sched_benchmark() -> str:
    d = _load("sched_cpu.json")
    t, sc, lg = d["thesis_instance"], d["scoring"], d["large"]
    rows = [["greedy (\"Dijkstra\")", f"{t['greedy']['cost']:.4f} (`{t['greedy']['path']}`)", f"{t['greedy']['median_ms']:.3g}",
             f"{t['greedy']['thesis_ms']}"],
            ["GRASP, 1000 iterations, one jitted call", f"{t['grasp_1000']['cost']:.4f} (optimum in "
             f"{t['grasp_1000']['optimum_found_fraction']:.0%} of the runs)", f"{t['grasp_1000']['median_ms']:.3g}",
             f"{t['grasp_1000']['thesis_ms']}"],
            ["A* (thesis heuristic)", f"{t['astar']['cost']:.4f}", f"{t['astar']['median_ms']:.3g}", f"{t['astar']['thesis_ms']}"],
            ["exact DP", f"{t['exact']['cost']:.4f}", f"{t['exact']['median_ms']:.3g}", "—"],
            ["OR-Tools, first solution", f"{t['ortools_first_solution']['cost']:.4f}",
             f"{t['ortools_first_solution']['time_ms']:.3g}", "—"],
            ["OR-Tools, guided local search 1 s", f"{t['ortools_gls_1s']['cost']:.4f}", f"{t['ortools_gls_1s']['time_ms']:.4g}", "—"]]
    big = []
    for key, label in (("10x10_1to3_bases", "1–3 allowed bases per object"), ("10x10_all_bases", "every base allowed")):
        g = lg[key]

        def ort(name):
            return f"{g[name]['time_ms']:.4g} ms, gap {g[name]['gap']:.1%}"
        big.append([label, f"{g['exact']['median_ms']:.3g} ms ({g['exact']['states']:,} states)",
                    f"{g['grasp_1000']['median_ms']:.3g} ms, {g['grasp_1000']['gap_mean']:.1%} / {g['grasp_1000']['gap_best']:.1%}",
                    ort("ortools_first_solution"), ort("ortools_gls_1s"), ort("ortools_gls_5s")])
    return (f"`{d['command']}` ({d['device']}; `benchmarks/results/sched_cpu.json`; medians over repeats after a "
            f"warm-up, GRASP's one-off compile of {t['grasp_compile_s']:.1f} s excluded).\n\n"
            "Thesis instance (eq. 4.1, 10 nodes):\n\n"
            + md_table(["solver", "cost", "time [ms]", "thesis (Table 5.5) [ms]"], rows)
            + f"\n\nBatch scoring (`score`, {sc['batch']:,} schedules of 13 nodes, about half of them shuffled and "
            f"invalid): {_sci(sc['schedules_per_s'])} schedules/s (best run {_sci(sc['schedules_per_s_best'])}); the "
            f"same checks in NumPy: {_sci(sc['peer_numpy_schedules_per_s'])}/s "
            f"({sc['schedules_per_s'] / sc['peer_numpy_schedules_per_s']:.1f}×).\n\n"
            "10 objects / 10 bases (random costs; gaps to the exact optimum):\n\n"
            + md_table(["instance", "exact DP", "GRASP 1000 it (gap mean / best of 5)", "OR-Tools first solution",
                      "OR-Tools GLS 1 s", "OR-Tools GLS 5 s"], big) + "\n")


def plan_benchmark() -> str:
    d = _load("plan_cpu.json")
    rows = []
    for checker, c in d["checkers"].items():
        for planner, p in c["planners"].items():
            rows.append([checker, planner, f"{p['success']}/{p['edges']}", f"{p['revalidated']}/{p['edges']}",
                         f"{p['median_ms']:.1f}", f"{p['mean_ms']:.1f}", f"{p['max_ms']:.1f}", f"{p['graph_wall_s']:.2f}"])
    v = d["validity_checks"]
    checks = [["MuJoCo `is_valid(q)` (argument checks)", f"{v['mujoco_single_is_valid_per_s']:,.0f}"],
              ["MuJoCo OMPL callback (`state_validator`)", f"{v['mujoco_ompl_callback_per_s']:,.0f}"],
              ["MuJoCo `is_valid_batch(Q)`", f"{v['mujoco_batched_is_valid_per_s']:,.0f}"],
              ["sphere checker, one call over all states", f"{v['spheres_one_call_per_state_per_s']:,.0f}"]]
    sp, mj = d["checkers"]["spheres"], d["checkers"].get("mujoco")
    steps = sp["planners"]["RRTConnect"]["steps_s"]
    return (f"`{d['command']}` ({d['device']}; `benchmarks/results/plan_cpu.json`): {d['budget_s']:g} s per-edge budget, "
            f"the straight-segment shortcut {'on' if d['straight_shortcut'] else 'off (each planner its own path, simplified)'}."
            "\n\n" + md_table(["checker", "planner", "planned", "re-checked OK", "median [ms]", "mean [ms]", "max [ms]",
                                "whole graph [s]"], rows)
            + f"\n\nWhole task graph with all three planners: {sp['graph_all_planners_wall_s']:.2f} s with the sphere checker"
            + (f" against {mj['graph_all_planners_wall_s']:.2f} s with MuJoCo state by state" if mj else "")
            + ". Where RRTConnect's graph time goes (spheres, `steps_s`): "
            + ", ".join(f"{k.replace('_', ' ')} {t:.3f} s" for k, t in steps.items())
            + f". IK targets (one batched `kin.numeric_ik` call, compilation included, warm cache) "
            f"{d['ik_targets_s_incl_compile']:.1f} s; the sphere checker's Numba compile or cache load "
            f"{d['numba_compile_or_cache_load_s']:.2f} s.\n\nValidity checks (uniform random configurations, "
            f"{v['valid_fraction_uniform']:.0%} valid):\n\n" + md_table(["call", "checks/s"], checks) + "\n")


def _ms(v: float) -> str:
    return f"{v:.1f}" if v < 100 else f"{v:.0f}"


def mbm_benchmark() -> str:
    """The MotionBenchMaker Panda set on the CPU: the query path beside OMPL with MuJoCo."""
    d = _load("mbm_cpu.json")
    peer = "ompl_mujoco" in next(iter(d["families"].values()))
    vamp = "vamp" in next(iter(d["families"].values()))
    rows = []
    for family, f in d["families"].items():
        q = f["query"]
        row = [family, str(q["valid"]), f"{q['solved']}", _ms(q["median_ms"]), _ms(q["p95_ms"]), _ms(q["max_ms"]),
               str(q["rechecked_free"])]
        if peer:
            o = f["ompl_mujoco"]
            row += [str(o["solved"]), str(o["rechecked_free"]), _ms(o["median_ms"]), _ms(o["p95_ms"]), _ms(o["max_ms"])]
        if vamp:
            v = f["vamp"]
            row += [str(v["solved"]), str(v["rechecked_free"]), str(v["in_limits"]), _ms(v["median_ms"]),
                    _ms(v["p95_ms"]), _ms(v["max_ms"]), f"{v['own_median_ms'] * 1e3:.0f}"]
        rows.append(row)
    t = d["query_total"]
    header = ["family", "valid", "solved", "median [ms]", "p95 [ms]", "max [ms]", "re-checked free"]
    if peer:
        header += ["OMPL+MuJoCo solved", "re-checked free", "median [ms]", "p95 [ms]", "max [ms]"]
    if vamp:
        header += ["VAMP solved", "re-checked free", "in the URDF's limits", "median [ms]", "p95 [ms]", "max [ms]",
                   "its own clock, median [µs]"]
    invalid = ", ".join(f"{n} {reason}" for reason, n in sorted(d["invalid"].items()))
    checks = d["state_check"]
    spheres = sorted(c["spheres_us"] for c in checks.values())
    verdict = sorted(c["verdict_us"] for c in checks.values())
    mujoco = sorted(c["mujoco_us"] for c in checks.values())
    maybe = sorted(c["maybe_fraction"] for c in checks.values())
    return (f"`{d['command']}` ({d['device']}, 2 cores; `benchmarks/results/mbm_cpu.json`): the Panda with its own "
            f"hand and fingers from its URDF ({d['n_spheres']} covering spheres, largest excess "
            f"{d['sphere_excess_m'] * 1e3:.0f} mm), fingers at {d['opening_m']:g} m (the requests' "
            f"{d['request_opening_m']:g} m is past the URDF's limit), {d['budget_s']:g} s budget per problem, "
            f"a failure counted at the whole budget. Every returned path re-checked by MuJoCo with the real "
            f"fingers, densified to {d['recheck_rad']:g} rad.\n\n" + md_table(header, rows)
            + f"\n\nAll families: {t['solved']}/{t['valid']} model-valid problems solved ({t['success_rate']:.1%}), "
            f"median {_ms(t['median_ms'])} ms, p95 {_ms(t['p95_ms'])} ms, {t['rechecked_free']} of the {t['solved']} "
            f"returned paths free for MuJoCo. "
            f"Invalid in the model (MuJoCo on the description's geometry; limits in float64): {invalid}. "
            f"Numba compile or cache load {d['compile_s']:.1f} s before any timing.\n\n" + _mbm_vamp(d) +
            f"Per state, one call over 4096 uniform random configurations (range over the seven families' first "
            f"worlds): the spheres alone {spheres[0]:.1f}–{spheres[-1]:.1f} µs ({maybe[-1]:.0%} or fewer "
            f"undecided), the verdicts with MuJoCo settling those {verdict[0]:.1f}–{verdict[-1]:.1f} µs, MuJoCo "
            f"alone {mujoco[0]:.1f}–{mujoco[-1]:.1f} µs.\n")


def _mbm_vamp(d: dict) -> str:
    """The VAMP peer's totals in the MotionBenchMaker run, if it ran (docs/planning.md, 'VAMP as a peer')."""
    if "vamp_total" not in d:
        return ""
    v = d["vamp_total"]
    return (f"VAMP (its own 59-sphere model, fingers at 0.065 m; docs/planning.md, \"VAMP as a peer\"): "
            f"{v['solved']}/{v['valid']} solved, median {_ms(v['median_ms'])} ms per call from Python and "
            f"{v['own_median_ms'] * 1e3:.0f} µs by its own clock, {v['rechecked_free']} of the {v['solved']} paths free "
            f"for MuJoCo, a finger in every contact of {v['fingers_only_hits']} of the others, "
            f"{v['in_limits']} inside the URDF's limits; its model calls {v['model_invalid']} of the problems "
            f"invalid.\n\n")


def mbm_summary() -> str:
    """docs/planning.md's summary of the MotionBenchMaker run (``benchmarks/mbm.py``)."""
    d = _load("mbm_cpu.json")
    t = d["query_total"]
    peer = [f["ompl_mujoco"] for f in d["families"].values() if "ompl_mujoco" in f]
    line = (f"{t['solved']}/{t['valid']} model-valid problems solved ({t['success_rate']:.1%}), median "
            f"{_ms(t['median_ms'])} ms and p95 {_ms(t['p95_ms'])} ms per problem, {t['rechecked_free']} of the "
            f"{t['solved']} returned paths free for MuJoCo at {d['recheck_rad']:g} rad")
    if peer:
        line += (f"; OMPL's RRT-Connect with MuJoCo's checks solved {sum(p['solved'] for p in peer)} with family "
                 f"medians of {_ms(min(p['median_ms'] for p in peer))}–{_ms(max(p['median_ms'] for p in peer))} ms")
    vamp = [f["vamp"] for f in d["families"].values() if "vamp" in f]
    if vamp:
        line += (f"; VAMP solved {sum(v['solved'] for v in vamp)} with family medians of "
                 f"{_ms(min(v['median_ms'] for v in vamp))}–{_ms(max(v['median_ms'] for v in vamp))} ms, "
                 f"{sum(v['rechecked_free'] for v in vamp)} of its paths free for MuJoCo")
    invalid = ", ".join(f"{n} {reason}" for reason, n in sorted(d["invalid"].items()))
    return (line + f". Invalid in the model: {invalid} (`benchmarks/results/mbm_cpu.json`, {d['device']}, "
            f"{d['budget_s']:g} s budget).\n")


def mbm_gpu() -> str:
    """The MotionBenchMaker Panda set in one batched call on a GPU (``benchmarks/mbm_gpu.py``)."""
    d = _load("mbm_gpu_h100.json")
    t = d["totals"]
    rows = [[f.removesuffix("_panda"), str(v["problems"]), str(v["endpoints_free"]), str(v["solved"]),
             str(v["rechecked_free"])] for f, v in d["families"].items()]
    return (f"`python benchmarks/mbm_gpu.py --device gpu` ({d['device']}, jax {d['jax']}, {d['dtype']}; "
            f"`benchmarks/results/mbm_gpu_h100.json`): all {d['n_problems']} problems in one jitted call, "
            f"{d['n_spheres']} covering spheres, no MuJoCo on the GPU (a state the spheres cannot tell counts as "
            f"a collision). Compile {d['compile_s']:.1f} s, run {min(d['run_s']):.0f} s; {t['solved']} solved, "
            f"every one free for MuJoCo at {d['settings']['resolution']:g} rad; {t['endpoints_free']} have a start "
            f"and goal the spheres call free.\n\n"
            + md_table(["family", "problems", "ends free (spheres)", "solved", "re-checked free"], rows) + "\n")


def pipeline_arms() -> str:
    d = _load("pipeline_arms_cpu.json")
    rows = []
    for r in d["runs"]:
        if "error" in r:
            rows.append([r["arm"], "", "", "", "", "", "", f"{r['process_wall_s']:.1f}", "—", "—", f"stopped: {r['error']}"])
            continue
        t = r["stage_wall_s"]
        rows.append([r["arm"], str(r["dof"]), *(f"{t[k]:.1f}" for k in ("docking", "plan", "schedule", "hw")),
                     f"{r['stages_wall_s']:.1f}", f"{r['process_wall_s']:.1f}", f"{r['edges_planned']}/34", r["schedule"],
                     f"{r['run']}, {r['gates']} gates, {r['executed_s']:.1f} s"])
    return (f"`{d['command']}` ({d['machine']['cpus']}-core CPU; `benchmarks/results/pipeline_arms_cpu.json`; preset "
            f"{d['preset']}, collision geometry from the {d['collision']}):\n\n"
            + md_table(["arm", "joints", "docking [s]", "plan [s]", "schedule [s]", "hw [s]", "stages [s]", "process [s]",
                      "edges planned", "schedule", "executed (simulated)"], rows) + "\n")


def own_arm() -> str:
    """README's own-arm example: what it prints and how long it takes (``benchmarks/own_arm.py``)."""
    d = _load("own_arm_cpu.json")
    return (f"prints `{d['printed'][0]}` and `{d['printed'][-1]}`, in {d['wall_s']:.0f} s on a "
            f"{d['cpu_count']}-core CPU with imports and compilation (`python benchmarks/own_arm.py`, "
            f"`benchmarks/results/own_arm_cpu.json`).\n")


def weights_sweep() -> str:
    """README's weight-sensitivity sweep: its gathered table and time (``benchmarks/weights_sweep.py``)."""
    d = _load("weights_sweep_cpu.json")
    return ("```bash\n" + "\n".join(d["commands"]) + "\n```\n\n"
            "gives five job folders `multirun/weights/0 … 4` (each with `table.md`, `results.json`,\n"
            "`route.png`, `schedule_edges.json`) and one table, `multirun/weights/gathered.md` (every\n"
            f"column in `gathered.csv`); both commands take {d['wall_s']:.0f} s on a {d['cpu_count']}-core CPU "
            "(`python benchmarks/weights_sweep.py`, `benchmarks/results/weights_sweep_cpu.json`):\n\n"
            + d["gathered_md"].strip() + "\n")


def hover_levelling() -> str:
    """The demo's hover stage: the largest tilt with levelling on (docs/hover.md)."""
    runs = _load("demo_cpu.json")["hover"]["runs"]
    tilt = max(r["max_tilt_deg"] for r in runs.values())
    return (f"Held level by the vertical thrusters, the tilt stays within {tilt:.1f}° in each of the demo's "
            f"{len(runs)} hover runs (the `hover` stage of `benchmarks/results/demo_cpu.json`).\n")


BLOCKS = {f.__name__: f for f in (docking_certify, test_suite, hover_vehicle, kin_roofline, scale_out, surrogate_roofline, docking_ga, docking_panel, pipeline_arms, plan_benchmark, sched_benchmark, hw_runner, hw_acceptance, kin_indices_cpu, kin_indices_accuracy, kin_indices_gpu, demo, docking_search, docking_fitness, docking_map, docking_collision,
                                   kin_summary, papers, hover_mjx, hover_robustness, surrogate_networks,
                                   surrogate_paper_sizes_cpu, surrogate_paper_sizes_h100, surrogate_sizes, own_arm,
                                   weights_sweep, hover_levelling, mbm_benchmark, mbm_gpu, mbm_summary, test_suite_isa)}


def render(text: str) -> str:
    """``text`` (a document) with every report block regenerated from its files."""
    def block(m: re.Match) -> str:
        name = m.group("name")
        if name not in BLOCKS:
            raise KeyError(f"a document has a block {name!r} that benchmarks/report.py does not write")
        return m.group(1) + BLOCKS[name]() + m.group(4)
    return BLOCK.sub(block, text)


def stale_blocks(text: str) -> list[str]:
    """Names of the blocks of ``text`` that differ from what their files give."""
    fresh = render(text)
    old = {m.group("name"): m.group("body") for m in BLOCK.finditer(text)}
    new = {m.group("name"): m.group("body") for m in BLOCK.finditer(fresh)}
    return [name for name in old if old[name] != new[name]]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="only report blocks that are out of date and prose numbers without a source")
    args = parser.parse_args()
    stale = {doc.name: stale_blocks(doc.read_text()) for doc in DOCUMENTS}
    if args.check:
        sys.path.insert(0, str(ROOT / "benchmarks"))
        import sources

        stale = {name: blocks for name, blocks in stale.items() if blocks}
        if stale:
            print(f"blocks out of date with benchmarks/results: {stale}", file=sys.stderr)
        unsourced = sources.check()
        for name, problems in unsourced.items():
            print("\n".join(f"{name}:{p}" for p in problems), file=sys.stderr)
        return 1 if stale or unsourced else 0
    for doc in DOCUMENTS:
        doc.write_text(render(doc.read_text()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
