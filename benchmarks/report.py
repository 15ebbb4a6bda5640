"""The quoted figures of README.md and BENCHMARKS.md, generated from benchmarks/results/.

Each generated block sits between ``<!-- report:NAME -->`` and ``<!-- /report:NAME -->`` in one
of :data:`DOCUMENTS`, and is written by the function of that name below from the JSON files
that the benchmark scripts print or a pipeline run writes (``results.json`` of ``make demo``,
copied as ``demo_cpu.json``; the command that wrote a file is named next to its block). So a
figure in a block always has a file and a command behind it, and
``tests/test_benchmarks_report.py`` fails when a block no longer matches its files.

Usage: python benchmarks/report.py            # rewrite the blocks
       python benchmarks/report.py --check    # exit 1 naming the blocks that are out of date
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
DOCUMENTS = (ROOT / "README.md", ROOT / "BENCHMARKS.md")
BLOCK = re.compile(r"(<!-- report:(?P<name>[a-z0-9_]+) -->\n)(?P<body>.*?)(<!-- /report:(?P=name) -->)", re.S)


def _load(name: str) -> dict:
    return json.loads((RESULTS / name).read_text())


def _rate(v: float) -> str:
    """``2.50e7`` style: three significant digits, no '+' or leading zero in the exponent."""
    mantissa, exponent = f"{v:.2e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _batch(n: int) -> str:
    mantissa, exponent = f"{n:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def kin_indices_cpu() -> str:
    d = _load("kin_indices_uvms12_cpu.json")
    rows = [[_batch(r["batch"]), _rate(r["uvms_jax_w_per_s"]), _rate(r["gram_w_per_s"]), _rate(r["peer_w_per_s"]),
             f"{r['w_speedup']:.0f}", _rate(r["uvms_jax_kci_per_s"]), _rate(r["gram_kci_per_s"]),
             _rate(r["peer_kci_per_s"]), f"{r['kci_speedup']:.1f}"] for r in d["results"]]
    b7 = _load("kin_indices_bravo7_cpu.json")["results"][0]
    return (f"**2-core CPU ({d['machine']}), jax {d['jax']}, torch {d['torch']}**, 12-DOF UVMS\n"
            f"(`python benchmarks/kin_indices.py --batches 1e3,1e5`):\n\n"
            + _table(["batch", "w/s", "w/s (Gram)", "peer w/s", "w speed-up", "KCI/s", "KCI/s (Gram)",
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
    return (_table(["chain (device)", "median σ_min of the near-singular poses", "w: J factored", "w: Gram",
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
    return (_table(["batch", "w/s (kernel)", "w/s (Gram kernel)", "w/s (XLA)", "peer w/s", "KCI/s (kernel)",
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
        ["surrogate", f"map learned from {sur['n_train_poses']} poses ({sur['n_test_poses']} held out); held-out RMSE "
                      f"of w {sur['rmse_w']:.4f} (largest w {sur['w_range']:.3f})", f"{t['surrogate']:.1f}"],
        ["docking", f"GA runs: best {dock['ga_best_fitness']:.3f} (M_a {dock['ga_best_M_a']:.4f}), worst "
                    f"{dock['ga_ratio_to_grid_min'] * dock['grid_fitness']:.2f}; grid + zoom: **{dock['grid_fitness']:.3f} "
                    f"(M_a {dock['pose_M_a']:.4f})**, chosen ({dock['pose_source']}); GA on the map: "
                    f"{dock['map_best_fitness']:.3f}, a loss of optimum of {dock['map_loss_of_optimum']:.1%}, its "
                    f"evaluations {dock['map_eval_speedup']:.0f}× faster than the analytic ones", f"{t['docking']:.1f}"],
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
    return (f"Pipeline {d['total_seconds']:.1f} s (compilation cache warm):\n\n"
            + _table(["stage", "result", "wall [s]"], rows)
            + f"\n\nSo the docked arm is more dexterous over the targets (M_a {docked['M_a'] / fixed['M_a'] - 1:+.0%}), and the "
            f"fixed mount finishes\nsooner ({fixed['executed_s'] / docked['executed_s'] - 1:+.0%}): from the cage top the "
            f"arm's tool travels {fixed['ee_distance_m']:.1f} m against {docked['ee_distance_m']:.1f} m docked.\n")


BLOCKS = {f.__name__: f for f in (kin_indices_cpu, kin_indices_accuracy, kin_indices_gpu, demo)}


def render(text: str) -> str:
    """``text`` (a document) with every report block regenerated from its files."""
    def block(m: re.Match) -> str:
        name = m.group("name")
        if name not in BLOCKS:
            raise KeyError(f"BENCHMARKS.md has a block {name!r} that benchmarks/report.py does not write")
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
    parser.add_argument("--check", action="store_true", help="only report blocks that are out of date")
    args = parser.parse_args()
    stale = {doc.name: stale_blocks(doc.read_text()) for doc in DOCUMENTS}
    if args.check:
        stale = {name: blocks for name, blocks in stale.items() if blocks}
        if stale:
            print(f"blocks out of date with benchmarks/results: {stale}", file=sys.stderr)
        return 1 if stale else 0
    for doc in DOCUMENTS:
        doc.write_text(render(doc.read_text()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
