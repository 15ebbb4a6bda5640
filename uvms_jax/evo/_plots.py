"""Figures of the docking run (matplotlib imported lazily, Agg backend)."""

from __future__ import annotations

from pathlib import Path

import jax.numpy as jnp
import numpy as np

from uvms_jax import kin
from uvms_jax.evo._collide import link_points
from uvms_jax.evo._problem import base_transform
from uvms_jax.evo._wmax import WmaxMap
from uvms_jax.plotting import pyplot, save_figure


def plot_wmax(m: WmaxMap, title: str, path: Path, vmax: float) -> None:
    """Heat map of ``w_max`` (eq. 16) over the task area, zero-w area shaded red, to ``path``."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5, 4.2))
    im = ax.pcolormesh(m.x, m.y, m.w_max.T, shading="nearest", cmap="viridis", vmin=0.0, vmax=vmax)
    zero = np.ma.masked_where(m.w_max.T > 0, np.ones_like(m.w_max.T))
    ax.pcolormesh(m.x, m.y, zero, shading="nearest", cmap="Reds", vmin=0, vmax=1.5, alpha=0.6)
    fig.colorbar(im, ax=ax, label="$w_{max}$ (eq. 16)")
    ax.set(xlabel="x in G [m]", ylabel="y in G [m]", title=f"{title}\nzero-w area {100 * m.zero_fraction:.1f} %")
    ax.set_aspect("equal")
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def plot_convergence(ga_hist, cma_hist, references: dict[str, float], path: Path) -> None:
    """Best fitness per generation of every GA (and CMA-ES) run, with reference lines."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for i, h in enumerate(ga_hist):
        ax.plot(np.arange(1, len(h) + 1), h, color="C0", alpha=0.8, label="GA runs" if i == 0 else None)
    for i, h in enumerate(cma_hist):
        ax.plot(np.arange(1, len(h) + 1), h, color="C1", alpha=0.6, label="CMA-ES runs" if i == 0 else None)
    for (name, f), ls in zip(references.items(), ("--", ":")):
        ax.axhline(f, color="k", ls=ls, label=name)
    top = max(references.values())
    finite = [v for h in list(ga_hist) + list(cma_hist) for v in np.asarray(h)[np.isfinite(h)]]
    lo = np.percentile(finite, 5) if finite else top - 1
    ax.set_ylim(min(lo, top - 0.5), top + 0.1 * abs(top - lo) + 0.05)
    ax.set(xlabel="generation", ylabel="best fitness (eq. 15)", title="Docking optimisation: convergence")
    ax.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
    ax.legend(loc="lower right")
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def _footprint(T: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Outline ``(m, 2)`` in x-y of a box ``T (4, 4), half (3,)`` seen from above."""
    from scipy.spatial import ConvexHull

    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    xy = (corners @ T[:3, :3].T + T[:3, 3])[:, :2]
    return xy[ConvexHull(xy).vertices]


def plot_docked_top_view(problem, pose, q, ok, w, path: Path, margin: float = 0.3) -> None:
    """Top view (world x-y) of an arm docked at vehicle pose ``(4,)``: scene boxes, vehicle
    body, arm base, and per target its best alternative tool pose with the arm in its best
    solution (from ``q (k, n)`` NaN where none, ``ok (k,)``, ``w (k,)`` per demanded tool pose),
    coloured by w (crosses: no valid solution). The view spans the vehicle, the arm and the
    targets plus ``margin`` [m]."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 6.5), layout="constrained")
    pose = np.asarray(pose, dtype=float)
    T_wv = np.asarray(base_transform(jnp.asarray(pose, dtype=jnp.float32)), dtype=float)
    T_wb = T_wv @ np.asarray(problem.T_vehicle_base, dtype=float)
    T_box, half = np.asarray(problem.T_world_box, float), np.asarray(problem.scene_half, float)
    tops = np.array([np.max((np.abs(T[2, :3]) * h).sum() + T[2, 3]) for T, h in zip(T_box, half)])
    shade = np.linspace(0.9, 0.6, len(tops)) if len(tops) > 1 else [0.75]
    for i, j in enumerate(np.argsort(tops)):  # lowest first: higher boxes are drawn over lower ones
        xy = _footprint(T_box[j], half[j])
        ax.fill(xy[:, 0], xy[:, 1], color=str(shade[i]), ec="0.3", lw=0.8, zorder=0,
                label="scene boxes (darker: higher top)" if i == 0 else None)
    hull = []
    for i, (T, h) in enumerate(zip(np.asarray(problem.T_vehicle_box, float), np.asarray(problem.vehicle_half, float))):
        xy = _footprint(T_wv @ T, h)
        hull.append(xy)
        ax.fill(xy[:, 0], xy[:, 1], color="C0", alpha=0.25, ec="C0", lw=1.2, zorder=1,
                label="vehicle" if i == 0 else None)
    ax.annotate("", xy=T_wv[:2, 3] + 0.3 * T_wv[:2, 0], xytext=T_wv[:2, 3],
                arrowprops=dict(arrowstyle="->", color="C0", lw=1.5), zorder=3)
    ax.plot(*T_wv[:2, 3], "o", color="C0", ms=5, zorder=3, label="vehicle frame V (arrow: heading)")
    # One marker and one arm per target: its best alternative pose (all alternatives failed: a cross).
    group = np.asarray(problem.group)
    best = np.array([np.flatnonzero(group == g)[np.argmax(w[group == g])] for g in range(problem.n_groups)])
    q, ok, w = q[best], ok[best], w[best]
    chain = problem.chain
    arm = []
    for qi, o in zip(q, ok):
        if not o:
            continue
        K = kin.kinematics(chain, jnp.asarray(qi, dtype=jnp.float32))
        pts = np.asarray(link_points(jnp.asarray(T_wb, jnp.float32), K.T_base_joint, K.T_base_tool))
        arm.append(pts[:, :2])
        ax.plot(pts[:, 0], pts[:, 1], "-", color="0.25", lw=1.0, alpha=0.7, zorder=2,
                label="arm links, best IK per target" if len(arm) == 1 else None)
    targets = np.asarray(problem.T_world_tool, dtype=float)[best, :3, 3]
    sc = ax.scatter(targets[ok, 0], targets[ok, 1], c=w[ok], cmap="viridis", s=45, ec="k", zorder=4,
                    vmin=0.0, vmax=max(float(np.max(w)), 1e-9), label="targets (best tool pose)")
    if np.any(~ok):
        ax.scatter(targets[~ok, 0], targets[~ok, 1], marker="x", color="C3", s=50, zorder=4,
                   label="target without valid IK")
    fig.colorbar(sc, ax=ax, label="w at the target, best valid IK (6×6 Jacobian)")
    ax.plot(*T_wb[:2, 3], "s", color="C1", ms=9, zorder=5, label="arm base")
    ax.annotate("arm base", T_wb[:2, 3], textcoords="offset points", xytext=(-10, 10), ha="right", color="C1",
                fontweight="bold", zorder=6)
    seen = np.concatenate([targets[:, :2], *hull, *arm, T_wb[None, :2, 3]])
    lo, hi = seen.min(axis=0) - margin, seen.max(axis=0) + margin
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]))
    ax.set_aspect("equal")
    ax.set(xlabel="x in W [m]", ylabel="y in W [m]",
           title=f"Docked vehicle pose (top view)\nx = {pose[0]:.3f} m, y = {pose[1]:.3f} m, "
                 f"z = {pose[2]:.3f} m, ψ = {np.degrees(pose[3]):.1f}°")
    fig.legend(loc="outside lower center", ncols=2, fontsize=8)
    save_figure(fig, path, dpi=120)
