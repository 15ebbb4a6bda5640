"""Plan every edge of the thesis task graph with RRTConnect, BKPIECE1 and PRM (issue 6).

Writes into the Hydra run directory: ``targets.json`` (IK targets), ``edges.csv`` (one row per
planner and edge), ``metrics_<planner>.json`` (the five metric matrices), ``cost_<planner>.csv``
(thesis eq. 4.16 cost matrix, NaN = forbidden), ``plan.json`` (the configured schedule, format
of ``uvms_jax.hw.plan``), ``summary.json`` and PNGs (end-effector paths in the scene, joint
curves, rendered frames where offscreen rendering works).

    .venv/bin/python experiments/plan.py plan.planners=[RRTConnect] plan.budget_s=2
"""

from __future__ import annotations

import csv
import json
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path

import hydra
import jax
import numpy as np
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf
from tqdm import tqdm

os.environ.setdefault("MUJOCO_GL", "egl")  # headless offscreen rendering where EGL exists

from uvms_jax import hw, kin  # noqa: E402
from uvms_jax import plan as P  # noqa: E402

log = logging.getLogger(__name__)


def _write_csv(path: Path, rows: list[dict]) -> None:
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def plot_paths(scene, chain, results, path: Path) -> None:
    """End-effector paths of every planned edge over the scene (3-D and top view).

    All densified paths go through one ``kin.fk`` call: one XLA compilation, not one per path length."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in results if r.success]
    dense = [np.asarray(P.densify(r.plan.path, 0.02)) for r in ok]
    p_all = np.asarray(kin.fk(chain, np.concatenate(dense)))[:, :, 3] if dense else np.zeros((0, 4))
    p_world = (scene.T_world_base @ p_all.T).T[:, :3]
    fig = plt.figure(figsize=(13, 6))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    corners = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1)])
    for t in scene.spec.tables[1:]:  # the first table is the floor under everything
        c = corners * np.asarray(t.size[:2]) / 2
        pts = (t.T_world_top @ np.c_[c, np.zeros(5), np.ones(5)].T).T[:, :3]
        ax3.plot(*pts.T, color="0.5")
        ax2.plot(pts[:, 0], pts[:, 1], color="0.5")
    for node in list(scene.objects) + list(scene.bases):
        T = scene.T_world_object(node) if node in scene.objects else scene.T_world_base_top(node)
        ax3.scatter(*T[:3, 3], color="tab:orange" if node in scene.objects else "tab:red")
        ax2.annotate(str(node), T[:2, 3])
    cmap = plt.get_cmap("viridis")
    bounds = np.cumsum([0] + [len(d) for d in dense])
    for i, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
        color = cmap(i / max(1, len(dense)))
        ax3.plot(*p_world[a:b].T, color=color, lw=0.8)
        ax2.plot(p_world[a:b, 0], p_world[a:b, 1], color=color, lw=0.8)
    name = results[0].planner if results else ""
    ax3.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]", title=f"{name}: end-effector paths ({len(ok)} edges)")
    ax2.set(xlabel="x [m]", ylabel="y [m]", title="top view (node numbers)", aspect="equal")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_joints(plan_obj: dict, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(12, 4.5))
    t0, ts, qs = 0.0, [], []
    for seg in plan_obj["segments"]:
        if seg.get("t"):
            ts.append(np.asarray(seg["t"]) + t0)
            qs.append(np.asarray(seg["q"]))
            t0 = ts[-1][-1]
    t, q = np.concatenate(ts), np.concatenate(qs)
    for j, name in enumerate(plan_obj["joint_names"]):
        ax.plot(t, q[:, j], marker=".", ms=3, label=name)
    ax.set(xlabel="time [s] (waypoints; synchronised rest-to-rest legs)", ylabel="joint angle [rad]",
           title="plan.json joint waypoints")
    ax.legend(ncol=6)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def _render(scene, targets, out_dir: Path) -> int:
    """Offscreen frames of the start and every node's grasp/final pose; 0 if no GL."""
    try:
        import mujoco

        m = scene.model
        d = mujoco.MjData(m)
        renderer = mujoco.Renderer(m, 480, 640)
    except Exception as e:  # no EGL/OSMesa/GLFW context on this machine
        log.warning("offscreen rendering unavailable (%s); skipping frames", e)
        return 0
    import matplotlib.pyplot as plt

    cam = mujoco.MjvCamera()
    cam.lookat[:] = (0, 0, 0.45)
    cam.distance, cam.azimuth, cam.elevation = 2.2, 135, -30
    frames = [("start", np.asarray(scene.spec.start_q))] + [(f"node{n}", t.q_at) for n, t in targets.items()]
    for name, q in frames:
        d.qpos[:] = q
        mujoco.mj_forward(m, d)
        renderer.update_scene(d, cam)
        plt.imsave(out_dir / f"frame_{name}.png", renderer.render())
    renderer.close()
    return len(frames)


@dataclass(frozen=True)
class PlanRun:
    """What planning the task graph produced, kept in memory for turning a schedule into a plan.json."""

    scene: P.Scene
    checker: P.CollisionChecker
    targets: dict  # node -> P.NodeTarget
    by_planner: dict[str, list]  # planner -> [P.EdgeResult] in task_edges order
    summary: dict  # per planner: edges, success, revalidated, planning-time statistics [s]
    edges_csv: Path
    ik_seconds: float


def run(cfg: DictConfig, out: Path) -> PlanRun:
    """IK targets, then every task-graph edge with every configured planner, into ``out``:
    targets.json, edges.csv, metrics_<planner>.json, cost_<planner>.csv, ee_paths_<planner>.png."""
    pc = cfg.plan
    P.seed_ompl(int(pc.seed))  # once per process, before any planner (NOTES.md)
    scene = P.build_scene(OmegaConf.to_container(cfg.scenario, resolve=True))
    checker = P.CollisionChecker(scene, margin=pc.margin, clearance_max=pc.clearance_max)
    t0 = time.perf_counter()
    targets = P.pick_place_targets(scene, checker, jax.random.PRNGKey(int(pc.seed)), n_seeds=pc.ik.n_seeds,
                                   iterations=pc.ik.iterations, n_yaw_continuous=pc.ik.n_yaw_continuous,
                                   max_branch_jump=pc.ik.max_branch_jump, resolution=pc.recheck_resolution)
    t_ik = time.perf_counter() - t0
    log.info("IK targets for %d nodes in %.1f s (compilation included)", len(targets), t_ik)
    (out / "targets.json").write_text(json.dumps({
        str(n): {"q_pre": t.q_pre.tolist(), "q_at": t.q_at.tolist(), "yaw": t.yaw,
                 "manipulability": t.manipulability, "candidates": t.n_candidates}
        for n, t in targets.items()} | {"start": list(scene.spec.start_q)}, indent=1))
    chain = kin.bravo7()
    edges = P.task_edges(scene)
    kw = dict(budget_s=pc.budget_s, resolution=pc.resolution, recheck_resolution=pc.recheck_resolution,
              clearance_resolution=pc.clearance_resolution, simplify_s=pc.simplify_s,
              max_velocity=pc.max_velocity, max_acceleration=pc.max_acceleration, chain=chain)
    rows, summary, by_planner = [], {}, {}
    for planner in pc.planners:
        results = []
        for src, dst in tqdm(edges, desc=f"plan {planner}", unit="edge", leave=False, disable=None):
            r = P.plan_edge(scene, checker, targets, src, dst, planner, **kw)
            results.append(r)
            rows.append(r.row())
            log.debug("%s %d->%d success=%s revalidated=%s %.3f s", planner, src, dst, r.success, r.revalidated,
                      r.plan.planning_time_s)
        by_planner[planner] = results
        mats = P.metric_matrices(scene, results)
        (out / f"metrics_{planner}.json").write_text(json.dumps(
            {k: np.where(np.isnan(v), None, v).tolist() for k, v in mats.items()}))
        np.savetxt(out / f"cost_{planner}.csv", P.cost_matrix(mats, dict(pc.weights)), delimiter=",", fmt="%.6g")
        times = np.array([r.plan.planning_time_s for r in results])
        summary[planner] = {
            "edges": len(results), "success": int(sum(r.success for r in results)),
            "revalidated": int(sum(r.revalidated for r in results)),
            "median_planning_time_s": float(np.median(times)), "mean_planning_time_s": float(times.mean()),
            "max_planning_time_s": float(times.max()),
            "max_speed_ratio": float(max((r.check.get("max_speed_ratio", 0.0) for r in results), default=0.0)),
        }
        log.info("%s: %s", planner, summary[planner])
        plot_paths(scene, chain, results, out / f"ee_paths_{planner}.png")
    _write_csv(out / "edges.csv", rows)
    return PlanRun(scene, checker, targets, by_planner, summary, out / "edges.csv", t_ik)


def write_plan_json(planned: PlanRun, pc: DictConfig, planner: str, sequence: list[int], out: Path) -> dict:
    """``out/plan.json`` (format of ``uvms_jax.hw.plan``) and its joint plot for a node sequence,
    from ``planner``'s trajectories; returns the plan object."""
    jp = pc.plan_json
    emap = {(r.src, r.dst): r for r in planned.by_planner[planner]}
    plan_obj = P.plan_json(planned.scene, planned.targets, emap, sequence, jaws_open_mm=jp.jaws_open_mm,
                           jaws_closed_mm=jp.jaws_closed_mm, max_velocity=pc.max_velocity,
                           max_acceleration=pc.max_acceleration, checker=planned.checker)
    (out / "plan.json").write_text(json.dumps(plan_obj, indent=1))
    _plot_joints(plan_obj, out / "joints.png")
    return plan_obj


@hydra.main(version_base="1.3", config_path="../configs", config_name="plan")
def main(cfg: DictConfig) -> dict:
    jax.config.update("jax_enable_x64", True)  # IK in float64
    out = Path(HydraConfig.get().runtime.output_dir)
    planned = run(cfg, out)
    summary = dict(planned.summary)
    jp = cfg.plan.plan_json
    if jp.planner in planned.by_planner:
        plan_obj = write_plan_json(planned, cfg.plan, jp.planner, list(jp.sequence), out)
        check = hw.check_plan(hw.parse_plan(plan_obj))
        summary["plan_json"] = {"segments": check.n_segments, "estimated_s": check.estimated_s}
    summary["frames"] = _render(planned.scene, planned.targets, out) if cfg.plan.render else 0
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    log.info("outputs in %s", out)
    return summary


if __name__ == "__main__":
    main()
