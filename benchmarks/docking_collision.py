"""Docking's collision test: the planner's world in JAX (spheres against boxes and polytopes,
self-collision, per-target pairs) against the link capsules it replaced, on the same batch in
one process; optionally MJX collision of the planner's MuJoCo scene; and the agreement of the
JAX test with the planner's sphere checker and with MuJoCo on random configurations at docked
vehicle poses. Prints one JSON object.

  JAX_PLATFORMS=cpu python benchmarks/docking_collision.py --mjx > benchmarks/results/docking_collision_demo_cpu.json
  JAX_PLATFORMS=cpu python benchmarks/docking_collision.py --arm panda > benchmarks/results/docking_collision_panda_cpu.json

``--arm`` is a shipped arm card or an arm of ``examples/arms.yaml`` (as ``tests/pipeline``
runs it: no start configuration); ``--mjx`` adds MJX (compiles for minutes on a CPU).

The batch is what one evaluation call of the demo's docking fitness tests: ``--poses`` vehicle
poses (the GA's evaluation chunk, 64) × the demo's 16 tool poses × 8 IK seeds, the
configurations drawn uniformly in the joint limits. Both tests get the same body frames (the
FK is not timed) and are each one ``jax.jit`` call, compiled ahead (``lower().compile()``);
the time is the best of ``--repeat`` runs. The capsule test is the former one (capsules of
the link radius between joint origins against the vehicle's and the tables' boxes, 40
golden-section steps per segment–box distance, no self-collision, no margin); the sphere test
answers the planner's question (every pair it tests, its margin). The full fitness evaluation
of the same poses is timed too, for scale.

Agreement (``--agree`` configurations, uniform in the joint limits, spread over the ``--pose``
vehicle poses and every target, as ``tests/plan/test_plan_world.py`` draws them): a
configuration is free for the sphere checker or MuJoCo when it is free in each context of its
target; counted are the configurations on which the JAX test agrees with each, and those where
it reports free and the other a collision (the unsafe side, which must be none).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.metadata
import io
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import yaml
from hydra import compose, initialize_config_dir

from uvms_jax import evo, kin
from uvms_jax import plan as planning
from uvms_jax.evo._collide import capsules_hit_boxes, link_points

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "experiments"))
from pipeline import settings_of  # noqa: E402  (the pipeline's own reading of its config)
from uvms_jax.files import json_text  # noqa: E402
from uvms_jax.plan import docked_scene  # noqa: E402

# Vehicle poses [x, y, z, ψ] of the agreement: the demo's docked pose and one over the other tables
# (those of tests/plan/test_plan_world.py), and for other arms the centre of the tiny preset's
# pose box (configs/experiment/tiny.yaml) instead of the first.
BRAVO7_POSES = [[-0.262, 0.300, 1.205, -0.873], [0.15, -0.35, 1.0, 2.2]]
OTHER_POSES = [[0.0, 0.4, 1.2, -1.575], [0.15, -0.35, 1.0, 2.2]]
AGREE_CHUNK = 512  # configurations per call of the agreement's JAX test


def _arm_overrides(arm: str, folder: Path) -> list[str]:
    """Pipeline overrides for ``arm``: a shipped card as it is, an example-robot-data arm as a
    card written to ``folder`` (its description located in the installed package)."""
    arms = yaml.safe_load((ROOT / "examples" / "arms.yaml").read_text())
    if arm not in arms["arms"]:
        return [f"scenario.arm.card={arm}"]
    robots = importlib.metadata.distribution("example-robot-data").locate_file(
        "cmeel.prefix/share/example-robot-data/robots")
    card = dict(arms["arms"][arm], gripper=arms["jaws"])
    card["description"] = str(Path(robots) / card["description"])
    path = folder / f"{arm}.yaml"
    path.write_text(yaml.safe_dump(card))
    return [f"scenario.arm.card={path}", "scenario.start_q=null"]


def agreement(settings, problem, robot, poses: np.ndarray, n: int, seed: int) -> dict:
    """The JAX test against the planner's sphere checker and MuJoCo on ``n`` configurations."""
    n_rows = problem.n_groups
    per = n // (len(poses) * n_rows)
    Q = np.random.default_rng(seed).uniform(robot.lower, robot.upper, (len(poses), n_rows, per, robot.n_joints))
    T_world_base = np.stack([docked_scene(settings.scenario, problem, p)[1] for p in poses])
    dtype = problem.pose_low.dtype
    collides = jax.jit(lambda q: evo.world_collides(problem.world, jnp.arange(n_rows), jnp.asarray(T_world_base, dtype),
                                                    kin.kinematics(problem.chain, q).T_base_joint))
    # In chunks of configurations per pose and target: a mesh arm's sphere pairs take megabytes each.
    chunk = max(1, AGREE_CHUNK // (len(poses) * n_rows))
    jax_free = ~np.concatenate([np.asarray(collides(jnp.asarray(Q[:, :, j:j + chunk], dtype)))
                                for j in range(0, per, chunk)], axis=2)
    spheres_free, mujoco_free = np.zeros_like(jax_free), np.zeros_like(jax_free)
    for i, pose in enumerate(poses):
        scene = planning.build_scene(robot, docked_scene(settings.scenario, problem, pose)[2])
        reference = planning.CollisionChecker(scene, settings.plan.margin)
        spheres = planning.SphereChecker(reference)
        for r, node in enumerate(sorted(scene.objects) + sorted(scene.bases)):
            contexts = [planning.node_contexts(scene, node)[step] for step in ("down", "up")]
            spheres_free[i, r] = np.logical_and.reduce([spheres.spheres_free(Q[i, r], c) for c in contexts])
            mujoco_free[i, r] = np.logical_and.reduce([reference.is_valid_batch(Q[i, r], c) for c in contexts])
    return {"configurations": int(jax_free.size), "poses": poses.tolist(), "seed": seed,
            "jax_free": float(jax_free.mean()), "spheres_free": float(spheres_free.mean()),
            "mujoco_free": float(mujoco_free.mean()),
            "agree_spheres": float(np.mean(jax_free == spheres_free)),
            "agree_mujoco": float(np.mean(jax_free == mujoco_free)),
            "jax_collision_spheres_free": int(np.sum(~jax_free & spheres_free)),
            "jax_collision_mujoco_free": int(np.sum(~jax_free & mujoco_free)),
            "jax_free_spheres_collision": int(np.sum(jax_free & ~spheres_free)),
            "jax_free_mujoco_collision": int(np.sum(jax_free & ~mujoco_free))}


def _best(fn, *args, repeat: int) -> float:
    jax.block_until_ready(fn(*args))
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        times.append(time.perf_counter() - t0)
    return min(times)


def _compiled(fn, *args):
    t0 = time.perf_counter()
    out = jax.jit(fn).lower(*args).compile()
    return out, time.perf_counter() - t0


def capsule_test(problem: evo.ArmDockingProblem, link_radius, T_world_vehicle, T_world_base, K_joint, K_tool):
    """The former test of ``evo.arm_solutions``: link capsules against the vehicle's boxes
    (the first, fixed on the vehicle, skipped) and the scene's boxes, ``(..., k, S)``."""
    p = problem
    points = link_points(T_world_base[..., None, None, :, :], K_joint, K_tool)
    n_caps = points.shape[-2] - 1
    T_vb = kin.matmul(T_world_vehicle[..., None, :, :], p.T_vehicle_box)[..., None, None, None, :, :, :]
    skip = jnp.zeros((n_caps, p.vehicle_half.shape[0]), bool).at[0].set(True)
    hit = capsules_hit_boxes(points, link_radius, T_vb, p.vehicle_half, skip)
    return hit | capsules_hit_boxes(points, link_radius, p.T_world_box, p.scene_half,
                                    jnp.zeros((n_caps, p.scene_half.shape[0]), bool))


def sphere_test(problem: evo.ArmDockingProblem, T_world_base, K_joint):
    return evo.world_collides(problem.world, problem.group, T_world_base, K_joint)


def mjx_time(m, Q: np.ndarray, repeat: int) -> dict:
    """MJX kinematics + collision of the planner's scene (its base fixed; ``m``: the scene's
    ``mujoco.MjModel``) over ``Q (B, n)``."""
    with contextlib.redirect_stdout(io.StringIO()):  # "Failed to import warp"
        from mujoco import mjx
    mx = mjx.put_model(m)
    dx = mjx.make_data(mx)

    def contacts(q):
        d = mjx.kinematics(mx, dx.replace(qpos=q))
        d = mjx.collision(mx, d)
        return jnp.any(d._impl.contact.dist < 0.0)

    fn, compile_s = _compiled(jax.vmap(contacts), jnp.asarray(Q, jnp.float32))
    return {"configurations": len(Q), "compile_s": compile_s,
            "run_s": _best(fn, jnp.asarray(Q, jnp.float32), repeat=repeat),
            "note": "one vehicle pose (its base fixed): the docked scene as the planner builds it (convex meshes), contacts at 0 margin"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--poses", type=int, default=64, help="vehicle poses per call (the demo's GA chunk)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--mjx", action="store_true", help="also MJX collision of the planner's scene")
    ap.add_argument("--arm", default="bravo7", help="a shipped arm card or an arm of examples/arms.yaml")
    ap.add_argument("--agree", type=int, default=10_000, help="configurations of the agreement (0: none)")
    ap.add_argument("--pose", type=float, nargs=4, action="append", metavar=("X", "Y", "Z", "PSI"),
                    help="a docked vehicle pose of the agreement (repeat; default: two per arm, see the source)")
    args = ap.parse_args()

    with tempfile.TemporaryDirectory() as folder, initialize_config_dir(config_dir=str(ROOT / "configs"),
                                                                        version_base="1.3"):
        settings = settings_of(compose("pipeline", overrides=_arm_overrides(args.arm, Path(folder))))
        robot = planning.scenario_robot(settings.scenario)
    t0 = time.perf_counter()
    task = planning.docking_task(planning.build_scene(robot, settings.scenario), vehicle=settings.docking.scene,
                                 margin=settings.plan.margin)
    world_s = time.perf_counter() - t0
    problem = evo.docking_problem(settings.docking.scene, settings.docking.dtype, task, robot)
    k, S, n = problem.group.shape[0], problem.seeds.shape[0], problem.chain.n_joints

    rng = np.random.default_rng(args.seed)
    low, high = np.asarray(problem.pose_low), np.asarray(problem.pose_high)
    poses = jnp.asarray(rng.uniform(low, high, (args.poses, 4)), jnp.float32)
    q = jnp.asarray(rng.uniform(robot.lower, robot.upper, (args.poses, k, S, n)), jnp.float32)
    T_world_vehicle, T_world_base, _ = evo.arm_tool_poses(problem, poses)
    K = kin.kinematics(problem.chain, q)
    radius = jnp.asarray(robot.link_radius, jnp.float32)

    caps, caps_compile = _compiled(capsule_test, problem, radius, T_world_vehicle, T_world_base, K.T_base_joint,
                                   K.T_base_tool)
    sph, sph_compile = _compiled(sphere_test, problem, T_world_base, K.T_base_joint)
    caps_s = _best(caps, problem, radius, T_world_vehicle, T_world_base, K.T_base_joint, K.T_base_tool,
                   repeat=args.repeat)
    sph_s = _best(sph, problem, T_world_base, K.T_base_joint, repeat=args.repeat)
    fit, fit_compile = _compiled(evo.evaluate_arm_traced, problem, poses)
    fit_s = _best(fit, problem, poses, repeat=max(1, args.repeat // 2))
    hit_caps = np.asarray(caps(problem, radius, T_world_vehicle, T_world_base, K.T_base_joint, K.T_base_tool))
    hit_sph = np.asarray(sph(problem, T_world_base, K.T_base_joint))

    rows = problem.world.rows
    B = args.poses * k * S
    out = {
        "benchmark": "docking_collision",
        "arm": args.arm,
        "command": " ".join(["python benchmarks/docking_collision.py", *sys.argv[1:]]),
        "device": {"platform": jax.devices()[0].platform, "device_kind": jax.devices()[0].device_kind,
                   "count": jax.device_count()},
        "host": {"machine": platform.machine(), "cpus": os.cpu_count(), "python": platform.python_version(),
                 "load_average": os.getloadavg()},
        "versions": {"jax": jax.__version__},
        "xla_flags": os.environ.get("XLA_FLAGS", ""),
        "batch": {"poses": args.poses, "tool_poses": k, "seeds": S, "configurations": B},
        "world": {"build_s": world_s, "rows": int(rows.radius.shape[0]), "spheres_per_row": int(rows.radius.shape[1]),
                  "boxes": int(problem.world.box_half.shape[0]), "polytopes": int(problem.world.faces.shape[0]),
                  "faces_per_polytope": int(problem.world.faces.shape[1]), "sphere_pairs_per_row": int(np.max(np.sum(rows.pair_on, axis=(1, 2)))),
                  "sphere_pair_block": list(rows.pair_on.shape[1:]),
                  "capsule_pairs_per_row": int(rows.cap_reach.shape[1]), "margin_m": float(problem.world.margin)},
        "capsules": {"compile_s": caps_compile, "run_s": caps_s, "configurations_per_s": B / caps_s,
                     "collision_share": float(hit_caps.mean())},
        "spheres": {"compile_s": sph_compile, "run_s": sph_s, "configurations_per_s": B / sph_s,
                    "collision_share": float(hit_sph.mean())},
        "spheres_over_capsules_time": sph_s / caps_s,
        "fitness": {"compile_s": fit_compile, "run_s": fit_s, "collision_share_of_time": sph_s / fit_s},
    }
    if args.agree:
        poses_agree = np.asarray(args.pose or (BRAVO7_POSES if args.arm == "bravo7" else OTHER_POSES))
        out["agreement"] = agreement(settings, problem, robot, poses_agree, args.agree, args.seed + 1)
    if args.mjx:
        _, _, spec = docked_scene(settings.scenario, problem, np.asarray(poses[0]))
        out["mjx"] = mjx_time(planning.build_scene(robot, spec).model, np.asarray(q[0].reshape(-1, n)), args.repeat)
        out["mjx"]["spheres_same_count_s"] = sph_s * out["mjx"]["configurations"] / B
    print(json_text(out))


if __name__ == "__main__":
    main()
