"""Your own arm: load it from its robot description, put it on a vehicle, score it, dock it.

    python examples/own_arm.py

A small GA (its time and output: README.md, ``benchmarks/own_arm.py``; ``python experiments/docking.py
docking/preset=bravo7`` is the full experiment with its grid reference). The arm here is the
Bravo 7's shipped description; point ``URDF`` and ``TIP`` at your own file.
"""

import jax
import numpy as np

from uvms_jax import evo, indices, kin, robot

URDF, TIP = str(robot.DESCRIPTIONS / "bravo7.urdf"), "tool"


def main() -> None:
    arm = robot.chain_from_urdf(URDF, tip_link=TIP)  # fixed joints folded into the geometry, limits kept
    mount = np.diag([1.0, -1.0, -1.0, 1.0])  # arm base under the hull's front, hanging down
    mount[:3, 3] = [0.35, 0.0, -0.2]
    rov = kin.uvms(arm, mount=mount, vehicle_dofs=("x", "y", "z", "yaw"))  # 4 vehicle DOFs + the arm

    q = np.random.default_rng(0).uniform(np.maximum(rov.lower, -1.0), np.minimum(rov.upper, 1.0),
                                         (100_000, rov.n_joints))
    w = indices.manipulability_of(rov, q)  # one fused call; any joint count and task space
    w_pos = indices.manipulability_of(arm, q[:, 4:], task="position")
    print(f"{rov.name}: {rov.n_joints} joints, median w {np.median(w):.3g} (6-D), "
          f"arm alone {np.median(w_pos):.3g} (position only)")

    # Dock beside a vertical panel: 3 × 3 tool poses on its face, numerical IK from 8 seeds.
    panel = evo.BoxSettings("panel", (0.05, 0.0, 0.0), (0.1, 1.6, 1.2))
    scene = evo.ArmSceneSettings(arm=URDF, arm_tip=TIP, link_radius=0.04, mount_xyz=(0.35, 0.0, -0.2),
                                 scene_boxes=(panel,), panel=evo.PanelSettings(), ik_seeds=8)
    problem = evo.arm_docking_problem(scene)
    codec, ga, params = evo.make_ga(evo.GASettings(population_size=40, max_generations=30,
                                                   bits=evo.FieldBits(9, 9, 9, 8), eval_chunk=None), problem)
    best = evo.run_ga(jax.random.key(0), problem, codec, ga, params)
    report = evo.arm_report(problem, best.best_x)
    x, y, z, psi = np.asarray(best.best_x)
    print(f"docked at x {x:.3f} m, y {y:.3f} m, z {z:.3f} m, ψ {np.degrees(psi):.1f}°: "
          f"M_a {float(report.terms.M_a):.4f}, {int(np.sum(report.valid))}/{report.valid.size} tool poses reached")


if __name__ == "__main__":
    main()
