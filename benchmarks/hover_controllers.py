"""The tool's error on the hovering vehicle: the station keeping's PID with the arm replaying its
waypoints (``pid``; ``feed_forward``: with the model-based feed-forward on the thrusters) against
the whole-body controller (``whole_body``: the tool's pose first, station keeping in its null
space, feed-forward on the thrusters), on the CPU (:func:`uvms_jax.hover.run_plan_hovering`,
MuJoCo's C engine), for a demo run's scheduled plan at its docked pose in a few currents. Prints
one JSON object.

    JAX_PLATFORMS=cpu .venv/bin/python benchmarks/hover_controllers.py outputs/<date>/<time> \\
        > benchmarks/results/hover_controllers_cpu.json

The run folder is a `make demo` run's (its `schedule/plan.json` and `docking/best_pose.json`).
``--controls whole_body_bpl`` runs the whole-body controller in the BPL executor's loop on the
simulated arm instead (:func:`uvms_jax.hover.execute_plan_hovering`, gates judged on the tool
after each move). ``--navigation`` gives the whole-body controller the navigation estimate's defaults (30 Hz,
50 ms, 5 mm, 0.2°, fused with dead reckoning at ``--fix-gain``); ``--gust`` adds gusts of that
standard deviation [m/s] every 2 s.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

from uvms_jax import hover, planfile
from uvms_jax.files import json_text
from uvms_jax.robot import load_arm

BPL = "whole_body_bpl"  # the whole-body controller in the BPL executor's loop (execute_plan_hovering)


def _run(arm, plan, pose, current, control: str, navigation) -> dict:
    t0 = time.perf_counter()
    if control == BPL:  # the BPL executor on the simulated arm, the whole-body controller between
        r = hover.execute_plan_hovering(arm, plan, pose, current=current, control="whole_body", navigation=navigation)
    else:
        r = hover.run_plan_hovering(arm, plan, pose, current=current, control=control,
                                    navigation=navigation if control == "whole_body" else None)
    s = r.summary()
    return {"control": control, "status": s["status"], "reason": s["reason"], "gates": s["gates"],
            "gates_reached": s["gates_reached"], "max_gate_tool_error_m": s["max_gate_tool_error_m"],
            "mean_gate_tool_error_m": float(np.mean(r.gate_tool_error)),
            "gates_tool_within_tolerance": s["gates_tool_within_tolerance"],
            "max_tool_error_m": s["max_tool_error_m"], "p95_tool_error_m": float(np.percentile(r.tool_error, 95)),
            "max_gate_tool_angle_deg": None if r.gate_tool_angle is None
            else float(np.degrees(r.gate_tool_angle.max())),
            "max_drift_m": s["max_drift_m"], "peak_thrust_N": s["peak_thrust_N"],
            "thrust_limited_periods": s["thrust_limited_periods"], "joint_limited_periods": s["joint_limited_periods"],
            "periods": len(r.log.time) - 1, "wall_s": time.perf_counter() - t0}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path, help="a make demo run folder")
    ap.add_argument("--speeds", type=float, nargs="+", default=[0.0, 0.3, 0.5], help="[m/s]")
    ap.add_argument("--directions", type=float, nargs="+", default=[0.0, 120.0, 240.0], help="[deg from the world's x]")
    ap.add_argument("--controls", nargs="+", default=["pid", "whole_body"],
                    choices=["pid", "feed_forward", "whole_body", BPL])
    ap.add_argument("--navigation", action="store_true", help="the whole-body controller sees a navigation estimate")
    ap.add_argument("--fix-gain", type=float, default=None, help="the navigation's fix_gain (default: its setting's)")
    ap.add_argument("--gust", type=float, default=0.0, help="gusts' standard deviation [m/s]")
    ap.add_argument("--arm", default="bravo7")
    args = ap.parse_args()
    plan = planfile.load_plan(args.run / "schedule" / "plan.json")
    best = json.loads((args.run / "docking" / "best_pose.json").read_text())["pose"]
    pose = [best["x"], best["y"], best["z"], best["psi"]]
    arm = load_arm(args.arm)
    duration = hover.plan_targets(plan, 0.5, 1.0)[2]
    navigation = None
    if args.navigation:
        navigation = hover.NavigationSettings(**({} if args.fix_gain is None else {"fix_gain": args.fix_gain}))
    rows = []
    for speed in args.speeds:
        for angle in args.directions if speed > 0 else [0.0]:
            a = np.radians(angle)
            mean = (speed * np.cos(a), speed * np.sin(a), 0.0)
            current = hover.CurrentSettings.gusty(mean, args.gust, 2.0, duration + 1.0) if args.gust \
                else hover.CurrentSettings(velocity=mean)
            for control in args.controls:
                rows.append({"speed_m_s": speed, "direction_deg": angle,
                             **_run(arm, plan, pose, current, control, navigation)})
                print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    worst = {c: {str(s): max(r["max_tool_error_m"] for r in rows if r["control"] == c and r["speed_m_s"] == s)
                 for s in args.speeds} for c in args.controls}
    worst_gate = {c: {str(s): max(r["max_gate_tool_error_m"] for r in rows if r["control"] == c and r["speed_m_s"] == s)
                      for s in args.speeds} for c in args.controls}
    print(json_text({"command": " ".join(["python benchmarks/hover_controllers.py", *sys.argv[1:]]),
                      "machine": platform.processor() or platform.machine(), "pose": pose, "simulated_s": duration,
                      "navigation": None if navigation is None else dataclasses.asdict(navigation),
                      "gust_m_s": args.gust, "worst_tool_error_m": worst, "worst_gate_tool_error_m": worst_gate,
                      "runs": rows}))


if __name__ == "__main__":
    main()
