"""The docking paper [D11] drawn under our model: the arm at the control points K, L, M, N of a
docking pose, in 3-D (Figs 5–8) and from the side (Figs 12–15), and the final docking pose on
the block (Fig. 11).

Each figure shows the paper's run 1 (Table 3), with the configurations of its Table 4 as printed
and with θ2, θ3, θ5 negated (the reading under which they fit our frames, docs/reproduction.md
§1), our IK at that pose (the branch of largest w per corner), and our optimum of eq. 15 over the
face grid with our IK. Frames and arm as in :mod:`uvms_jax.papers.docking`.
"""

from __future__ import annotations

import time
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from uvms_jax import evo, indices, kin
from uvms_jax.papers._data import D11_BLOCK_SIZE, D11_P_BP, D11_TABLE3, D11_TABLE4, D11_TASK_SIZE
from uvms_jax.papers._preset import Preset, join_and, save_figure
from uvms_jax.papers.docking import CORNER_OF, READINGS, distance_d, grid_optimum, ik_branches
from uvms_jax.plotting import pyplot
from uvms_jax.text import md_table

#: Drawn length of the approach axis (tool x), ending at the tool point [m]: a drawing choice, so
#: the tool's orientation shows (the tool point is the wrist centre, the arm has no tool length).
GRIPPER = 0.1
#: A wrist centre within this distance of its corner reaches it [m] (IK's own check is tighter).
REACHED = 1e-3
POINTS = "KLMN"
#: Matlab's default 3-D view (the paper draws its arm with Matlab's Robotics Toolbox) [deg].
VIEW = dict(elev=30.0, azim=-37.5)


def corners() -> np.ndarray:
    """The corners K, L, M, N of the task area in G, ``(4, 3)`` [m]."""
    return indices.control_points((0.0, 0.0, 0.0), D11_TASK_SIZE, 2)[[CORNER_OF[k] for k in POINTS]]


def arm_polyline(pose, q) -> np.ndarray:
    """The arm at base pose ``(4,)`` and joints ``q (6,)`` [rad] as points in G ``(5, 3)`` [m]:
    base, shoulder, elbow, wrist centre and the start of the approach axis drawn to it
    (:data:`GRIPPER` before the tool point). The joint frames of ``kin.docking_arm`` 2 and 3 sit at the shoulder and the elbow."""
    arm = kin.docking_arm(*READINGS[0].lengths)
    k = kin.kinematics(arm, jnp.asarray(q, jnp.float32))
    T = np.asarray(k.T_base_tool, np.float64)
    joints = np.asarray(k.T_base_joint, np.float64)[1:3, :3, 3]
    pts = np.concatenate([np.zeros((1, 3)), joints, T[None, :3, 3], T[None, :3, 3] - GRIPPER * T[None, :3, 0]])
    T_G_B = np.asarray(evo.base_transform(jnp.asarray(pose, jnp.float32)), np.float64)
    return pts @ T_G_B[:3, :3].T + T_G_B[:3, 3]


def our_arms(pose) -> tuple[np.ndarray, np.ndarray]:
    """Our IK at K, L, M, N from base pose ``(4,)``: the branch of largest w per corner,
    ``q (4, 6)`` [rad] (NaN where no branch reaches) and its ``w (4,)`` (0 there)."""
    q, valid, w = (np.asarray(a, np.float64) for a in ik_branches(READINGS[0], np.asarray(pose)[None], corners()))
    q, valid, w = q[0], valid[0].astype(bool), np.where(valid[0], w[0], -1.0)
    best = np.argmax(w, axis=-1)
    ok = valid[np.arange(4), best]
    return np.where(ok[:, None], q[np.arange(4), best], np.nan), np.where(ok, w[np.arange(4), best], 0.0)


def views(ours) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The drawn cases: label → (base pose ``(4,)``, joints ``q (4, 6)`` at K, L, M, N, NaN
    where the corner is not reached)."""
    run1 = D11_TABLE3[0, :4]
    table4 = np.array([D11_TABLE4[k] for k in POINTS], np.float64)
    return {
        "paper run 1, Table 4 as printed": (run1, table4),
        "paper run 1, Table 4 with θ2, θ3, θ5 negated": (run1, table4 * np.array([1, -1, -1, 1, -1, 1])),
        "paper run 1, our IK": (run1, our_arms(run1)[0]),
        "our optimum, our IK": (np.asarray(ours, np.float64), our_arms(ours)[0]),
    }


def _draw_arm(ax, pts: np.ndarray, colour, side: tuple | None) -> None:
    """One arm polyline (``(5, 3)`` in G) on a 3-D axes, or projected on a side view ``(origin, u)``."""
    if side is None:
        ax.plot(*pts[:4].T, "o-", color=colour, lw=2.2, ms=4)
        ax.quiver(*pts[4], *(pts[3] - pts[4]), color="k", lw=2, arrow_length_ratio=0.4)
        return
    o, u = side
    s = (pts[:, :2] - o) @ u
    ax.plot(s[:4], pts[:4, 2], "o-", color=colour, lw=2.2, ms=4)
    ax.annotate("", xy=(s[3], pts[3, 2]), xytext=(s[4], pts[4, 2]), arrowprops=dict(arrowstyle="-|>", color="k", lw=2))


def plot_arm_views(cases: dict, img: Path, side: bool) -> str:
    """[D11] Figs 5–8 (``side`` False: 3-D) or 12–15 (True: the vertical plane through the base
    and the task centre): one row per case of :func:`views`, one column per corner → PNG path."""
    plt = pyplot()
    fig = plt.figure(figsize=(15, 3.6 * len(cases)), layout="constrained")
    square = corners()[[0, 1, 2, 3, 0]]
    for r, (label, (pose, q)) in enumerate(cases.items()):
        base = np.asarray(pose[:2], np.float64)
        u = -base / np.linalg.norm(base)  # towards the task centre
        for c, k in enumerate(POINTS):
            i = r * 4 + c + 1
            ax = fig.add_subplot(len(cases), 4, i, **({} if side else {"projection": "3d"}))
            target = corners()[c]
            if side:
                ax.axhspan(-0.3, 0.0, color="0.85", zorder=0)
                ax.plot((target[:2] - base) @ u, 0.0, "*", color="C3", ms=12)
                ax.set(xlim=(-0.15, 1.1), ylim=(-0.3, 0.9), xlabel="along base → task centre [m]", ylabel="z in G [m]")
                ax.set_aspect("equal")
            else:
                ax.plot(*square.T, "-", color="0.5", lw=1)
                ax.scatter(*target, marker="*", color="C3", s=120)
                ax.set(xlim=(-0.7, 0.3), ylim=(-0.7, 0.3), zlim=(-0.1, 0.9), xlabel="x [m]", ylabel="y [m]", zlabel="z [m]")
                ax.view_init(**VIEW)
            reached = not np.any(np.isnan(q[c]))
            if reached:
                pts = arm_polyline(pose, q[c])
                _draw_arm(ax, pts, f"C{c}", (base, u) if side else None)
                gap = np.linalg.norm(pts[3] - target)
                title = f"{k}: wrist {'on the corner' if gap < REACHED else f'{gap:.2f} m from it'}"
            else:
                title = f"{k}: no IK branch reaches it"
            ax.set_title(f"{label}\n{title}" if c == 0 else title, fontsize=9, loc="left")
    name = "docking_arm_side.png" if side else "docking_arm_3d.png"
    return save_figure(fig, img, name)


def plot_final_pose(poses: dict, img: Path) -> str:
    """[D11] Fig. 11: each base pose ``(4,)`` on the block: docking point (yellow), manipulator
    base (red), its projection on the top face (blue), task area and heading → PNG path."""
    plt = pyplot()
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    fig = plt.figure(figsize=(6.5 * len(poses), 6.5), layout="constrained")
    hx, hy, hz = np.asarray(D11_BLOCK_SIZE) / 2
    edges = [((sx * hx, sy * hy, 0.0), (sx * hx, sy * hy, -2 * hz)) for sx in (-1, 1) for sy in (-1, 1)]
    for z in (0.0, -2 * hz):
        rim = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy], [-hx, -hy]])
        edges += [((*a, z), (*b, z)) for a, b in zip(rim[:-1], rim[1:])]
    square = corners()[[0, 1, 2, 3, 0]]
    top = np.array([[-hx, -hy, 0.0], [hx, -hy, 0.0], [hx, hy, 0.0], [-hx, hy, 0.0]])
    for i, (label, pose) in enumerate(poses.items()):
        ax = fig.add_subplot(1, len(poses), i + 1, projection="3d")
        for a, b in edges:
            ax.plot(*np.array([a, b]).T, color="0.3", lw=1.0)
        ax.add_collection3d(Poly3DCollection([top], color="0.7", alpha=0.3))
        ax.plot(*square.T, "-", color="C2", lw=1.5, label="task area K, L, M, N")
        pose = np.asarray(pose, np.float64)
        T = np.asarray(evo.base_transform(jnp.asarray(pose, jnp.float32)), np.float64)
        p_d = _docking_point(pose)
        ax.scatter(*p_d, color="gold", s=70, ec="k", label="docking point p_d")
        ax.scatter(*pose[:3], color="red", s=60, ec="k", label="manipulator base")
        ax.scatter(pose[0], pose[1], 0.0, color="blue", s=50, ec="k", label="base projected on the top face")
        ax.quiver(*pose[:3], *(0.4 * T[:3, 0]), color="red", lw=1.5, arrow_length_ratio=0.2)
        ax.set(xlim=(-hx, hx), ylim=(-hy, hy), zlim=(-2 * hz, 0.5), xlabel="x in G [m]", ylabel="y in G [m]",
               zlabel="z in G [m]")
        ax.set_title(f"{label}: ({pose[0]:.2f}, {pose[1]:.2f}, {pose[2]:.2f}) m, ψ = {np.degrees(pose[3]):.0f}°, "
                     f"D = {distance_d(pose[None])[0]:.2f} m", fontsize=9)
        ax.set_box_aspect((2 * hx, 2 * hy, 2 * hz + 0.5))
        ax.view_init(**VIEW)
        ax.legend(loc="upper left", fontsize=8)
    return save_figure(fig, img, "docking_final_pose.png")


def _docking_point(pose) -> np.ndarray:
    """[D11] eq. 5: the docking point ``p_d (3,)`` in G [m] of base pose ``(4,)``."""
    pose = jnp.asarray(pose, jnp.float32)
    return np.asarray(evo.docking_point(pose, jnp.asarray(D11_P_BP, jnp.float32)), np.float64)


def reach_table(cases: dict) -> str:
    """Per case and corner: w of our 6 × 6 Jacobian where the wrist centre is on the corner, else
    how far from it it is, or that no branch reaches it (Markdown)."""
    arm, rows = kin.docking_arm(*READINGS[0].lengths), []
    for label, (pose, q) in cases.items():
        cells = []
        for c in range(4):
            if np.any(np.isnan(q[c])):
                cells.append("not reached")
                continue
            gap = np.linalg.norm(arm_polyline(pose, q[c])[3] - corners()[c])
            w = float(indices.manipulability(kin.jacobian(arm, jnp.asarray(q[c], jnp.float32))))
            cells.append(f"w {w:.3f}" if gap < REACHED else f"{gap:.3f} m off (w {w:.3f})")
        rows.append([label] + cells)
    return md_table(["case", *POINTS], rows)


def view_fields(p: Preset, img: Path) -> dict:
    """The fields of the views' template (experiments/papers_templates/docking_views.md)."""
    t0 = time.perf_counter()
    _, ours = grid_optimum(p)
    cases = views(ours)
    missed = [k for k, q in zip(POINTS, cases["paper run 1, our IK"][1]) if np.any(np.isnan(q))]
    return dict(
        seconds=time.perf_counter() - t0, preset=p.name, ours_x=float(ours[0]), ours_y=float(ours[1]),
        ours_z=float(ours[2]), ours_psi_deg=float(np.degrees(ours[3])), reach=reach_table(cases),
        run1_missed=join_and(missed) or "none", ours_pd_z=float(_docking_point(ours)[2]),
        fig_arm=plot_arm_views(cases, img, side=False), fig_side=plot_arm_views(cases, img, side=True),
        fig_final=plot_final_pose({"paper run 1": D11_TABLE3[0, :4], "our optimum": ours}, img),
    )
