"""Hovering scenarios: MJX batch throughput against CPU MuJoCo (HoverSim); prints one JSON object.

  JAX_PLATFORMS=cpu python benchmarks/hover_mjx.py --batches 16 64 --seconds 0.4      # CPU, small
  python benchmarks/hover_mjx.py --batches 64 1024 8192 65536 --seconds 2             # GPU

Each batch is B scenarios (the Bravo 7 on the default vehicle, trimmed), each its own docked pose
and current (a random horizontal current up to 0.5 m/s), the arm making the same minimum-jerk
move, station keeping on: ``--seconds`` simulated in one ``jax.jit(jax.vmap(rollout))`` call
that keeps no per-period record (only the final state and the largest drift). The compile time
(``lower().compile()``) is reported apart from the run time (best of ``--repeat`` runs).
env-steps/s counts physics steps × scenarios per second of run time. The CPU baseline is
``HoverSim.run`` on one thread (MuJoCo's C step, buoyancy by ``mj_step1``/``mj_step2``, the
controller in NumPy) for the same model and motion.

On the CPU, XLA's fusion emitters (on by default in this jax, 0.10.2) compile this program into code
that runs some 450 times slower (measured: 7.2 s against 0.016 s for 4 scenarios × 200 steps);
the benchmark therefore adds ``--xla_cpu_use_fusion_emitters=false`` to ``XLA_FLAGS`` unless
``--xla-cpu-fusion-emitters`` is given (tests/conftest.py sets it too). The flag only concerns
XLA's CPU backend; on a GPU it changes nothing. ``XLA_FLAGS`` is reported.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
_CPU_FLAG = "--xla_cpu_use_fusion_emitters"  # a CPU backend flag: jax 0.10's knows it, a GPU build may not
if (os.environ.get("JAX_PLATFORMS") == "cpu" and "--xla-cpu-fusion-emitters" not in sys.argv
        and _CPU_FLAG not in os.environ.get("XLA_FLAGS", "")):
    os.environ["XLA_FLAGS"] = " ".join(filter(None, [os.environ.get("XLA_FLAGS"), f"{_CPU_FLAG}=false"]))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from uvms_jax.files import json_text  # noqa: E402
from uvms_jax.hover import (ControllerSettings, CurrentSettings, HoverSim, VehicleSettings,  # noqa: E402
                            arm_motion, trimmed)
from uvms_jax.hover import hover_mjx  # noqa: E402
from uvms_jax.robot import load_arm  # noqa: E402


def _version(name: str) -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(name)
    except PackageNotFoundError:
        return "unknown"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--batches", type=int, nargs="+", default=[16, 64], help="scenarios per jitted call")
    ap.add_argument("--seconds", type=float, default=2.0, help="simulated time per scenario [s]")
    ap.add_argument("--cpu-seconds", type=float, default=None, help="HoverSim's simulated time (default: --seconds)")
    ap.add_argument("--repeat", type=int, default=2, help="timed runs per batch after the compile (best reported)")
    ap.add_argument("--arm", default="bravo7")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--xla-cpu-fusion-emitters", action="store_true",
                    help="keep XLA's CPU fusion emitters (slow for this program; see above)")
    args = ap.parse_args()

    arm = load_arm(args.arm)
    controller = ControllerSettings()
    q_a = (arm.lower + arm.upper) / 2
    q_b = np.clip(q_a + np.array([0.3, -0.2, 0.2, 0.0, 0.3, 0.0])[:arm.n_joints], arm.lower, arm.upper)
    move = arm_motion(q_a, q_b, 0.2 * args.seconds, 0.8 * args.seconds)
    periods = round(args.seconds / controller.period)
    table = np.array([move(k * controller.period) for k in range(periods)])
    vehicle = trimmed(VehicleSettings(), arm, q_a)
    sim = hover_mjx(arm, vehicle, controller)
    physics_steps = periods * sim.physics_steps

    def run_one(pose, wind):
        return sim.rollout(pose, wind, jnp.asarray(table, sim.dtype), record=False)

    batched = jax.jit(jax.vmap(run_one))
    rng = np.random.default_rng(args.seed)
    results = []
    for B in args.batches:
        poses = np.column_stack([rng.uniform(-1, 1, (B, 2)), rng.uniform(0.5, 1.5, B), rng.uniform(-np.pi, np.pi, B)])
        heading, speed = rng.uniform(-np.pi, np.pi, B), rng.uniform(0.0, 0.5, B)
        winds = np.column_stack([speed * np.cos(heading), speed * np.sin(heading), np.zeros(B)])
        p, w = jnp.asarray(poses, sim.dtype), jnp.asarray(winds, sim.dtype)
        t0 = time.perf_counter()
        compiled = batched.lower(p, w).compile()
        compile_s = time.perf_counter() - t0
        runs = []
        for _ in range(max(args.repeat, 1)):
            t0 = time.perf_counter()
            last, drift = jax.block_until_ready(compiled(p, w))
            runs.append(time.perf_counter() - t0)
        run_s = min(runs)
        drift = np.asarray(drift)
        results.append({"batch": B, "compile_s": compile_s, "run_s": run_s, "runs_s": runs,
                        "env_steps_per_s": B * physics_steps / run_s, "scenarios_per_s": B / run_s,
                        "simulated_s_per_s": B * args.seconds / run_s,
                        "finite": bool(np.all(np.isfinite(np.asarray(last.position)))),
                        "max_drift_m": {"median": float(np.median(drift)), "max": float(drift.max())}})

    # CPU MuJoCo, one scenario at a time on one thread
    cpu_seconds = args.seconds if args.cpu_seconds is None else args.cpu_seconds
    cpu_periods = round(cpu_seconds / controller.period)
    cpu_runs = []
    for _ in range(max(args.repeat, 1)):
        cpu = HoverSim(arm, vehicle, controller, CurrentSettings(velocity=(0.3, 0.1, 0.0)), xyz=(0.2, -0.3, 1.0),
                       rpy=(0.0, 0.0, 0.7), q0=q_a)
        t0 = time.perf_counter()
        cpu.run(cpu_seconds, arm_trajectory=move)
        cpu_runs.append(time.perf_counter() - t0)
    cpu_s = min(cpu_runs)
    cpu_steps_per_s = cpu_periods * sim.physics_steps / cpu_s
    # For scale: MuJoCo's C step alone on the same model (its own fluid, no buoyancy hook, no
    # controller, no Python between steps but the loop): what HoverSim's Python costs on top.
    m = sim.model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    n_raw = max(cpu_periods * sim.physics_steps, 5000)
    t0 = time.perf_counter()
    for _ in range(n_raw):
        mujoco.mj_step(m, d)
    raw_steps_per_s = n_raw / (time.perf_counter() - t0)
    for r in results:
        r["speedup_vs_cpu_one_thread"] = r["env_steps_per_s"] / cpu_steps_per_s

    device = jax.devices()[0]
    print(json_text({
        "benchmark": "hover_mjx",
        "command": " ".join(["python benchmarks/hover_mjx.py", *sys.argv[1:]]),
        "device": {"platform": device.platform, "device_kind": device.device_kind, "count": jax.device_count()},
        "host": {"machine": platform.machine(), "cpus": os.cpu_count(), "python": platform.python_version()},
        "versions": {"jax": jax.__version__, "mujoco": mujoco.__version__, "mujoco_mjx": _version("mujoco-mjx")},
        "xla_flags": os.environ.get("XLA_FLAGS", ""),
        "dtype": str(sim.dtype),
        "model": {"arm": arm.name, "nbody": sim.model.nbody, "nv": sim.model.nv, "nu": sim.model.nu,
                  "physics_dt_s": float(sim.model.opt.timestep), "control_period_s": controller.period,
                  "integrator": "implicitfast"},
        "simulated_s": args.seconds, "physics_steps_per_scenario": physics_steps,
        "mjx": results,
        "cpu_mujoco_hoversim": {"threads": 1, "simulated_s": cpu_seconds, "wall_s": cpu_s, "runs_s": cpu_runs,
                                "steps_per_s": cpu_steps_per_s},
        "cpu_mujoco_mj_step_only": {"threads": 1, "steps": n_raw, "steps_per_s": raw_steps_per_s},
    }))


if __name__ == "__main__":
    main()
