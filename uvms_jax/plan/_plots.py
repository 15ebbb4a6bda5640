"""Figures of the planning stage: end-effector paths, plan joint curves, rendered frames.

matplotlib is imported inside each function with the Agg backend (files only, no display).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from uvms_jax import kin, planfile
from uvms_jax.plan._collision import densify
from uvms_jax.plan._scene import Scene
from uvms_jax.plan._targets import NodeTarget
from uvms_jax.plan._tasks import EdgeResult
from uvms_jax.plan._video import scene_camera
from uvms_jax.plotting import pyplot, save_figure

__all__ = ["plot_ee_paths", "plot_plan_joints", "render_frames"]

log = logging.getLogger(__name__)

_EE_PATH_STEP = 0.02  # [rad] interpolation step of the drawn paths: smooth curves, few points


def plot_ee_paths(scene: Scene, results: Sequence[EdgeResult], path: Path) -> None:
    """End-effector paths of every planned edge over the scene (3-D and top view), world frame;
    colour = the edge's place in the task graph (colour bar), the arm base marked.

    All densified paths go through one ``kin.fk`` call: one XLA compilation, not one per path
    length."""
    plt = pyplot()
    from matplotlib.lines import Line2D
    from matplotlib.ticker import MaxNLocator

    chain = scene.robot.chain
    ok = [r for r in results if r.success]
    dense = [np.asarray(densify(r.plan.path, _EE_PATH_STEP)) for r in ok]
    p_all = np.asarray(kin.fk(chain, np.concatenate(dense)))[:, :, 3] if dense else np.zeros((0, 4))
    p_world = (scene.T_world_base @ p_all.T).T[:, :3]
    fig = plt.figure(figsize=(14, 6.2), layout="constrained")
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
        color = "tab:orange" if node in scene.objects else "tab:red"
        ax3.scatter(*T[:3, 3], color=color, s=25)
        ax2.scatter(*T[:2, 3], color=color, s=25)
        ax2.annotate(str(node), T[:2, 3], textcoords="offset points", xytext=(4, 4))
    base = scene.T_world_base[:3, 3]
    ax3.scatter(*base, marker="^", s=90, color="k")
    ax3.text(*base, "  arm base", fontsize=9)
    ax2.scatter(*base[:2], marker="^", s=90, color="k")
    ax2.annotate("arm base", base[:2], textcoords="offset points", xytext=(6, -12))
    cmap = plt.get_cmap("viridis")
    n = max(1, len(dense))
    bounds = np.cumsum([0] + [len(d) for d in dense])
    for i, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
        color = cmap(i / max(1, n - 1))
        ax3.plot(*p_world[a:b].T, color=color, lw=0.8)
        ax2.plot(p_world[a:b, 0], p_world[a:b, 1], color=color, lw=0.8)
    name = results[0].planner if results else ""
    ax3.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]", title=f"{name}: end-effector paths ({len(ok)} edges)")
    ax2.set(xlabel="x [m]", ylabel="y [m]", title="top view (node numbers)", aspect="equal")
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0, n - 1))
    cb = fig.colorbar(sm, ax=ax2, label="edge (task-graph order)", shrink=0.8)
    cb.locator = MaxNLocator(integer=True)
    cb.update_ticks()
    handles = [Line2D([], [], marker="^", color="k", ls="", label="arm base"),
               Line2D([], [], marker="o", color="tab:orange", ls="", label="object (start)"),
               Line2D([], [], marker="o", color="tab:red", ls="", label="base plate"),
               Line2D([], [], color="0.5", label="table top")]
    fig.legend(handles=handles, loc="outside lower center", ncol=4)
    save_figure(fig, path, dpi=110)


def plot_plan_joints(plan: planfile.Plan, path: Path) -> None:
    """Joint angles [rad] of a plan's waypoints over time [s], segments one after another."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(12, 4.5), layout="constrained")
    t0, ts, qs = 0.0, [], []
    for seg in plan.segments:
        if seg.t:
            ts.append(np.asarray(seg.t) + t0)
            qs.append(np.asarray(seg.q))
            t0 = ts[-1][-1]
    if not ts:
        raise ValueError("the plan has no motion segment to plot")
    t, q = np.concatenate(ts), np.concatenate(qs)
    for j, name in enumerate(plan.joint_names):
        ax.plot(t, q[:, j], marker=".", ms=3, label=name)
    ax.set(xlabel="time [s] (waypoints; synchronised rest-to-rest legs)", ylabel="joint angle [rad]",
           title="plan.json joint waypoints")
    fig.legend(title="joint", loc="outside right upper")  # beside the axes, off the curves
    save_figure(fig, path, dpi=110)


def render_frame(scene: Scene, q, path: Path) -> bool:
    """One offscreen frame of the scene with the arm at ``q (6,)`` [rad] into ``path`` (PNG);
    False where no GL context exists."""
    try:
        import mujoco

        m = scene.model
        d = mujoco.MjData(m)
        renderer = mujoco.Renderer(m, 480, 640)
    except Exception as e:  # no EGL/OSMesa/GLFW context on this machine
        log.warning("offscreen rendering unavailable (%s); no frame", e)
        return False
    d.qpos[:] = q
    mujoco.mj_forward(m, d)
    renderer.update_scene(d, scene_camera(scene))
    pyplot().imsave(path, renderer.render())
    renderer.close()
    return True


def render_frames(scene: Scene, targets: Mapping[int, NodeTarget], out_dir: Path) -> int:
    """Offscreen frames ``frame_start.png`` and ``frame_node<n>.png`` (each node's grasp/final
    configuration) into ``out_dir``; returns how many were written, 0 where no GL context
    exists (set ``MUJOCO_GL`` before MuJoCo is first imported to choose the backend)."""
    frames = [("start", np.asarray(scene.start_q))] + [(f"node{n}", t.q_at) for n, t in targets.items()]
    return sum(render_frame(scene, q, out_dir / f"frame_{name}.png") for name, q in frames)
