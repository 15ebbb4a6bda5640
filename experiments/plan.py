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
from pathlib import Path

import hydra
import jax
import numpy as np
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

os.environ.setdefault("MUJOCO_GL", "egl")  # headless offscreen rendering where EGL exists

from uvms_jax import hw, kin  # noqa: E402
from uvms_jax import plan as P  # noqa: E402

log = logging.getLogger(__name__)


def _edge_rows_csv(path: Path, rows: list[dict]) -> None:
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def _plot_paths(scene, chain, results, targets, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(13, 6))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    for t in scene.spec.tables[1:]:
        c = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1)]) * np.asarray(t.size[:2]) / 2
        pts = (t.T_world_top @ np.c_[c, np.zeros(5), np.ones(5)].T).T[:, :3]
        ax3.plot(*pts.T, color="0.5")
        ax2.plot(pts[:, 0], pts[:, 1], color="0.5")
    for node in list(scene.objects) + list(scene.bases):
        T = scene.T_world_object(node) if node in scene.objects else scene.T_world_base_top(node)
        ax3.scatter(*T[:3, 3], color="tab:orange" if node in scene.objects else "tab:red")
        ax2.annotate(str(node), T[:2, 3])
    cmap = plt.get_cmap("viridis")
    for i, r in enumerate(results):
        if not r.success:
            continue
        dense = P.densify(r.plan.path, 0.02)
        p = (scene.T_world_base @ np.concatenate(
            [np.asarray(kin.fk(chain, dense))[:, :, 3]], axis=0).T).T[:, :3]
        ax3.plot(*p.T, color=cmap(i / max(1, len(results))), lw=0.8)
        ax2.plot(p[:, 0], p[:, 1], color=cmap(i / max(1, len(results))), lw=0.8)
    ax3.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]", title=f"{results[0].planner}: end-effector paths")
    ax2.set(xlabel="x [m]", ylabel="y [m]", title="top view (node numbers)", aspect="equal")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
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


@hydra.main(version_base="1.3", config_path="../configs", config_name="plan")
def main(cfg: DictConfig) -> dict:
    jax.config.update("jax_enable_x64", True)
    out = Path(HydraConfig.get().runtime.output_dir)
    pc = cfg.plan
    P.seed_ompl(int(pc.seed))
    scene = P.build_scene(OmegaConf.to_container(cfg.scenario, resolve=True))
    checker = P.CollisionChecker(scene, margin=pc.margin, clearance_max=pc.clearance_max)
    t0 = time.perf_counter()
    targets = P.pick_place_targets(scene, checker, jax.random.PRNGKey(int(pc.seed)), n_seeds=pc.ik.n_seeds,
                                   iterations=pc.ik.iterations, n_yaw_continuous=pc.ik.n_yaw_continuous,
                                   max_branch_jump=pc.ik.max_branch_jump, resolution=pc.recheck_resolution)
    log.info("IK targets for %d nodes in %.1f s", len(targets), time.perf_counter() - t0)
    (out / "targets.json").write_text(json.dumps({
        str(n): {"q_pre": t.q_pre.tolist(), "q_at": t.q_at.tolist(), "yaw": t.yaw,
                 "manipulability": t.manipulability, "candidates": t.n_candidates}
        for n, t in targets.items()} | {"start": list(scene.spec.start_q)}, indent=1))
    chain = kin.bravo7()
    edges = P.task_edges(scene)
    rows, summary, by_planner = [], {}, {}
    kw = dict(budget_s=pc.budget_s, resolution=pc.resolution, recheck_resolution=pc.recheck_resolution,
              clearance_resolution=pc.clearance_resolution, simplify_s=pc.simplify_s,
              max_velocity=pc.max_velocity, max_acceleration=pc.max_acceleration, chain=chain)
    for planner in pc.planners:
        results = []
        for src, dst in edges:
            r = P.plan_edge(scene, checker, targets, src, dst, planner, **kw)
            results.append(r)
            rows.append(r.row())
            log.info("%s %d->%d success=%s revalidated=%s %.3f s", planner, src, dst, r.success, r.revalidated,
                     r.plan.planning_time_s)
        by_planner[planner] = results
        mats = P.metric_matrices(scene, results)
        (out / f"metrics_{planner}.json").write_text(json.dumps(
            {k: np.where(np.isnan(v), None, v).tolist() for k, v in mats.items()}))
        C = P.cost_matrix(mats, dict(pc.weights))
        np.savetxt(out / f"cost_{planner}.csv", C, delimiter=",", fmt="%.6g")
        times = np.array([r.plan.planning_time_s for r in results])
        summary[planner] = {
            "edges": len(results), "success": int(sum(r.success for r in results)),
            "revalidated": int(sum(r.revalidated for r in results)),
            "median_planning_time_s": float(np.median(times)), "max_planning_time_s": float(times.max()),
            "max_speed_ratio": float(max((r.check.get("max_speed_ratio", 0.0) for r in results), default=0.0)),
        }
        log.info("%s: %s", planner, summary[planner])
        _plot_paths(scene, chain, results, targets, out / f"ee_paths_{planner}.png")
    _edge_rows_csv(out / "edges.csv", rows)
    jp = pc.plan_json
    if jp.planner in by_planner:
        emap = {(r.src, r.dst): r for r in by_planner[jp.planner]}
        plan_obj = P.plan_json(scene, targets, emap, list(jp.sequence), jaws_open_mm=jp.jaws_open_mm,
                               jaws_closed_mm=jp.jaws_closed_mm, max_velocity=pc.max_velocity,
                               max_acceleration=pc.max_acceleration, checker=checker)
        (out / "plan.json").write_text(json.dumps(plan_obj, indent=1))
        check = hw.check_plan(hw.parse_plan(plan_obj))
        summary["plan_json"] = {"segments": check.n_segments, "estimated_s": check.estimated_s}
        _plot_joints(plan_obj, out / "joints.png")
    summary["frames"] = _render(scene, targets, out) if cfg.plan.render else 0
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    log.info("outputs in %s", out)
    return summary


if __name__ == "__main__":
    main()
