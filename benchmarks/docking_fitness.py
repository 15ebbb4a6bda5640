"""The demo's docking fitness on a batch of vehicle poses: poses/s and XLA's flop count per
pose, with the DLS step's 6 × 6 solve written out (Cholesky, ``kin.spd_solve``, the library's)
beside the library's LU (``jnp.linalg.solve``), and on a GPU the whole IK loop as one kernel
(``uvms_jax.kin._ik_gpu``, the library's GPU path) beside both, in the same process; prints one
JSON object.

    JAX_PLATFORMS=cpu python benchmarks/docking_fitness.py --batches 256 1024
    python benchmarks/docking_fitness.py --batches 16384 131072          # GPU

The fitness is the demo's (``make demo``'s docking stage: 16 tool poses, 8 IK seeds × 25 DLS
iterations each, collisions), on poses drawn uniformly in its pose box. Compilation is timed
apart; the best of ``--repeat`` calls is reported. ``flops_per_pose`` is XLA's cost analysis of
the compiled call over the batch; with the device's peak it bounds the rate from above.
``stages`` times cumulative pieces of the fitness at the largest batch (:data:`STAGES`): where
the time goes.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

import jax
import jax.numpy as jnp

from uvms_jax import indices, kin
from uvms_jax.evo import _arm
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--batches", type=int, nargs="+", default=[256, 1024])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    _, _, problem = demo_problem(demo_settings([]))
    library, kernel_applies = _ik.spd_solve, _ik_gpu.applies
    settings = demo_settings([]).docking.scene
    solves_per_pose = len(problem.T_world_tool) * settings.ik_seeds * settings.ik_iterations
    per_pose = dls_iteration_flops(problem) * solves_per_pose
    variants = [("cholesky", library, False), ("lu", _lu, False)]
    if jax.default_backend() == "gpu":
        variants.insert(0, ("kernel", library, True))
    rows = {}
    for name, solve, kernel in variants:
        # dls_ik reads both at trace time: each variant compiles anew.
        _ik.spd_solve, _ik_gpu.applies = solve, (kernel_applies if kernel else lambda q: False)
        rows[name] = [{**m, "dls_flops_per_pose": per_pose, "achieved_flops_per_s": per_pose * m["poses_per_s"]}
                      for m in (measure(problem, n, args.repeat) for n in args.batches)]
    _ik.spd_solve, _ik_gpu.applies = library, kernel_applies
    stages = {"batch": args.batches[-1], "seconds": stage_seconds(problem, args.batches[-1], args.repeat)}
    print(json.dumps({
        "command": " ".join(["python benchmarks/docking_fitness.py", *sys.argv[1:]]),
        "device": jax.devices()[0].device_kind, "platform": jax.devices()[0].platform, "jax": jax.__version__,
        "machine": platform.machine(), "cpus": os.cpu_count(), "fitness": "demo (16 tool poses, 8 seeds x 25 DLS iterations)",
        "variants": rows, "stages": stages}, indent=1))


if __name__ == "__main__":
    main()
