"""Report blocks of kinematics and indices: CPU and GPU rates, accuracy, roofline, scale-out."""

from __future__ import annotations

import json

from uvms_jax.text import md_table
from blocks._format import H200_BANDWIDTH, HOPPER_FP32, RESULTS, _batch, _load, _rate, _sci

__all__ = ["kin_indices_cpu", "kin_indices_accuracy", "kin_indices_gpu", "kin_roofline", "kin_summary", "scale_out"]


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
