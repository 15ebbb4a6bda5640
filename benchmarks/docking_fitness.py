"""The demo's docking fitness on a batch of vehicle poses: poses/s and XLA's flop count per
pose, with the DLS step's 6 × 6 solve written out (Cholesky, ``kin.spd_solve``, the library's)
beside the library's LU (``jnp.linalg.solve``), and on a GPU the library's GPU path
(``kernels``: the whole IK loop as one kernel, ``uvms_jax.kin._ik_gpu``, and the collision test
as another, ``uvms_jax.evo._world_gpu``) and the IK kernel with XLA's collision test (``ik
kernel``) beside both, in the same process; prints one JSON object.

    JAX_PLATFORMS=cpu python benchmarks/docking_fitness.py --batches 256 1024
    python benchmarks/docking_fitness.py --batches 16384 131072          # GPU

The fitness is the demo's (``make demo``'s docking stage: 16 tool poses, 8 IK seeds × 25 DLS
iterations each, collisions), on poses drawn uniformly in its pose box. Compilation is timed
apart; the best of ``--repeat`` calls is reported. ``dls_flops_per_pose`` and
``collision_flops_per_pose`` are XLA's cost analysis of one DLS iteration (times the pose's
solves) and of the collision test of one pose's configurations; with the device's peak they
bound the rate from above.
``stages`` times cumulative pieces of the fitness at the largest batch (:data:`STAGES`): where
the time goes.
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import sys
import time

import jax
import jax.numpy as jnp

from uvms_jax import indices, kin
from uvms_jax.evo import _arm, _world, _world_gpu
from uvms_jax.files import json_text
from uvms_jax.kin import _ik, _ik_gpu

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from docking_search import demo_problem, demo_settings  # noqa: E402  (the demo's problem, built as the pipeline does)


def _lu(A, b):
    return jnp.linalg.solve(A, b[..., None])[..., 0]


def _poses(problem, n: int):
    return jax.random.uniform(jax.random.key(0), (n, 4), jnp.float32, problem.pose_low, problem.pose_high)


def _timed(f, problem, poses, repeat: int):
    """``f(problem, poses)`` compiled, then called ``repeat + 1`` times (the first warms up):
    (compile [s], best call [s], its output)."""
    t0 = time.perf_counter()
    compiled = jax.jit(f).lower(problem, poses).compile()
    compile_s = time.perf_counter() - t0
    times = []
    for _ in range(repeat + 1):
        t0 = time.perf_counter()
        out = jax.block_until_ready(compiled(problem, poses))
        times.append(time.perf_counter() - t0)
    return compile_s, min(times[1:]), out


def measure(problem, n: int, repeat: int) -> dict:
    compile_s, best, f = _timed(lambda p, x: p.fitness(x), problem, _poses(problem, n), repeat)
    return {"batch": n, "compile_s": compile_s, "best_s": best, "poses_per_s": n / best,
            "fitness_sum": float(jnp.nansum(f))}


def _solutions(p, poses):
    _, T_world_base, T_base_tool = _arm.arm_tool_poses(p, poses)
    q = kin.dls_ik(p.chain, T_base_tool[..., None, :, :], p.seeds, p.iterations, p.damping, limits="wrap")
    return T_world_base, T_base_tool, q


def _with_fk(p, poses):
    _, T_base_tool, q = _solutions(p, poses)
    K = kin.kinematics(p.chain, q)
    return jnp.sum(kin.reaches(T_base_tool[..., None, :, :], K.T_base_tool)) + jnp.sum(K.T_base_joint[..., 3])


def _with_collision(p, poses):
    T_world_base, _, q = _solutions(p, poses)
    return jnp.sum(_arm.world_collides(p.world, p.group, T_world_base, kin.kinematics(p.chain, q).T_base_joint))


#: Cumulative pieces of the fitness (``evo.ArmDockingProblem.fitness``: IK, then forward
#: kinematics and the reach test, the collision test, w), each compiled alone and summed so
#: that XLA keeps all of it.
STAGES = {
    "ik, 1 iteration": (lambda p, x: jnp.sum(_solutions(p, x)[2]), 1),
    "ik": (lambda p, x: jnp.sum(_solutions(p, x)[2]), None),
    "ik + fk + reach test": (_with_fk, None),
    "ik + fk + collision test": (_with_collision, None),
    "ik + w": (lambda p, x: jnp.sum(indices.manipulability_of(p.chain, _solutions(p, x)[2])), None),
    "fitness": (lambda p, x: jnp.sum(p.fitness(x)), None),
}


def stage_seconds(problem, n: int, repeat: int) -> dict:
    """Best time [s] of each of :data:`STAGES` over ``n`` poses (the library's path)."""
    poses = _poses(problem, n)
    return {name: _timed(f, problem if iterations is None else problem.replace(iterations=iterations), poses, repeat)[1]
            for name, (f, iterations) in STAGES.items()}


def dls_iteration_flops(problem) -> float:
    """Flops of one DLS iteration (``kin.dls_step``) of one IK problem, XLA's count."""
    chain, T = problem.chain, problem.T_world_tool[0]
    q = jnp.zeros((chain.n_joints,), jnp.float32)
    cost = jax.jit(_ik.dls_step).lower(chain, T, q).compile().cost_analysis()
    return float((cost[0] if isinstance(cost, (list, tuple)) else cost)["flops"])


def collision_flops(problem) -> float:
    """Flops of the collision test (XLA's form) of one vehicle pose's configurations, XLA's count."""
    T_world_base, _, q = jax.jit(_solutions)(problem, _poses(problem, 1))
    frames = jax.jit(lambda q: kin.kinematics(problem.chain, q).T_base_joint)(q)
    kernel_applies, _world_gpu.applies = _world_gpu.applies, lambda T: False  # a kernel's cost is not XLA's to count
    try:
        xla = jax.jit(lambda p, T, F: _world.world_collides(p.world, p.group, T, F)).lower(problem, T_world_base, frames)
        cost = xla.compile().cost_analysis()
    finally:
        _world_gpu.applies = kernel_applies
    return float((cost[0] if isinstance(cost, (list, tuple)) else cost)["flops"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--batches", type=int, nargs="+", default=[256, 1024])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--variants", nargs="+", default=None,
                    help="variants to time (default: all: kernels, 'ik kernel' on a GPU; cholesky, lu)")
    args = ap.parse_args()
    _, _, problem = demo_problem(demo_settings([]))
    library = (_ik.spd_solve, _ik_gpu.applies, _world_gpu.applies)
    settings = demo_settings([]).docking.scene
    solves_per_pose = len(problem.T_world_tool) * settings.ik_seeds * settings.ik_iterations
    per_pose = dls_iteration_flops(problem) * solves_per_pose
    never = lambda x: False  # noqa: E731
    # name: (the DLS step's solve, whether the IK kernel and the collision kernel apply)
    variants = {"cholesky": (library[0], never, never), "lu": (_lu, never, never)}
    if jax.default_backend() == "gpu":
        variants = {"kernels": library, "ik kernel": (library[0], library[1], never), **variants}
    unknown = set(args.variants or ()) - set(variants)
    if unknown:
        ap.error(f"unknown variants {sorted(unknown)}; this device has {list(variants)}")
    variants = {k: v for k, v in variants.items() if args.variants is None or k in args.variants}
    rows = {}
    for name, patch in variants.items():
        # dls_ik and world_collides read them at trace time: each variant compiles anew.
        _ik.spd_solve, _ik_gpu.applies, _world_gpu.applies = patch
        rows[name] = [{**m, "dls_flops_per_pose": per_pose, "achieved_flops_per_s": per_pose * m["poses_per_s"]}
                      for m in (measure(problem, n, args.repeat) for n in args.batches)]
    _ik.spd_solve, _ik_gpu.applies, _world_gpu.applies = library
    stages = {"batch": args.batches[-1], "seconds": stage_seconds(problem, args.batches[-1], args.repeat)}
    print(json_text({
        "command": shlex.join(["python", "benchmarks/docking_fitness.py", *sys.argv[1:]]),
        "device": jax.devices()[0].device_kind, "platform": jax.devices()[0].platform, "jax": jax.__version__,
        "machine": platform.machine(), "cpus": os.cpu_count(), "fitness": "demo (16 tool poses, 8 seeds x 25 DLS iterations)",
        "collision_flops_per_pose": collision_flops(problem),
        "variants": rows, "stages": stages}))


if __name__ == "__main__":
    main()
