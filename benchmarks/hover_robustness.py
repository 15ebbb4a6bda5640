"""Tool error against current speed, per controller: a demo run's scheduled plan at its docked
pose, the vehicle hovering, in a grid of currents (speed × horizontal direction), for PID alone
(the plan replayed on the servos), + feed-forward, + whole-body coordination, each with exact
and with noisy navigation (``NavigationSettings()``: 30 Hz, 50 ms, 5 mm, 0.2°), all in one MJX
call (:func:`uvms_jax.hover.batch_controlled`). Per variant and speed: the worst and the 95th
percentile over the directions of each scenario's largest gate tool error, and the first speed
at which the worst direction loses 10 mm. Writes the result file and, with ``--plot``, the plot.

    python benchmarks/hover_robustness.py RUN --device cpu --directions 8 --segments 9 \\
        --plot docs/img/hover_robustness.png       # a reduced CPU run (the file says how it was reduced)
    python benchmarks/hover_robustness.py RUN --device gpu --out benchmarks/results/hover_robustness_curve_h200.json

RUN is a ``make demo`` run folder (its ``schedule/plan.json`` and ``docking/best_pose.json``).
The full size is 48 directions and the whole plan; ``--scenarios S`` repeats the grid with fresh
navigation noise draws up to S scenarios (the last repetition cut short), for a throughput run
whose statistics then also cover the repetitions' draws.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
_CPU_FLAG = "--xla_cpu_use_fusion_emitters"  # MJX on jax 0.10's CPU backend: ~450× faster without them


def _platform() -> str:
    """Before jax is imported: ``--device cpu`` (the default) pins JAX to the CPU, with the flag above."""
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--device", choices=("cpu", "gpu"), default="cpu")
    device = pre.parse_known_args()[0].device
    if device == "cpu":
        os.environ["JAX_PLATFORMS"] = "cpu"
        if _CPU_FLAG not in os.environ.get("XLA_FLAGS", ""):
            os.environ["XLA_FLAGS"] = " ".join(filter(None, [os.environ.get("XLA_FLAGS"), f"{_CPU_FLAG}=false"]))
    return device


_DEVICE = _platform()

import jax  # noqa: E402
import numpy as np  # noqa: E402

from uvms_jax import hover, planfile  # noqa: E402
from uvms_jax.files import write_json  # noqa: E402
from uvms_jax.planfile import Plan  # noqa: E402
from uvms_jax.robot import load_arm  # noqa: E402

VARIANTS = [("PID", "pid"), ("+ feed-forward", "feed_forward"), ("+ whole-body", "whole_body")]
LOSS_M = 0.01  # the gate tolerance whose first loss is reported [m]


def _grid(chosen, speeds, directions: int, repeats: int, scenarios: int | None, gust: float, gust_s: float, seconds: float):
    """The scenarios' controls, noise flags, current profiles and labels (variant, speed, direction, draw)."""
    rows = [(v, noisy, s, d, r) for r in range(repeats) for v in chosen for noisy in (False, True)
            for s in speeds for d in range(directions)][:scenarios]
    v, noisy, s, d, r = (np.array(c) for c in zip(*rows))
    angle = 2 * np.pi * d / directions
    mean = np.stack([s * np.cos(angle), s * np.sin(angle), np.zeros_like(s)], axis=-1)
    if gust == 0:
        return v, noisy, s, r, mean, None
    profiles = [hover.CurrentSettings.gusty(m, gust, gust_s, seconds, seed=i).profile() for i, m in enumerate(mean)]
    return v, noisy, s, r, np.stack([p[1] for p in profiles]), profiles[0][0]


def _per_speed(res, mask_variant, speeds, s) -> list[dict]:
    out = []
    for speed in speeds:
        m = mask_variant & np.isclose(s, speed)
        gate = res.worst_gate_tool_error[0, m]
        reasons = res.reasons[0, m]
        held = reasons != ""
        out.append({"speed_m_s": float(speed), "scenarios": int(m.sum()), "held": int(held.sum()),
                    "held_thrust_limited": int((held & (res.thrust_limited_periods[0, m] > 0)).sum()),
                    "worst_reason": str(reasons[np.argmax(gate)]),
                    "worst_gate_tool_error_m": float(gate.max()), "p95_gate_tool_error_m": float(np.percentile(gate, 95)),
                    "worst_gate_tool_angle_deg": float(np.degrees(res.gate_tool_angle[0, m].max())),
                    "worst_tool_error_m": float(res.max_tool_error[0, m].max()),
                    "gates_reached_worst": float(res.gate_reached[0, m].mean(axis=-1).min()),
                    "thrust_limited_periods_max": int(res.thrust_limited_periods[0, m].max()),
                    "joint_limited_periods_max": int(res.joint_limited_periods[0, m].max()),
                    "thrust_violations": int(res.thrust_violations[0, m].sum()),
                    "joint_violations": int(res.joint_violations[0, m].sum()),
                    "max_joint_excess_rad": float(res.max_joint_excess[0, m].max())})
    return out


def plot(result: dict, path: Path) -> None:
    """Worst and 95th-percentile gate tool error against the current's speed, per variant."""
    from uvms_jax.plotting import pyplot

    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True, constrained_layout=True)
    colours = {"pid": "C3", "feed_forward": "C1", "whole_body": "C0"}
    for ax, key, title in zip(axes, ("worst_gate_tool_error_m", "p95_gate_tool_error_m"),
                              ("worst direction", "95th percentile of the directions")):
        for v in result["variants"]:
            x = [r["speed_m_s"] for r in v["per_speed"]]
            ax.plot(x, [1e3 * r[key] for r in v["per_speed"]], marker="o", color=colours[v["control"]],
                    ls="--" if v["navigation_noise"] else "-", label=v["name"])
        ax.axhline(1e3 * LOSS_M, color="k", lw=0.8, ls=":", label="10 mm gate")
        ax.set(xlabel="current speed [m/s]", yscale="log", title=f"gate tool error, {title}")
    axes[0].set_ylabel("tool error at the gates [mm]")
    axes[1].legend(fontsize=7)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path, help="a make demo run folder")
    ap.add_argument("--device", choices=("cpu", "gpu"), default="cpu")
    ap.add_argument("--speeds", type=float, nargs="+", default=[0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7], help="[m/s]")
    ap.add_argument("--directions", type=int, default=48, help="horizontal directions, evenly spaced")
    ap.add_argument("--segments", type=int, default=None, help="the plan's first segments only (default: all)")
    ap.add_argument("--scenarios", type=int, default=None, help="repeat the grid (fresh noise draws) up to this many")
    ap.add_argument("--gust", type=float, default=0.0, help="gusts' standard deviation about the mean current [m/s]")
    ap.add_argument("--gust-interval", type=float, default=2.0, help="[s] between the gusts' knots")
    ap.add_argument("--controls", nargs="+", choices=[c for _, c in VARIANTS], default=[c for _, c in VARIANTS],
                    help="the variants to run (default: all three)")
    ap.add_argument("--arm", default="bravo7")
    ap.add_argument("--out", type=Path, default=None, help="result file (default: benchmarks/results/hover_robustness_"
                                                             "cpu.json, or _<gpu>.json)")
    ap.add_argument("--plot", type=Path, default=None)
    args = ap.parse_args()
    if args.device == "gpu" and jax.devices()[0].platform != "gpu":
        raise SystemExit(f"--device gpu: JAX sees no GPU, only {jax.devices()}")
    t0 = time.perf_counter()
    full = planfile.load_plan(args.run / "schedule" / "plan.json")
    plan = Plan(full.joint_names, full.segments[: args.segments]) if args.segments else full
    best = json.loads((args.run / "docking" / "best_pose.json").read_text())["pose"]
    pose = [best["x"], best["y"], best["z"], best["psi"]]
    seconds = hover.plan_targets(plan, 0.5, 1.0)[2]
    chosen = [i for i, (_, c) in enumerate(VARIANTS) if c in args.controls]
    grid = len(chosen) * 2 * len(args.speeds) * args.directions
    repeats = 1 if args.scenarios is None else -(-args.scenarios // grid)
    v, noisy, s, r, currents, times = _grid(chosen, args.speeds, args.directions, repeats, args.scenarios, args.gust,
                                            args.gust_interval, seconds + 1.0)
    controls = [VARIANTS[i][1] for i in v]
    res = hover.batch_controlled(load_arm(args.arm), plan, [pose], currents, current_times=times, controls=controls,
                                 noisy=noisy, navigation=hover.NavigationSettings())
    variants = []
    for i in chosen:
        name, control = VARIANTS[i]
        for nz in (False, True):
            rows = _per_speed(res, (v == i) & (noisy == nz), args.speeds, s)
            lost = [row["speed_m_s"] for row in rows if row["worst_gate_tool_error_m"] > LOSS_M]
            variants.append({"name": name + (", navigation noise" if nz else ""), "control": control,
                             "navigation_noise": nz, "first_speed_losing_10mm_m_s": lost[0] if lost else None,
                             "per_speed": rows})
    device = jax.devices()[0]
    full_size = args.directions == 48 and args.segments is None and len(chosen) == len(VARIANTS)
    result = {
        "benchmark": "hover_robustness",
        "command": " ".join(["python benchmarks/hover_robustness.py", *sys.argv[1:]]),
        "device": device.device_kind, "platform": device.platform, "jax": jax.__version__,
        "xla_flags": os.environ.get("XLA_FLAGS", ""), "dtype": str(jax.numpy.zeros(()).dtype),
        "reduction": None if full_size else (
            f"reduced from the full size (48 directions, the whole plan of {len(full.segments)} segments, the three "
            f"controllers): {args.directions} directions, "
            + (f"the plan's first {len(plan.segments)} segments" if args.segments else "the whole plan")
            + f", controllers {', '.join(VARIANTS[i][1] for i in chosen)}"),
        "pose": pose, "segments": len(plan.segments), "gates": int(res.gate_times.size), "simulated_s": seconds,
        "navigation": dataclasses.asdict(hover.NavigationSettings()),
        "gust_m_s": args.gust, "gust_interval_s": args.gust_interval if args.gust else None,
        "speeds_m_s": args.speeds, "directions": args.directions, "repetitions": repeats,
        "scenarios": int(len(v)), "tool_tolerance_m": res.tool_tolerance_m,
        "tool_tolerance_deg": float(np.degrees(res.tool_tolerance_rad)),
        "compile_s": res.compile_s, "run_s": res.run_s, "env_steps": res.env_steps,
        "env_steps_per_s": res.env_steps / res.run_s, "wall_s": time.perf_counter() - t0, "variants": variants}
    model = re.search(r"[a-z]\d{2,4}", device.device_kind.lower())  # "NVIDIA H100 80GB HBM3" → h100
    tag = "cpu" if device.platform == "cpu" else model.group(0) if model else "gpu"
    out = args.out or ROOT / "benchmarks" / "results" / f"hover_robustness_{tag}.json"
    write_json(out, result)
    if args.plot:
        plot(result, args.plot)
    print(json.dumps({k: result[k] for k in ("scenarios", "compile_s", "run_s", "env_steps_per_s")}))


if __name__ == "__main__":
    main()
