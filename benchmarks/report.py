"""The quoted figures of BENCHMARKS.md, generated from the result files in benchmarks/results/.

Each generated block sits between ``<!-- report:NAME -->`` and ``<!-- /report:NAME -->`` in
BENCHMARKS.md, and is written by the function of that name below from the JSON files that the
benchmark scripts print (the command that wrote a file is named next to its block). So a
figure in the document always has a file and a command behind it, and
``tests/test_benchmarks_report.py`` fails when a block no longer matches its files.

Usage: python benchmarks/report.py            # rewrite the blocks of BENCHMARKS.md
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
DOCUMENT = ROOT / "BENCHMARKS.md"
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


BLOCKS = {f.__name__: f for f in (kin_indices_cpu, kin_indices_accuracy, kin_indices_gpu)}


def render(text: str) -> str:
    """``text`` with every report block regenerated from its files."""
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
    text = DOCUMENT.read_text()
    if args.check:
        stale = stale_blocks(text)
        if stale:
            print(f"BENCHMARKS.md: blocks out of date with benchmarks/results: {stale}", file=sys.stderr)
            return 1
        return 0
    DOCUMENT.write_text(render(text))
    return 0


if __name__ == "__main__":
    sys.exit(main())
