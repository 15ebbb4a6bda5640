"""MotionBenchMaker benchmark: the Franka Panda with its own hand and fingers (from its URDF) in
the 7 MBM families (700 problems), the query path (:func:`uvms_jax.plan.plan_query`: compiled
RRT-Connect on the fitted spheres, then MuJoCo's exact check of every returned path) beside the
peer in the same process: OMPL's RRT-Connect with MuJoCo's exact state checks and OMPL's
state-by-state motion checks (the project's MuJoCo planning path), on the same robot model,
worlds and budget; and, with ``--vamp``, VAMP (the vectorized planner of Thomason et al.,
ICRA 2024: RRT-Connect and its simplification on its own sphere model of the Panda), fed the
same worlds, starts and goals through its Python API.

Per family and planner: problems valid in the model, solved, the median and p95 time per
problem (planning + simplification, the budgeted part; MuJoCo's final check reported apart),
and the returned paths re-checked exactly (MuJoCo, the real fingers, densified to 0.01 rad).
Problems invalid in the model are counted by reason. The requests hold the fingers at 0.065 m,
past the URDF's 0.04 m limit: every problem is planned with the fingers at 0.04 m (VAMP keeps
its own model's, at 0.065 m). VAMP's paths are re-checked the same way, and counted apart
where they leave the URDF's joint limits (its model has wider ones). Prints one JSON object
and writes it to ``--out``.

The problems: MotionBenchMaker's Panda set (Chamzas et al., RA-L 2022), as distributed with the
VAMP planner's resources (``problems/<family>_panda/{scene,request}NNNN.yaml``).

    .venv/bin/python benchmarks/mbm.py --problems PATH/problems [--budget 1.0] [--per-family 100]
        [--peer] [--vamp] [--out benchmarks/results/mbm_cpu.json]

``--vamp`` needs the ``vamp-planner`` package, a peer for this benchmark only (not a
dependency of the project): docs/planning.md, "VAMP as a peer", says how to build it.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import platform
import time
from pathlib import Path

import numpy as np

from uvms_jax import frames
from uvms_jax import plan as P
from uvms_jax import robot as R
from uvms_jax.files import json_text, write_json
from uvms_jax.plan._collision import densify

FAMILIES = ("table_pick", "table_under_pick", "box", "bookshelf_small", "bookshelf_tall", "bookshelf_thin", "cage")
OPENING = 0.04  # [m] the URDF's largest finger opening (the requests' 0.065 m is past it)
RECHECK = 0.01  # [rad] densification of the exact re-check of every returned path
VAMP_LIMIT_TOL = 1e-6  # [rad] VAMP's states are float32: its endpoints may round past a limit by ~2e-7
VAMP_MISSING = ("--vamp needs the vamp-planner package (a benchmark peer, not a project dependency): "
                "build and install it as docs/planning.md, section 'VAMP as a peer', says")


def panda() -> R.Robot:
    """The Panda of the example-robot-data wheel, its hand and fingers from the URDF."""
    robots = importlib.metadata.distribution("example-robot-data").locate_file(
        "cmeel.prefix/share/example-robot-data/robots")
    return R.load_robot(robots / "panda_description/urdf/panda.urdf", tip="panda_hand_tcp", link_radius=0.05,
                        gripper="panda_finger_joint1")


def _ompl_mujoco(exact: P.ExactChecker, robot: R.Robot, start, goal, budget_s: float) -> tuple[bool, float, np.ndarray]:
    """The peer: OMPL RRT-Connect, MuJoCo's state checks, OMPL's motion checks at 0.01 rad."""
    from ompl import geometric as og

    from uvms_jax.plan._planners import joint_space

    n = robot.n_joints
    space, ss, si = joint_space(robot.lower, robot.upper)
    ss.setStateValidityChecker(lambda s: not exact.contacts(np.array([[s[i] for i in range(n)]])))
    si.setStateValidityCheckingResolution(RECHECK / space.getMaximumExtent())
    ss.setPlanner(og.RRTConnect(si))
    a, b = space.allocState(), space.allocState()
    a[0:n], b[0:n] = list(start), list(goal)
    ss.setStartAndGoalStates(a, b)
    t0 = time.perf_counter()
    solved = bool(ss.solve(budget_s)) and ss.haveExactSolutionPath()
    path = np.zeros((0, n))
    if solved:
        ss.simplifySolution(max(1e-3, budget_s - (time.perf_counter() - t0)))
        path = np.array([[s[i] for i in range(n)] for s in ss.getSolutionPath().getStates()])
    spent = time.perf_counter() - t0
    del ss, si
    return solved, spent, path


def _vamp_module():
    """VAMP's Python package, imported only when asked for; SystemExit with how to get it."""
    try:
        import vamp
    except ImportError:
        raise SystemExit(VAMP_MISSING) from None
    return vamp


def vamp_environment(vamp, world: P.World, family: str):
    """VAMP's ``Environment`` of ``world``: boxes as cuboids, spheres as spheres, and cylinders
    (VAMP has no cylinder) as capsules of the same radius and axis segment, or in the ``box``
    family as their bounding cuboid, as VAMP's own MotionBenchMaker set has them (the capsule's
    caps would block the top-down grasp of that family's cylinder). Both enclose the cylinder."""
    env = vamp.Environment()
    for o in world.obstacles:
        T = o.T_world
        pos, rpy = T[:3, 3].tolist(), frames.matrix_rpy(T[:3, :3]).tolist()  # VAMP's Euler XYZ is URDF's rpy
        if o.shape == "box":
            env.add_cuboid(vamp.Cuboid(pos, rpy, [d / 2 for d in o.dims]))
        elif o.shape == "sphere":
            env.add_sphere(vamp.Sphere(pos, o.dims[0]))
        elif o.shape == "cylinder" and family == "box":
            env.add_cuboid(vamp.Cuboid(pos, rpy, [o.dims[0], o.dims[0], o.dims[1] / 2]))
        elif o.shape == "cylinder":
            env.add_capsule(vamp.Cylinder(pos, rpy, o.dims[0], o.dims[1]))
        else:
            raise ValueError(f"obstacle {o.name!r}: VAMP's peer takes boxes, spheres and cylinders, got {o.shape!r}")
    return env


class VampPeer:
    """VAMP's RRT-Connect and simplification for its Panda, with its defaults (Halton samples,
    reset per problem, so each problem's run is repeatable)."""

    def __init__(self):
        self.vamp = _vamp_module()
        self.robot, self.planner, self.settings, self.simplify = \
            self.vamp.configure_robot_and_planner_with_kwargs("panda", "rrtc")
        self.sampler = self.robot.halton()

    def valid(self, q: np.ndarray, env) -> bool:
        """Whether VAMP's own model calls ``q (7,)`` [rad] free in ``env`` (bounds not checked)."""
        return bool(self.robot.validate(q.tolist(), env))

    def plan(self, env, start: np.ndarray, goal: np.ndarray) -> tuple[bool, float, float, np.ndarray]:
        """(solved, seconds of the planning + simplification calls, seconds by VAMP's own clock,
        ``(k, 7)`` path [rad]) from ``start`` to ``goal`` ``(7,)`` [rad]; the path is empty where
        VAMP finds none. VAMP's clock starts after it allocates its trees (for ``max_samples``
        states), which the calls' time includes."""
        self.sampler.reset()
        t0 = time.perf_counter()
        result = self.planner(start.tolist(), goal.tolist(), env, self.settings, self.sampler)
        if not result.solved:
            return False, time.perf_counter() - t0, result.nanoseconds * 1e-9, np.zeros((0, 7))
        simple = self.robot.simplify(result.path, env, self.simplify, self.sampler)
        spent = time.perf_counter() - t0
        own = (result.nanoseconds + simple.nanoseconds) * 1e-9
        return True, spent, own, np.asarray(simple.path.numpy(), dtype=np.float64)


def _summary(times: list[float], solved: int, valid: int, recheck_ok: int) -> dict:
    t = np.array(times) if times else np.array([np.nan])
    return {"valid": valid, "solved": solved, "success_rate": solved / valid if valid else None,
            "median_ms": float(np.median(t) * 1e3), "p95_ms": float(np.percentile(t, 95) * 1e3),
            "max_ms": float(np.max(t) * 1e3), "rechecked_free": recheck_ok}


def state_rates(robot: R.Robot, problems: Path, batch: int = 4096) -> dict:
    """Per-state cost of the checker in one call over ``batch`` uniform random configurations,
    in each family's first world [µs]: the spheres alone (FREE/HIT/MAYBE, over the CPU's
    threads), and the verdicts with MuJoCo settling MAYBE (serially), with MuJoCo's own check
    (``mj_kinematics`` + ``mj_collision`` per state) beside them."""
    Q = np.random.default_rng(0).uniform(robot.lower, robot.upper, (batch, robot.n_joints))
    out = {}
    for family in FAMILIES:
        checker = P.VectorChecker(robot, P.load_moveit_scene(problems / f"{family}_panda" / "scene0001.yaml"), OPENING)
        checker.states_free(Q)  # compiled, and the threads started
        row = {}
        for name, fn in (("spheres_us", checker.states_status), ("verdict_us", checker.states_free),
                         ("mujoco_us", lambda X: [checker.exact.free(q) for q in X])):
            t0 = time.perf_counter()
            fn(Q)
            row[name] = (time.perf_counter() - t0) / batch * 1e6
        status = checker.states_status(Q)
        row["maybe_fraction"] = float(np.mean(status == 2))
        out[family] = row
    return out


def _tally(rows: dict, name: str, done: bool, spent: float, free: bool, budget_s: float) -> None:
    """Add one problem to planner ``name``'s (times, solved, re-checked free)."""
    times, solved, ok = rows[name]
    # A failure counts at the whole budget it was given (or what it spent, if more).
    times.append(spent if done else max(budget_s, spent))
    rows[name] = (times, solved + done, ok + free)


def _vamp_problem(vamp: VampPeer, robot: R.Robot, exact: P.ExactChecker, env, start, goal, budget_s: float,
                  rows: dict) -> dict:
    """VAMP on one problem, tallied in ``rows``; its record's fields: times [ms], whether it
    solved within the budget, stayed in the URDF's limits, and is free for MuJoCo, else the
    deepest penetration [mm] and whether a finger is in every contact."""
    done, spent, own, path = vamp.plan(env, start, goal)
    done = done and spent <= budget_s
    hits = exact.contacts(densify(path, RECHECK)) if done else []
    inside = done and bool(np.all((path >= robot.lower - VAMP_LIMIT_TOL) & (path <= robot.upper + VAMP_LIMIT_TOL)))
    _tally(rows, "vamp", done, spent, done and not hits, budget_s)
    rec = {"vamp_ms": spent * 1e3, "vamp_own_ms": own * 1e3, "vamp_solved": done, "vamp_free": done and not hits,
           "vamp_in_limits": inside, "vamp_model_valid": vamp.valid(start, env) and vamp.valid(goal, env)}
    if hits:
        rec.update(vamp_depth_mm=max(d for *_, d in hits) * 1e3,
                   vamp_fingers_only=all("finger" in a or "finger" in b for _, a, b, _ in hits))
    return rec


def _vamp_family(records: list[dict], budget_s: float) -> dict:
    """VAMP's extra counts over one family's records: paths in the URDF's limits, problems its
    model calls invalid, paths whose every contact is a finger's, and its own clock [ms]."""
    own = np.array([r["vamp_own_ms"] if r["vamp_solved"] else max(budget_s * 1e3, r["vamp_own_ms"])
                    for r in records] or [np.nan])
    return {"in_limits": sum(r["vamp_in_limits"] for r in records),
            "model_invalid": sum(not r["vamp_model_valid"] for r in records),
            "fingers_only_hits": sum(r.get("vamp_fingers_only", False) for r in records),
            "own_median_ms": float(np.median(own)), "own_p95_ms": float(np.percentile(own, 95))}


def run(problems: Path, budget_s: float, per_family: int, peer: bool, with_vamp: bool = False) -> dict:
    robot = panda()
    vamp = VampPeer() if with_vamp else None
    P.seed_ompl(0)
    # Compile the kernels before any timing (Numba's cache makes later runs load them): a query
    # in an empty world runs every compiled function once.
    t0 = time.perf_counter()
    mid = (robot.lower + robot.upper) / 2
    P.plan_query(robot, P.World(), mid, mid + 0.1, opening=OPENING, budget_s=budget_s)
    compile_s = time.perf_counter() - t0
    names = ["query"] + ["ompl_mujoco"] * peer + ["vamp"] * with_vamp
    families, invalid, records = {}, {}, []
    for family in FAMILIES:
        folder = problems / f"{family}_panda"
        rows, valid = {name: ([], 0, 0) for name in names}, 0
        for k in range(1, per_family + 1):
            world = P.load_moveit_scene(folder / f"scene{k:04d}.yaml")
            req = P.load_moveit_request(folder / f"request{k:04d}.yaml", robot)
            reason = None
            try:
                start = P.check_in_limits(robot, req.start, "start")
                goal = P.check_in_limits(robot, req.goal, "goal")
            except ValueError as err:
                reason = "start outside the limits" if str(err).startswith("start") else "goal outside the limits"
            checker = P.VectorChecker(robot, world, OPENING)
            exact = checker.exact
            if reason is None:
                start, goal = np.clip(start, robot.lower, robot.upper), np.clip(goal, robot.lower, robot.upper)
                if exact.contacts(start[None]):
                    reason = "start in collision"
                elif exact.contacts(goal[None]):
                    reason = "goal in collision"
            if reason is not None:
                invalid[reason] = invalid.get(reason, 0) + 1
                records.append({"family": family, "problem": k, "invalid": reason})
                continue
            valid += 1
            res = P.plan_query(robot, world, start, goal, opening=OPENING, budget_s=budget_s, checker=checker)
            rec = {"family": family, "problem": k, "query_ms": res.time_s * 1e3, "query_reason": res.reason,
                   "query_exact_ms": res.exact_s * 1e3, "iterations": res.iterations}
            _tally(rows, "query", res.success, res.time_s, res.success and not exact.contacts(
                densify(res.path, RECHECK)), budget_s)
            if peer:
                done, spent, path = _ompl_mujoco(exact, robot, start, goal, budget_s)
                _tally(rows, "ompl_mujoco", done, spent, done and not exact.contacts(densify(path, RECHECK)), budget_s)
                rec.update(ompl_mujoco_ms=spent * 1e3, ompl_mujoco_solved=done)
            if vamp is not None:
                rec.update(_vamp_problem(vamp, robot, exact, vamp_environment(vamp.vamp, world, family), start, goal,
                                         budget_s, rows))
            records.append(rec)
        families[family] = {name: _summary(t, s, valid, ok) for name, (t, s, ok) in rows.items()}
        if vamp is not None:
            families[family]["vamp"].update(_vamp_family(
                [r for r in records if r["family"] == family and "vamp_ms" in r], budget_s))
    spheres = R.collision_spheres(robot)
    return {"families": families, "invalid": invalid, "compile_s": compile_s, "records": records,
            "state_check": state_rates(robot, problems), "n_spheres": len(spheres), "sphere_excess_m": spheres.max_excess}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--problems", type=Path, required=True, help="the MBM 'problems' folder")
    ap.add_argument("--budget", type=float, default=1.0, help="time budget per problem [s]")
    ap.add_argument("--per-family", type=int, default=100)
    ap.add_argument("--peer", action="store_true", help="also run OMPL with MuJoCo's checks")
    ap.add_argument("--vamp", action="store_true", help="also run VAMP (needs the vamp-planner package)")
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "mbm_cpu.json")
    args = ap.parse_args()
    if args.vamp:
        _vamp_module()  # before any work: a missing package is said at once
    result = run(args.problems, args.budget, args.per_family, args.peer, args.vamp)
    all_query = [r for r in result["records"] if "query_ms" in r]
    result.update({
        "benchmark": "mbm", "device": f"{platform.machine()} CPU, Python {platform.python_version()}",
        "budget_s": args.budget, "opening_m": OPENING, "request_opening_m": 0.065, "recheck_rad": RECHECK,
        "problems": sum(1 for _ in result["records"]),
        "query_total": _summary([r["query_ms"] / 1e3 for r in all_query],
                                sum(r["query_reason"] == "solved" for r in all_query), len(all_query),
                                sum(f["query"]["rechecked_free"] for f in result["families"].values())),
        "command": "python benchmarks/mbm.py --problems PROBLEMS" + (" --peer" if args.peer else "")
                   + (" --vamp" if args.vamp else ""),
    })
    if args.vamp:
        mine = [r for r in result["records"] if "vamp_ms" in r]
        rows = {"vamp": ([], 0, 0)}
        for r in mine:
            _tally(rows, "vamp", r["vamp_solved"], r["vamp_ms"] / 1e3, r["vamp_free"], args.budget)
        times, solved, ok = rows["vamp"]
        result["vamp_total"] = _summary(times, solved, len(mine), ok) | _vamp_family(mine, args.budget)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json(args.out, result)
    print(json_text({k: v for k, v in result.items() if k != "records"}))


if __name__ == "__main__":
    main()
