"""The docking paper [D11] under our model: Tables 3–4, the bound on w, readings, Figs 9–10.

Frames and symbols as in docs/theory.md §3: G at the centre of the block's top face, a base
pose ``(x, y, z [m], ψ [rad])`` of the arm base B in G, the arm of theory §1.1. The scene's
paper values come from :mod:`uvms_jax.papers._data`; the values the paper leaves open (margin
d, eq. 8 weights a, b) are our defaults, :class:`uvms_jax.evo.SceneSettings`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from uvms_jax import evo, indices, kin, progress
from uvms_jax.papers._data import D11_ARM_LENGTHS, D11_BLOCK_SIZE, D11_ILL_PLACED_POSE, D11_P_BP, D11_P_INIT
from uvms_jax.papers._data import D11_TABLE3, D11_TABLE4, D11_TASK_SIZE
from uvms_jax.papers._preset import Preset, join_and, save_figure
from uvms_jax.plotting import pyplot
from uvms_jax.text import md_table

log = logging.getLogger(__name__)
DEG = math.pi / 180.0
SCENE = evo.SceneSettings()  # our margin d and eq. 8 weights a, b (configs/docking/scene/paper.yaml)


@dataclasses.dataclass(frozen=True)
class Reading:
    """One reading of the paper's arm and index: link lengths, tool offset beyond the wrist
    centre along the approach axis [m], Jacobian rows (6: full, 3: positional) and task size [m]."""

    label: str
    lengths: tuple[float, float, float] = D11_ARM_LENGTHS
    tool_offset: float = 0.0
    rows: int = 6
    task_size: float = D11_TASK_SIZE


READINGS = (
    Reading("ours: tool = wrist centre, 6 × 6 geometric J"),
    Reading("tool 0.1 m beyond the wrist, 6 × 6", tool_offset=0.1),
    Reading("tool 0.2 m beyond the wrist, 6 × 6", tool_offset=0.2),
    Reading("positional 3 × 6 J at the wrist centre", rows=3),
    Reading("positional 3 × 6 J, point 0.55 m beyond the wrist", tool_offset=0.55, rows=3),
    Reading("positional 3 × 6 J, point 0.60 m beyond the wrist", tool_offset=0.60, rows=3),
    Reading("positional 3 × 6 J, point 0.65 m beyond the wrist", tool_offset=0.65, rows=3),
    Reading("links l1 = l2 = 0.5 m, 6 × 6", lengths=(0.1, 0.5, 0.5)),
    Reading("task area 0.2 m, 6 × 6", task_size=0.2),
)
#: A reading gives M_a "of the paper's size" from this share of the paper's smallest M_a (Table 3) up.
PAPER_SIZED = 0.75

#: Corner of the task area each Table 4 configuration reaches (nearest corner of its wrist
#: centre when θ2, θ3, θ5 are mirrored, see the section): index into ``control_points(…, 2)``,
#: whose order is (−,−), (−,+), (+,−), (+,+).
CORNER_OF = {"K": 0, "L": 1, "M": 3, "N": 2}


def offset_chain(arm: kin.Chain, offset: float) -> kin.Chain:
    """The arm with its tool point ``offset`` [m] beyond the wrist centre along the tool x
    axis (the approach axis of ``indices.approach_down``)."""
    T = np.array(arm.T_base_tool0, dtype=np.float64)
    T[:3, 3] += offset * T[:3, 0]
    return kin.make_chain(twists=np.asarray(arm.twists), T_base_tool0=T, lower=np.asarray(arm.lower),
                          upper=np.asarray(arm.upper), kinds=arm.kinds, name=f"{arm.name}+{offset:g}")


def w_max_at(reading: Reading, poses, points) -> jax.Array:
    """``w_max`` ([D11] eq. 16) of ``reading`` at control points ``(k, 3)`` [m] in G from base
    poses ``(..., 4)``: ``(..., k)``; 0 where no IK branch is valid. The tool points down with
    its z axis along the pose's heading (our default)."""
    _, valid, w = ik_branches(reading, poses, points)
    return jnp.max(jnp.where(valid, w, 0.0), axis=-1)


def ik_branches(reading: Reading, poses, points) -> tuple[jax.Array, jax.Array, jax.Array]:
    """The arm's IK branches at control points ``(k, 3)`` [m] in G from base poses ``(..., 4)``
    (tool as in :func:`w_max_at`): joint angles ``q (..., k, 8, 6)`` [rad] (0 on branches that
    do not exist), ``valid (..., k, 8)`` (the branch exists and reaches its point) and
    ``w (..., k, 8)`` of ``reading``'s Jacobian."""
    arm = kin.docking_arm(*reading.lengths)
    tool = offset_chain(arm, reading.tool_offset)
    poses = jnp.asarray(poses, jnp.float32)
    # The wrist centre sits ``tool_offset`` above the tool point (approach axis = −z of G).
    wrist_points = jnp.asarray(points, jnp.float32) + jnp.array([0.0, 0.0, reading.tool_offset], jnp.float32)
    R = indices.approach_down(poses[..., 3])[..., None, :, :]
    T = indices.tool_targets(evo.base_transform(poses), wrist_points, R)  # (..., k, 4, 4) wrist targets in B
    ik = kin.elbow_ik(arm, T)  # q (..., k, 8, 6); NaN on branches that do not exist
    q = jnp.where(ik.valid[..., None], ik.q, 0.0)
    valid = ik.valid & kin.reaches(T[..., None, :, :], kin.fk(arm, q))
    J = kin.jacobian(tool, q)[..., : reading.rows, :]
    return q, valid, indices.manipulability(J)


def area_m(reading: Reading, poses, chunk: int = 4096) -> np.ndarray:
    """``M_a`` ([D11] eq. 1, four corners) of ``reading`` at base poses ``(n, 4)``: ``(n,)``,
    evaluated ``chunk`` poses at a time."""
    corners = indices.control_points((0.0, 0.0, 0.0), reading.task_size, 2)
    poses = np.asarray(poses, np.float32).reshape(-1, 4)
    out = [np.asarray(jnp.min(w_max_at(reading, poses[i:i + chunk], corners), axis=-1))
           for i in range(0, len(poses), chunk)]
    return np.concatenate(out)


def face_grid(p: Preset) -> np.ndarray:
    """Base poses ``(n, 4)`` over the quarter of the top face nearest p_init, outside the task
    area ([D11] eq. 14), z in the margin d [m], ψ in [0, π/2] [rad]."""
    xs = np.arange(-D11_BLOCK_SIZE[0] / 2, 1e-9, p.face_step)
    zs = np.linspace(0.0, SCENE.d, p.z_values)
    psis = np.linspace(0.0, math.pi / 2, p.psi_values)
    g = np.stack(np.meshgrid(xs, xs, zs, psis, indexing="ij"), -1).reshape(-1, 4)
    half = D11_TASK_SIZE / 2
    return g[~((np.abs(g[:, 0]) < half) & (np.abs(g[:, 1]) < half))]


def grid_optimum(p: Preset) -> tuple[np.ndarray, np.ndarray]:
    """Our optimum of eq. 15 over :func:`face_grid` (the GA of experiments/docking.py finds the
    same apex): the grid ``(n, 4)`` and its best pose ``(4,)`` [m, rad]."""
    t0 = time.perf_counter()
    grid = face_grid(p)
    m_grid = area_m(READINGS[0], grid)
    ours = grid[np.argmax(fitness(m_grid, grid))]
    log.info("docking: %d grid poses, best %s (M_a %.4f) in %.1f s", len(grid), ours, m_grid.max(),
             time.perf_counter() - t0)
    return grid, ours


def distance_d(poses) -> np.ndarray:
    """[D11] eq. 3: distance from p_init to the docking point ``T_G_B · p_bp`` of each base
    pose ``(n, 4)``: ``(n,)`` [m], in float64 (``evo`` computes it in the run's dtype)."""
    poses = np.asarray(poses, np.float64)
    c, s = np.cos(poses[:, 3]), np.sin(poses[:, 3])
    bx, by, bz = D11_P_BP
    p_d = poses[:, :3] + np.stack([c * bx - s * by, s * bx + c * by, np.full_like(c, bz)], -1)
    return np.linalg.norm(p_d - np.asarray(D11_P_INIT), axis=-1)


def heading_offset(poses) -> np.ndarray:
    """Angle between each pose's heading ψ and its bearing to the task centre, poses ``(n, 4)``:
    ``(n,)`` [deg]."""
    poses = np.asarray(poses, np.float64)
    bearing = np.arctan2(-poses[:, 1], -poses[:, 0])
    return np.abs((poses[:, 3] - bearing + math.pi) % (2 * math.pi) - math.pi) / DEG


def facing_centre(poses) -> np.ndarray:
    """The poses ``(n, 4)`` with ψ turned to the bearing from each pose to the task centre."""
    poses = np.array(poses, np.float64)
    poses[:, 3] = np.arctan2(-poses[:, 1], -poses[:, 0])
    return poses


def ga_runs(n_runs: int = 7, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Our GA as the paper runs it (:class:`uvms_jax.evo.GASettings`' defaults, the paper's
    Table 2, as configs/ga/paper.yaml) on eq. 15 of our scene, ``n_runs`` runs in one call:
    best poses ``(n_runs, 4)`` and their fitness ``(n_runs,)``."""
    problem = evo.docking_problem(SCENE)
    codec, ga, params = evo.make_ga(evo.GASettings(), problem)
    res = evo.run_ga_batch(jax.random.split(jax.random.key(seed), n_runs), problem, codec, ga, params)
    return np.asarray(res.best_x, np.float64), np.asarray(res.best_fitness, np.float64)


def fitness(m_a, poses) -> np.ndarray:
    """[D11] eq. 15 inside Wd: ``a · M_a − b · D`` of ``M_a (n,)`` at poses ``(n, 4)``: ``(n,)``."""
    return SCENE.a * np.asarray(m_a) - SCENE.b * distance_d(poses)


def w_bound(p: Preset) -> tuple[float, tuple[float, float, float]]:
    """Largest w of the 6 × 6 geometric Jacobian of the [D11] arm within its joint limits, and
    where: ``(w, (θ2, θ3, θ5) [rad])``.

    w does not depend on θ1 (a rotation of the base), θ4 and θ6 (the wrist axes meet at the
    tool point): a grid of ``p.bound_n`` points per joint over θ2, θ3, θ5 refined by
    Nelder–Mead (scipy)."""
    from scipy.optimize import minimize

    arm = kin.docking_arm()
    lo, hi = np.asarray(arm.lower, np.float64), np.asarray(arm.upper, np.float64)
    axes = [np.linspace(lo[i], hi[i], p.bound_n) for i in (1, 2, 4)]
    g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    q = np.zeros((len(g), 6), np.float32)
    q[:, [1, 2, 4]] = g
    w = np.asarray(indices.manipulability_of(arm, q))
    best = g[np.argmax(w)]

    def neg(x):
        qq = np.zeros(6)
        qq[[1, 2, 4]] = np.clip(x, lo[[1, 2, 4]], hi[[1, 2, 4]])
        return -float(indices.manipulability(jnp.asarray(kin.jacobian(arm, qq.astype(np.float32)))))

    res = minimize(neg, best, method="Nelder-Mead", options={"xatol": 1e-6, "fatol": 1e-9})
    return -float(res.fun), tuple(float(v) for v in res.x)


def table4_rows(arm: kin.Chain) -> tuple[list[list], dict]:
    """FK of the Table 4 configurations under our frames, as given and with θ2, θ3, θ5 negated
    (the paper's y axes reversed), placed at Table 3's run-1 pose.

    Returns the table rows (reading, point, wrist centre in G, corner, distance [m], wrist −
    shoulder height [m], approach axis z) and the facts quoted: ``p`` (reading, point) → wrist
    centre ``(3,)`` in B [m], ``LM`` and ``MN`` distances [m], ``sum235`` ``(4,)`` θ2 + θ3 + θ5
    [rad] per point."""
    q = np.array([D11_TABLE4[k] for k in "KLMN"], np.float32)
    T_G_B = np.asarray(evo.base_transform(jnp.asarray(D11_TABLE3[0, :4], jnp.float32)), np.float64)
    corners = indices.control_points((0.0, 0.0, 0.0), D11_TASK_SIZE, 2)
    rows, facts = [], {"p": {}}
    mirrored = q * np.array([1, -1, -1, 1, -1, 1], np.float32)
    for label, qq in (("as given", q), ("θ2, θ3, θ5 negated", mirrored)):
        T = np.asarray(kin.fk(arm, qq), np.float64)
        for k, t in zip("KLMN", T):
            p_g = T_G_B[:3, :3] @ t[:3, 3] + T_G_B[:3, 3]
            a_g = T_G_B[:3, :3] @ t[:3, 0]
            c = corners[CORNER_OF[k]]
            rows.append([label, k, "(" + ", ".join(f"{v:.3f}" for v in p_g) + ")",
                         f"({c[0]:+.1f}, {c[1]:+.1f}, 0)", f"{np.linalg.norm(p_g - c):.3f}",
                         f"{t[2, 3] - arm.T_base_tool0[2, 3]:+.3f}", f"{a_g[2]:+.2f}"])
            facts["p"][(label, k)] = t[:3, 3]
    p = {k: facts["p"][("as given", k)] for k in "KLMN"}
    facts["LM"], facts["MN"] = np.linalg.norm(p["L"] - p["M"]), np.linalg.norm(p["M"] - p["N"])
    facts["sum235"] = q[:, 1] + q[:, 2] + q[:, 4]
    return rows, facts


def plot_wmax_maps(p: Preset, poses: dict, img: Path) -> tuple[str, dict]:
    """[D11] Figs 9–10: ``w_max`` (eq. 16) over the task area from each pose ``(4,)`` → PNG;
    returns the figure path and the share of the task area with w_max = 0 per pose."""
    plt = pyplot()
    half = D11_TASK_SIZE / 2
    ax_ = np.linspace(-half, half, p.map_n)
    gx, gy = np.meshgrid(ax_, ax_, indexing="xy")
    pts = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], -1)
    maps = {k: np.asarray(w_max_at(READINGS[0], np.asarray(v, np.float32)[None], pts))[0].reshape(gx.shape)
            for k, v in poses.items()}
    vmax = max(float(m.max()) for m in maps.values())
    fig, axes = plt.subplots(1, len(maps), figsize=(4.3 * len(maps), 4.4), layout="constrained")
    for ax, (k, m) in zip(axes, maps.items()):
        pose = poses[k]
        im = ax.imshow(m, origin="lower", extent=(-half, half, -half, half), vmin=0, vmax=vmax, cmap="viridis")
        ax.contour(gx, gy, m, levels=[1e-6], colors="red", linewidths=1.2)
        ax.plot([], [], "r-", label="edge of the w_max = 0 region")
        ax.plot(pose[0], pose[1], "k^", ms=9)
        ax.annotate(f"arm base\n({pose[0]:.2f}, {pose[1]:.2f})", (pose[0], pose[1]), xytext=(6, 6),
                    textcoords="offset points", fontsize=8)
        ax.set(xlim=(-0.62, 0.25), ylim=(-0.62, 0.25), xlabel="x in G [m]", ylabel="y in G [m]",
               title=f"{k}\nzero w_max: {100 * np.mean(m == 0):.1f} % of the task area")
        ax.set_aspect("equal")
        ax.legend(loc="lower right", fontsize=7)
    fig.colorbar(im, ax=list(axes), label="w_max (eq. 16)", shrink=0.8)
    path = save_figure(fig, img, "docking_wmax_maps.png")
    return path, {k: float(np.mean(m == 0)) for k, m in maps.items()}


def _paper_table3_rows(base, corners: np.ndarray, order: list[int], far: np.ndarray) -> tuple[list, np.ndarray]:
    """Table 3's seven poses under our model (rows of the [D11] table: pose, the paper's
    fitness and M_a, our M_a and w_max at the corners K, L, M, N, the shoulder's distance to
    the far corner M [m], the heading's offset), and those distances ``(7,)`` [m]."""
    w_corner = np.asarray(w_max_at(base, D11_TABLE3[:, :4], corners))
    shoulder = D11_TABLE3[:, :3] + np.array([0.0, 0.0, base.lengths[0]])
    far_dist = np.linalg.norm(shoulder - far, axis=-1)
    rows = []
    for i, (x, y, z, psi, f, ma) in enumerate(D11_TABLE3):
        rows.append([i + 1, f"({x:.2f}, {y:.2f}, {z:.2f}, {psi:.2f})", f"{f:.2f}", f"{ma:.3f}",
                     f"{float(np.min(w_corner[i])):.3f}",
                     " / ".join(f"{w_corner[i][k]:.3f}" for k in order), f"{far_dist[i]:.2f}",
                     f"{heading_offset(D11_TABLE3[i:i + 1, :4])[0]:.0f}°"])
    return rows, far_dist


def _readings_table(ours: np.ndarray) -> tuple[str, list[str]]:
    """M_a of the paper's poses and of ``ours (4,)`` under each reading of the arm (a Markdown
    table), and the readings under which M_a reaches the paper's size."""
    r_rows, paper_sized = [], []
    for r in progress.bar(READINGS, desc="docking readings", unit="reading"):
        at_paper, at_ours = area_m(r, D11_TABLE3[:, :4]), float(area_m(r, ours[None])[0])
        r_rows.append([r.label, f"{at_paper[0]:.4f}", f"{at_paper.min():.3f}–{at_paper.max():.3f}", f"{at_ours:.4f}"])
        if max(at_paper.max(), at_ours) >= PAPER_SIZED * D11_TABLE3[:, 5].min():
            paper_sized.append(f"{r.label} ({at_ours:.3f} at our pose, {at_paper.max():.3f} at the paper's)")
    return md_table(["reading", "M_a at paper run 1", "M_a at paper runs 1–7", "M_a at our pose"], r_rows), paper_sized


def docking_fields(p: Preset, img: Path) -> dict:
    """The [D11] section's numbers, tables and figure: the fields of its template
    (experiments/papers_templates/docking.md)."""
    base = READINGS[0]
    arm = kin.docking_arm(*base.lengths)
    t0 = time.perf_counter()
    grid, ours = grid_optimum(p)

    # Table 3: the paper's seven poses under our model, and the headings.
    corners = indices.control_points((0.0, 0.0, 0.0), D11_TASK_SIZE, 2)
    order = [CORNER_OF[k] for k in "KLMN"]
    far = corners[CORNER_OF["M"]]
    rows, far_dist = _paper_table3_rows(base, corners, order, far)
    ga_poses, ga_fitness = ga_runs()
    facing = facing_centre(grid)
    m_facing = area_m(base, facing)
    ours_facing = facing[np.argmax(fitness(m_facing, facing))]
    labelled = [("ours, grid optimum", ours)] + [(f"ours, GA run {i + 1}", x) for i, x in enumerate(ga_poses)]
    labelled.append(("ours, ψ towards the centre", ours_facing))
    for label, x in labelled:
        m = float(area_m(base, x[None])[0])
        w_x = np.asarray(w_max_at(base, x[None], corners))[0][order]
        rows.append([label, f"({x[0]:.2f}, {x[1]:.2f}, {x[2]:.2f}, {x[3]:.2f})",
                     f"{fitness([m], x[None])[0]:.2f} (a = {SCENE.a:g}, b = {SCENE.b:g})", "—",
                     f"{m:.4f}", " / ".join(f"{v:.3f}" for v in w_x),
                     f"{np.linalg.norm(x[:3] + [0, 0, base.lengths[0]] - far):.2f}",
                     f"{heading_offset(x[None])[0]:.0f}°"])
    ga_heading = heading_offset(ga_poses)
    # The quarter of the top face nearest p_init (the paper's poses lie there): within 1 cm.
    sign = np.sign(np.asarray(D11_P_INIT[:2]))
    ga_near = int(np.sum(np.all(ga_poses[:, :2] * sign >= -0.01, axis=1)))
    ga_m = area_m(base, ga_poses)
    ga_best = float(fitness(ga_m, ga_poses).max())
    table3 = md_table(["run", "pose (x, y, z, ψ)", "fitness", "paper M_a", "our M_a at the pose",
                       "our w_max at K / L / M / N", "shoulder → far corner M [m]", "heading − bearing to centre"],
                      rows)
    heading = heading_offset(D11_TABLE3[:, :4])

    # Table 4 under our frames.
    t4_rows, facts = table4_rows(arm)
    table4 = md_table(["reading", "point", "wrist centre in G [m]", "corner", "distance [m]",
                       "wrist − shoulder height [m]", "approach axis z"], t4_rows)

    # The bound and the readings.
    bound, q_bound = w_bound(p)
    readings, paper_sized = _readings_table(ours)

    fig, zero = plot_wmax_maps(p, {"paper run 1 (Fig. 9)": D11_TABLE3[0, :4],
                                   "paper ill-placed pose (Fig. 10)": np.array(D11_ILL_PLACED_POSE),
                                   "our optimum": ours}, img)
    z1, zill, zours = zero.values()
    shoulder_z = arm.T_base_tool0[2, 3]
    return dict(
        seconds=time.perf_counter() - t0, preset=p.name, a=SCENE.a, b=SCENE.b, table3=table3,
        far_min=far_dist.min(), far_max=far_dist.max(), bound=bound,
        theta2=q_bound[0], theta3=q_bound[1], theta5=q_bound[2],
        heading_min=heading.min(), heading_max=heading.max(), ours_heading=heading_offset(ours[None])[0],
        ga_heading_min=ga_heading.min(), ga_heading_max=ga_heading.max(), ga_best=ga_best,
        ga_m_min=float(ga_m.min()), ga_m_max=float(ga_m.max()), ga_runs=len(ga_poses), ga_near_quarter=ga_near,
        grid_best=float(fitness(area_m(base, ours[None]), ours[None])[0]),
        facing_fitness=float(fitness(area_m(base, ours_facing[None]), ours_facing[None])[0]),
        facing_m=float(area_m(base, ours_facing[None])[0]),
        facing_loss=100 * (1 - fitness(area_m(base, ours_facing[None]), ours_facing[None])[0]
                           / fitness(area_m(base, ours[None]), ours[None])[0]),
        table4=table4, m_above=facts["p"][("as given", "M")][2] - shoulder_z,
        m_below=abs(facts["p"][("θ2, θ3, θ5 negated", "M")][2] - shoulder_z),
        sum235_m=facts["sum235"][2], sum235_n=facts["sum235"][3], lm=facts["LM"], mn=facts["MN"],
        readings=readings, paper_sized=join_and(paper_sized) or "no reading",
        paper_sized_min=PAPER_SIZED * D11_TABLE3[:, 5].min(), fig=fig, map_n=p.map_n, zero_run1=100 * z1, zero_ill=100 * zill, zero_ours=100 * zours)
