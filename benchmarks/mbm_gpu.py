"""MotionBenchMaker's Franka Panda problems planned in one batched JAX call
(:func:`uvms_jax.plan._batch_jax.plan_batch`): every problem's world padded into one batch, the
call compiled once (timed apart) and then run (timed), the solved paths re-checked one by one
by the Numba sphere checker at the check resolution (the CPU path's final check: every joint
moves at most 0.01 rad between two samples).

Per family: problems, those whose start and goal are within the joint limits and free for the
spheres, solved in the batch, and re-checked free. What the batch leaves unsolved is for the
CPU planner (:func:`uvms_jax.plan.plan_query`). Writes the record to
``benchmarks/results/mbm_gpu_<device>.json`` (``cpu``, ``h100``, …) unless ``--out`` is given,
and prints it.

    MBM_PROBLEMS=path/to/problems python benchmarks/mbm_gpu.py [--device cpu|gpu]
        [--families box_panda cage_panda] [--count 100] [--nodes 64] [--rounds 8] [--chunk 4096]

``path/to/problems`` holds ``<family>/sceneNNNN.yaml`` and ``requestNNNN.yaml`` (MoveIt's
PlanningScene and MotionPlanRequest) of each family.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.metadata
import os
import platform
import re
import sys
import time
from pathlib import Path

from uvms_jax.files import json_text, write_json

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
FAMILIES = ("bookshelf_small_panda", "bookshelf_tall_panda", "bookshelf_thin_panda", "box_panda", "cage_panda",
            "table_pick_panda", "table_under_pick_panda")
CHECK_RESOLUTION = 0.01  # [rad] the CPU path's final check


_SIZES = ("nodes", "rounds", "lazy", "waypoints", "coarse", "samples", "chunk")


def _args(argv=None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--problems", type=Path, default=os.environ.get("MBM_PROBLEMS"),
                    help="folder of the problem families (default: $MBM_PROBLEMS)")
    ap.add_argument("--device", default="cpu", help="JAX platform: cpu, gpu/cuda (default cpu)")
    ap.add_argument("--families", nargs="+", default=list(FAMILIES))
    ap.add_argument("--count", type=int, default=100, help="problems per family, from the first (default 100)")
    ap.add_argument("--opening", type=float, default=None, help="finger opening [m] (default: the gripper's largest)")
    ap.add_argument("--dtype", default="float32", choices=["float32", "float64"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=2, help="timed runs after the compile (default 2)")
    for f in _SIZES:
        ap.add_argument(f"--{f}", type=int, default=None, help="BatchSettings." + f)
    ap.add_argument("--uniform", type=float, default=None, help="BatchSettings.uniform")
    ap.add_argument("--urdf", type=Path, default=None, help="the Panda's URDF (default: example-robot-data's)")
    ap.add_argument("--out", type=Path, default=None, help="record file (default results/mbm_gpu_<device>.json)")
    args = ap.parse_args(argv)
    if args.problems is None or not Path(args.problems).is_dir():
        ap.error(f"problem folder {args.problems} not found (give --problems or set MBM_PROBLEMS)")
    if args.count < 1 or args.repeats < 1:
        ap.error("--count and --repeats must be >= 1")
    return args


def device_label(device) -> str:
    """``cpu``, or the GPU's model in lower case (``h100``, ``h200``, ``a100``), else its platform."""
    if device.platform == "cpu":
        return "cpu"
    m = re.search(r"\b([A-Z]{1,2}\d{2,4})\b", device.device_kind)
    return m.group(1).lower() if m else device.platform


def panda(urdf: Path | None = None):
    """The Panda with its hand: ``urdf``, or the example-robot-data wheel's."""
    from uvms_jax import robot as R

    if urdf is None:
        urdf = Path(str(importlib.metadata.distribution("example-robot-data").locate_file(
            "cmeel.prefix/share/example-robot-data/robots"))) / "panda_description/urdf/panda.urdf"
    return R.load_robot(urdf, tip="panda_hand_tcp", link_radius=0.05, gripper="panda_finger_joint1")


def load_problems(root: Path, families, count: int, robot):
    """``[(family, index, World, MotionRequest)]``, ``count`` of each family, in order."""
    from uvms_jax import plan

    out = []
    for fam in families:
        for i in range(1, count + 1):
            scene, request = root / fam / f"scene{i:04d}.yaml", root / fam / f"request{i:04d}.yaml"
            if not scene.is_file():
                raise ValueError(f"{scene} not found: family {fam!r} has fewer than {count} problems")
            out.append((fam, i, plan.load_moveit_scene(scene), plan.load_moveit_request(request, robot)))
    return out


def _recheck(robot, world, path, opening) -> bool:
    """The Numba checker's verdict on every sample of ``path (k, n)`` at the check resolution."""
    from uvms_jax.plan import VectorChecker, densify

    return bool(VectorChecker(robot, world, opening=opening).states_free(densify(path, CHECK_RESOLUTION)).all())


def run(args: argparse.Namespace) -> dict:
    """Plan the problems of ``args`` in one batch; the record (see the module docstring)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from uvms_jax.plan._batch_jax import BatchSettings, plan_batch
    from uvms_jax.plan._vector import LIMIT_TOL, robot_spheres_model
    from uvms_jax.plan._vector_jax import sphere_arm, sphere_worlds

    if args.dtype == "float64":
        jax.config.update("jax_enable_x64", True)
    dtype = np.dtype(args.dtype)
    robot = panda(args.urdf)
    side = robot_spheres_model(robot, args.opening)
    t0 = time.perf_counter()
    problems = load_problems(Path(args.problems), args.families, args.count, robot)
    starts = np.stack([p[3].start for p in problems])
    goals = np.stack([p[3].goal for p in problems])
    arm, worlds = sphere_arm(side, dtype), sphere_worlds(side, [p[2] for p in problems], dtype=dtype)
    load_s = time.perf_counter() - t0
    lo, hi = np.asarray(robot.lower) - LIMIT_TOL, np.asarray(robot.upper) + LIMIT_TOL
    in_limits = np.all((starts >= lo) & (starts <= hi) & (goals >= lo) & (goals <= hi), axis=1)

    given = {f: getattr(args, f) for f in (*_SIZES, "uniform") if getattr(args, f) is not None}
    settings = BatchSettings(**given, resolution=CHECK_RESOLUTION)
    S, G, key = jnp.asarray(starts, dtype), jnp.asarray(goals, dtype), jax.random.key(args.seed)
    t0 = time.perf_counter()
    compiled = plan_batch.lower(arm, worlds, S, G, key, settings).compile()
    compile_s = time.perf_counter() - t0
    run_s = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(compiled(arm, worlds, S, G, key))
        run_s.append(time.perf_counter() - t0)
    out = jax.tree.map(np.asarray, out)

    t0 = time.perf_counter()
    rechecked = np.zeros(len(problems), bool)
    for b, (_, _, world, _) in enumerate(problems):
        if out.solved[b]:
            rechecked[b] = _recheck(robot, world, out.path[b, :out.count[b]].astype(np.float64), side.opening)
    recheck_s = time.perf_counter() - t0

    families = {}
    for fam in args.families:
        sel = np.array([p[0] == fam for p in problems])
        families[fam] = {"problems": int(sel.sum()), "endpoints_in_limits": int(in_limits[sel].sum()),
                         "endpoints_free": int(out.endpoints_free[sel].sum()), "solved": int(out.solved[sel].sum()),
                         "rechecked_free": int(rechecked[sel].sum())}
    solved = out.solved
    device = jax.devices()[0]
    return {
        "benchmark": "mbm_gpu", "command": " ".join(["python benchmarks/mbm_gpu.py", *sys.argv[1:]]),
        "device": device.device_kind, "platform": device.platform, "cpu_count": os.cpu_count(),
        "python": platform.python_version(), "jax": jax.__version__, "dtype": args.dtype,
        "settings": dataclasses.asdict(settings), "seed": args.seed, "opening_m": side.opening,
        "n_problems": len(problems), "n_obstacle_rows": int(worlds.obstacles.shape[1]),
        "n_spheres": int(arm.radius.shape[0]), "load_s": load_s, "compile_s": compile_s, "run_s": run_s,
        "rounds_run": int(out.rounds), "recheck_s": recheck_s,
        "totals": {k: sum(f[k] for f in families.values()) for k in next(iter(families.values()))},
        "families": families,
        "solved_waypoints_median": float(np.median(out.count[solved])) if solved.any() else None,
        "solved_length_median_rad": float(np.median(out.length[solved])) if solved.any() else None,
        "failed_recheck": [f"{p[0]}/{p[1]}" for p, s, r in zip(problems, solved, rechecked) if s and not r],
        "note": "unsolved problems (and those whose ends collide or leave the limits) are the CPU planner's",
    }


def main(argv=None) -> dict:
    args = _args(argv)
    os.environ["JAX_PLATFORMS"] = {"gpu": "cuda"}.get(args.device, args.device)
    record = run(args)
    import jax

    out = args.out or RESULTS / f"mbm_gpu_{device_label(jax.devices()[0])}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    write_json(out, record)
    print(json_text(record))
    return record


if __name__ == "__main__":
    main()
