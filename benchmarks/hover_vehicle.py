"""The hovering vehicle's derived figures that docs/hover.md quotes, computed from its model;
prints one JSON object.

- the largest pure efforts of the thruster layout (a linear programme: the largest ``t`` with
  ``B u = t e_k`` and every thrust within its limit), in surge, sway, heave and yaw;
- the steady speeds those efforts reach against the hull's own drag (MuJoCo's inertia-box
  fluid model of the hull body: viscous plus quadratic term);
- the hydrostatic restoring moment per radian of roll or pitch of the hull (its buoyancy at
  ``cob`` above the centre of mass);
- the closed-loop poles of station keeping on the rigid vehicle with the arm held still: the
  roots of ``m s³ + kd s² + kp s + ki`` per translation and in yaw, with the vehicle's mass and
  yaw inertia from MuJoCo's joint-space inertia, the arm held at the middle of its joint ranges,
  and no drag.

    python benchmarks/hover_vehicle.py > benchmarks/results/hover_vehicle.json

Usage: python benchmarks/hover_vehicle.py [--arm bravo7]
"""

from __future__ import annotations

import argparse
import math
import sys

import mujoco
import numpy as np
from scipy.optimize import linprog

from uvms_jax.files import json_text
from uvms_jax.hover import ControllerSettings, VehicleSettings, fluid_bodies, hover_model, thrust_layout
from uvms_jax.robot import load_arm

#: Pure efforts reported: the row of the wrench (force xyz, moment xyz) and its name.
AXES = {"surge": 0, "sway": 1, "heave": 2, "yaw": 5}


def largest_effort(B: np.ndarray, limits: np.ndarray, axis: int) -> float:
    """The largest ``t`` such that thrusts ``u`` within ``±limits`` give the wrench ``t e_axis``."""
    n = B.shape[1]
    target = np.zeros((6, 1))
    target[axis] = 1.0
    # Variables (u, t): maximise t subject to B u − t e_axis = 0.
    res = linprog(np.r_[np.zeros(n), -1.0], A_eq=np.hstack([B, -target]), b_eq=np.zeros(6),
                  bounds=[(-lim, lim) for lim in limits] + [(0, None)])
    if not res.success:
        raise SystemExit(f"the effort LP along axis {axis} failed: {res.message}")
    return float(res.x[-1])


def steady_speed(force: float, edges: np.ndarray, axis: int, density: float, viscosity: float) -> float:
    """The speed [m/s] at which the inertia-box drag of a body with box ``edges`` along ``axis``
    equals ``force``: ``3π d β v + ½ ρ A v² = F`` (d the boxes' mean edge, A the face across ``axis``)."""
    d, area = edges.mean(), np.prod(np.delete(edges, axis))
    a, b = 0.5 * density * area, 3.0 * math.pi * d * viscosity
    return float((-b + math.sqrt(b * b + 4.0 * a * force)) / (2.0 * a))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arm", default="bravo7", help="arm card the vehicle carries (robot.load_arm)")
    args = ap.parse_args()
    vehicle, controller = VehicleSettings(), ControllerSettings()
    B, _, limits = thrust_layout(vehicle)
    efforts = {name: largest_effort(B, limits, axis) for name, axis in AXES.items()}

    hull = hover_model(None, vehicle)
    _, boxes = fluid_bodies(hull)
    speeds = {name: steady_speed(efforts[name], boxes[0], axis, vehicle.water_density, vehicle.viscosity)
              for name, axis in AXES.items() if axis < 3}

    arm = load_arm(args.arm)
    model = hover_model(arm, vehicle)
    data = mujoco.MjData(model)
    q_arm = (arm.lower + arm.upper) / 2
    data.qpos[7:7 + q_arm.size] = q_arm  # after the vehicle's free joint (7 coordinates)
    mujoco.mj_forward(model, data)
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    # The free joint's first six DOFs: translation in the world, rotation about the body's axes.
    mass, yaw_inertia = float(M[0, 0]), float(M[5, 5])
    poles = {}
    for name, inertia, i in (("translation", mass, 0), ("yaw", yaw_inertia, 3)):
        roots = np.roots([inertia, controller.kd[i], controller.kp[i], controller.ki[i]])
        poles[name] = [[float(r.real), float(r.imag)] for r in sorted(roots, key=lambda r: (r.real, r.imag))]
    print(json_text({
        "benchmark": "hover_vehicle", "command": " ".join(["python benchmarks/hover_vehicle.py", *sys.argv[1:]]),
        "arm": args.arm, "arm_joints_rad": q_arm.tolist(), "thrusters": len(limits), "thrust_limit_n": limits.tolist(),
        "thrust_matrix_rank": int(np.linalg.matrix_rank(B)),
        "largest_effort": efforts, "hull_drag_box_m": boxes[0].tolist(), "steady_speed_m_s": speeds,
        "restoring_moment_nm_per_rad": vehicle.water_density * vehicle.gravity * vehicle.volume * vehicle.cob[2],
        "mass_kg": mass, "yaw_inertia_kg_m2": yaw_inertia,
        "gains": {"kp": controller.kp, "kd": controller.kd, "ki": controller.ki}, "poles_rad_s": poles,
    }))


if __name__ == "__main__":
    main()
