"""The thrust a current asks for against what the thrusters give: a demo run's scheduled plan at
its docked pose, the hull held still there, in a current of one speed from evenly spread
horizontal directions. Per direction: the largest over the plan of the feed-forward wrench's
thrust as a share of the limits (:meth:`uvms_jax.hover.WholeBody.feed_forward`), allocated by
the scaled pseudo-inverse the controller uses and by the best allocation (a linear program over
the thrusts, min max_i |u_i| / u_max,i subject to B u = w); a share above 1 is a wrench no
allocation can give. Writes the result file.

    python benchmarks/hover_thrust_margin.py RUN --speed 0.5 --directions 48   # benchmarks/results/hover_thrust_margin.json

RUN is a ``make demo`` run folder (its ``schedule/plan.json`` and ``docking/best_pose.json``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import linprog

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from uvms_jax import hover, planfile  # noqa: E402
from uvms_jax.files import write_json  # noqa: E402
from uvms_jax.robot import load_arm  # noqa: E402


def best_share(B: np.ndarray, limits: np.ndarray, wrench: np.ndarray) -> float:
    """``min_u max_i |u_i| / limits_i`` subject to ``B u = wrench``, by a linear program."""
    n = B.shape[1]
    a_ub = np.block([[np.eye(n), -limits[:, None]], [-np.eye(n), -limits[:, None]]])
    lp = linprog(np.r_[np.zeros(n), 1.0], A_ub=a_ub, b_ub=np.zeros(2 * n), A_eq=np.c_[B, np.zeros(6)], b_eq=wrench,
                 bounds=[(None, None)] * n + [(0, None)])
    if not lp.success:
        raise RuntimeError(f"the allocation's linear program failed: {lp.message}")
    return float(lp.x[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path, help="a make demo run folder")
    ap.add_argument("--speed", type=float, default=0.5, help="[m/s]")
    ap.add_argument("--directions", type=int, default=48)
    ap.add_argument("--every", type=int, default=5, help="every this many control periods of the plan")
    ap.add_argument("--arm", default="bravo7")
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "hover_thrust_margin.json")
    args = ap.parse_args()
    plan = planfile.load_plan(args.run / "schedule" / "plan.json")
    best = json.loads((args.run / "docking" / "best_pose.json").read_text())["pose"]
    pose = np.array([best["x"], best["y"], best["z"], best["psi"]])
    arm, controller = load_arm(args.arm), hover.ControllerSettings()
    targets, _, duration = hover.plan_targets(plan, 0.5, 1.0)
    q = np.array([targets(t) for t in controller.period * np.arange(round(duration / controller.period) + 2)])
    vehicle = hover.trimmed(hover.VehicleSettings(), arm, q[0])
    wb = hover.WholeBody(arm, vehicle, controller, hover.WholeBodySettings(), pose, q, hover.hover_model(arm, vehicle))
    B, B_pinv, limits = hover.thrust_layout(vehicle)
    R, rows = wb.T_dock[:3, :3], np.arange(0, len(q), args.every)
    per_direction = []
    for d in range(args.directions):
        angle = 2 * np.pi * d / args.directions
        current = args.speed * np.array([np.cos(angle), np.sin(angle), 0.0])
        wrench = np.array([wb.feed_forward(k, R, current, np.zeros(3)) for k in rows])
        share = np.max(np.abs(wrench @ B_pinv.T) / limits, axis=1)
        worst = int(np.argmax(share))
        per_direction.append({"direction_deg": float(np.degrees(angle)), "pinv_share_max": float(share.max()),
                              "pinv_share_above_1": float(np.mean(share > 1.0)),
                              "best_share_at_that_period": best_share(B, limits, wrench[worst]),
                              "period": int(rows[worst]), "wrench": wrench[worst].round(2).tolist()})
    result = {"benchmark": "hover_thrust_margin", "command": " ".join(["python benchmarks/hover_thrust_margin.py",
                                                                        *sys.argv[1:]]),
              "pose": pose.tolist(), "speed_m_s": args.speed, "directions": args.directions, "every": args.every,
              "thrust_limits_N": limits.tolist(), "per_direction": per_direction,
              "directions_beyond_thrusters_deg": [p["direction_deg"] for p in per_direction
                                                  if p["best_share_at_that_period"] > 1.0]}
    write_json(args.out, result)
    print(json.dumps({k: result[k] for k in ("speed_m_s", "directions_beyond_thrusters_deg")}))


if __name__ == "__main__":
    main()
