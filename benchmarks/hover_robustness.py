"""How good is a docking pose if the vehicle only hovers there, in this current? A demo run's
scheduled plan replayed at its docked pose, and the same tool motion from the docking stage's
other candidate poses, in a grid of currents (speed × direction), all in one MJX batch
(:func:`uvms_jax.hover.batch_candidates`); per pose, the share of gates reached and the worst
tool error against the current's speed. Prints one JSON object and writes the plot.

    JAX_PLATFORMS=cpu .venv/bin/python benchmarks/hover_robustness.py outputs/<date>/<time> \\
        --plot docs/img/hover_robustness.png > benchmarks/results/hover_robustness_cpu.json

The run folder is a `make demo` run's (its `schedule/plan.json`, and `docking/best_pose.json`
with the chosen pose and the distinct candidates of the docking search).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

_CPU_FLAG = "--xla_cpu_use_fusion_emitters"  # MJX on jax 0.10's CPU backend: ~450× faster without them
if os.environ.get("JAX_PLATFORMS") == "cpu" and _CPU_FLAG not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = " ".join(filter(None, [os.environ.get("XLA_FLAGS"), f"{_CPU_FLAG}=false"]))

import jax  # noqa: E402
import numpy as np  # noqa: E402

from uvms_jax import hover, planfile  # noqa: E402
from uvms_jax.robot import load_arm  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path, help="a make demo run folder")
    ap.add_argument("--speeds", type=float, nargs="+", default=[0.0, 0.1, 0.2, 0.3, 0.4, 0.5], help="[m/s]")
    ap.add_argument("--directions", type=float, nargs="+", default=[0, 45, 90, 135, 180, 225, 270, 315],
                    help="[deg from the world's x]")
    ap.add_argument("--arm", default="bravo7")
    ap.add_argument("--candidates", type=int, default=4, help="poses: the docked one and the best other candidates")
    ap.add_argument("--plot", type=Path, default=None)
    args = ap.parse_args()
    plan = planfile.load_plan(args.run / "schedule" / "plan.json")
    best = json.loads((args.run / "docking" / "best_pose.json").read_text())
    as_pose = lambda p: [p["x"], p["y"], p["z"], p["psi"]]  # noqa: E731
    entries = [(as_pose(best["pose"]), best["fitness"])] + [
        (as_pose(c["pose"]), c["fitness"]) for c in best["candidates"]
        if not np.allclose(as_pose(c["pose"]), as_pose(best["pose"]))]
    poses = np.array([e[0] for e in entries[: args.candidates]])
    currents = hover.currents_grid(args.speeds, args.directions)
    t0 = time.perf_counter()
    res, reached = hover.batch_candidates(load_arm(args.arm), plan, poses, currents)
    kept = reached == 1.0
    wall = time.perf_counter() - t0
    speed = np.round(res.current_speed, 9)
    levels = np.unique(speed)
    per_pose = []
    for k, i in enumerate(np.flatnonzero(kept)):
        per_pose.append({"pose": poses[i].tolist(), "docked": bool(i == 0), "fitness": float(entries[i][1]),
                         "per_speed": [{"speed_m_s": float(s), "gate_share_worst": float(res.gate_share[k, speed == s].min()),
                                        "gate_share_mean": float(res.gate_share[k, speed == s].mean()),
                                        "max_tool_error_m": float(res.max_tool_error[k, speed == s].max()),
                                        "max_drift_m": float(res.max_drift[k, speed == s].max())} for s in levels]})
    if args.plot:
        labels = [("docked pose" if p["docked"] else f"candidate {k}") + f" ({', '.join(f'{v:.2f}' for v in p['pose'])}; "
                  f"fitness {p['fitness']:.3f})" for k, p in enumerate(per_pose)]
        hover.plot_robustness(res, args.plot, labels=labels)
    print(json.dumps({
        "command": " ".join(["python benchmarks/hover_robustness.py", *sys.argv[1:]]),
        "device": jax.devices()[0].device_kind, "platform": jax.devices()[0].platform, "jax": jax.__version__,
        "xla_flags": os.environ.get("XLA_FLAGS", ""), "currents": len(currents), "scenarios": res.gate_share.size,
        "left_out": [{"pose": p, "fitness": float(e[1]), "path_share_followed": float(r)}
                     for p, e, r in zip(poses.tolist(), entries, reached) if r < 1.0],
        "gates": int(res.gate_tool_error.shape[-1]), "simulated_s": hover.plan_targets(plan, 0.5, 1.0)[2],
        "compile_s": res.compile_s, "run_s": res.run_s, "wall_s": wall,
        "per_pose": per_pose}, indent=1))


if __name__ == "__main__":
    main()
