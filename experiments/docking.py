"""Docking-pose optimisation experiment (SPEC §3; docking paper Tables 2–3, Figs 9–10).

Writes into the Hydra run directory:
  runs.csv            one row per GA run: x, y, z, psi, fitness, Ma, generations, seconds
  grid_optimum.json   grid-search reference: pose, fitness, Ma, candidates, seconds (+ zoom stages)
  cmaes.json          CMA-ES (evosax) runs
  wmax.json           zero-w area fraction of the task area for the best and the ill-placed pose
  wmax_best.png, wmax_ill_placed.png   w_max heat maps (eq. 16)
  convergence.png     best fitness per generation of every GA and CMA-ES run
  summary.json        acceptance figures (GA vs grid, batch time, quarter/facing checks)

  python experiments/docking.py                       # full
  python experiments/docking.py docking/preset=fast   # ~1 minute demo
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
import jax.numpy as jnp
import matplotlib
import numpy as np
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from uvms_jax import evo  # noqa: E402

log = logging.getLogger(__name__)
# Full float32 matrix products on GPUs too (TF32 would break the IK residual check).
jax.config.update("jax_default_matmul_precision", "highest")
FIELDS = ("x", "y", "z", "psi")


def build(cfg: DictConfig):
    """Problem, codec, GA and its parameters from the config (plain values only)."""
    dtype = jnp.dtype(cfg.dtype)
    if dtype == jnp.float64:
        jax.config.update("jax_enable_x64", True)
    scene = OmegaConf.to_container(cfg.scene, resolve=True)
    problem = evo.make_docking_problem(**scene, dtype=dtype)
    g = cfg.ga
    codec = evo.make_codec(problem.pose_low, problem.pose_high, [g.bits[f] for f in FIELDS], gray=g.gray)
    ga = evo.BinaryGA(
        population_size=g.population_size,
        n_bits=codec.n_bits,
        max_generations=g.max_generations,
        n_elites=g.n_elites,
        tournament_size=g.tournament_size,
        eval_chunk=g.eval_chunk,
    )
    params = evo.GAParams(
        crossover_rate=g.crossover_rate,
        mutation_rate=g.mutation_rate,
        crossover_bias=g.crossover_bias,
        rate_decay=g.rate_decay,
        improvement_decay=g.improvement_decay,
        crossover_rate_min=g.crossover_rate_min,
        mutation_rate_min=g.mutation_rate_min,
        stall_generations=g.stall_generations,
        improvement_tol=g.improvement_tol,
    )
    return problem, codec, ga, params


def _timed(fn, *args):
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - t0


def pose_checks(problem: evo.DockingProblem, pose, p_init, tol: float) -> dict:
    """Where a pose lies relative to the start: the quarter of the top face nearest ``p_init``
    (closed, within ``tol`` [m], for the arm base; open for the docking point) and the
    heading vs the task area."""
    pose = np.asarray(pose, dtype=float)
    sx, sy = np.sign(p_init[0]), np.sign(p_init[1])
    p_d = np.asarray(evo.docking_point(jnp.asarray(pose), problem.p_bp))
    c = np.asarray(problem.task_center)
    bearing = np.arctan2(c[1] - pose[1], c[0] - pose[0])
    off = float(np.abs(np.angle(np.exp(1j * (pose[3] - bearing)))))
    return {
        "base_in_near_quarter": bool(pose[0] * sx >= -tol and pose[1] * sy >= -tol),
        "docking_point": p_d.tolist(),
        "docking_point_in_near_quarter": bool(p_d[0] * sx > 0 and p_d[1] * sy > 0),
        "heading_off_task_centre_deg": float(np.degrees(off)),
        "faces_task_area": bool(off < np.pi / 2),  # the task centre lies ahead of the vehicle
    }


def plot_wmax(m: evo.WmaxMap, title: str, path: Path, vmax: float) -> None:
    fig, ax = plt.subplots(figsize=(5, 4.2))
    im = ax.pcolormesh(m.x, m.y, m.w_max.T, shading="nearest", cmap="viridis", vmin=0.0, vmax=vmax)
    zero = np.ma.masked_where(m.w_max.T > 0, np.ones_like(m.w_max.T))
    ax.pcolormesh(m.x, m.y, zero, shading="nearest", cmap="Reds", vmin=0, vmax=1.5, alpha=0.6)
    fig.colorbar(im, ax=ax, label="$w_{max}$ (eq. 16)")
    ax.set(xlabel="x in G [m]", ylabel="y in G [m]", title=f"{title}\nzero-w area {100 * m.zero_fraction:.1f} %")
    ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_convergence(ga_hist, cma_hist, references: dict, path: Path) -> None:
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
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


@hydra.main(version_base="1.3", config_path="../configs", config_name="docking")
def main(cfg: DictConfig) -> dict:
    out = Path(HydraConfig.get().runtime.output_dir)
    problem, codec, ga, params = build(cfg)
    p_init = list(cfg.scene.p_init)
    log.info("load average %s; devices %s", os.getloadavg(), jax.devices())

    # GA: R runs in one call. The first call compiles; the second is timed.
    keys = jax.random.split(jax.random.key(cfg.seed), cfg.n_runs)
    _, t_compile = _timed(evo.run_ga_batch, keys, problem, codec, ga, params)
    res, t_batch = _timed(evo.run_ga_batch, keys, problem, codec, ga, params)
    log.info("GA: %d runs in %.3f s after compilation (compile + first run %.1f s)", cfg.n_runs, t_batch, t_compile)
    seconds = [t_batch] * cfg.n_runs
    if cfg.time_single_runs:
        evo.run_ga(keys[0], problem, codec, ga, params)  # compile the single-run path
        seconds = [_timed(evo.run_ga, keys[r], problem, codec, ga, params)[1] for r in range(cfg.n_runs)]
    ga_eval = evo.evaluate(problem, res.best_x)

    # Grid reference: a global grid (compiled once for any size), then zoom stages.
    gc = cfg.grid
    low, high = problem.pose_low, problem.pose_high
    periodic = (False, False, False, True)
    evo.grid_search(problem, low, high, (2, 2, 2, 2), periodic, gc.chunk_size)  # compile
    grid, t_grid = _timed(evo.grid_search, problem, low, high, tuple(gc.counts), periodic, gc.chunk_size)
    stages, t_refine = _timed(
        evo.refine_grid_search, problem, grid, tuple(gc.refine_counts), gc.refine_stages, gc.refine_shrink, gc.chunk_size
    )
    ref = stages[-1] if stages else grid
    ref_eval = evo.evaluate(problem, ref.x)
    grid_eval = evo.evaluate(problem, grid.x)
    grid_json = {
        # The dense grid's optimum (the reference of the acceptance test) ...
        "pose": dict(zip(FIELDS, np.asarray(grid.x).tolist())),
        "fitness": float(grid.fitness),
        "Ma": float(grid_eval.M_a),
        "D": float(grid_eval.D),
        "counts": list(gc.counts),
        "candidates": int(grid.n_candidates),
        "seconds": t_grid,
        # ... and its polish by zoom grids around it (closer to the continuous optimum).
        "refined": {
            "pose": dict(zip(FIELDS, np.asarray(ref.x).tolist())),
            "fitness": float(ref.fitness),
            "Ma": float(ref_eval.M_a),
            "D": float(ref_eval.D),
            "candidates": int(sum(s.n_candidates for s in stages)),
            "seconds": t_refine,
            "stages": [float(s.fitness) for s in stages],
        },
    }
    (out / "grid_optimum.json").write_text(json.dumps(grid_json, indent=2))
    log.info("grid: %d candidates in %.1f s, optimum %.4f; refined (%d more) %.4f",
             grid.n_candidates, t_grid, float(grid.fitness), grid_json["refined"]["candidates"], float(ref.fitness))

    # CMA-ES (evosax).
    cma_hist = []
    if cfg.cmaes.enabled:
        cc = cfg.cmaes
        ckeys = jax.random.split(jax.random.key(cfg.seed + 1), cc.n_runs)
        args = (ckeys, problem, low, high, cc.population_size, cc.generations, cc.std_init)
        _, t_cma_compile = _timed(evo.run_cmaes, *args)
        cma, t_cma = _timed(evo.run_cmaes, *args)
        cma_hist = np.asarray(cma.history)
        (out / "cmaes.json").write_text(json.dumps({
            "runs": [{**dict(zip(FIELDS, np.asarray(x).tolist())), "fitness": float(f)}
                     for x, f in zip(cma.best_x, cma.best_fitness)],
            "seconds": t_cma,
            "evaluations_per_run": cc.population_size * cc.generations,
            "ratio_to_grid": (np.asarray(cma.best_fitness) / float(grid.fitness)).tolist(),
            "ratio_to_refined_grid": (np.asarray(cma.best_fitness) / float(ref.fitness)).tolist(),
        }, indent=2))
        log.info("CMA-ES: %d runs in %.2f s, best %.4f", cc.n_runs, t_cma, float(np.max(cma.best_fitness)))

    # runs.csv
    with open(out / "runs.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([*FIELDS, "fitness", "Ma", "generations", "seconds"])
        for r in range(cfg.n_runs):
            w.writerow([*np.asarray(res.best_x[r]).round(6).tolist(), round(float(res.best_fitness[r]), 6),
                        round(float(ga_eval.M_a[r]), 6), int(res.generations[r]), round(seconds[r], 4)])

    # w_max maps (eq. 16) for the best GA pose and the paper's ill-placed pose.
    best_r = int(np.argmax(np.asarray(res.best_fitness)))
    best_pose = np.asarray(res.best_x[best_r])
    maps = {
        "best": (best_pose, evo.wmax_map(problem, best_pose, cfg.wmax.n_per_side)),
        "ill_placed": (np.asarray(cfg.ill_placed_pose), evo.wmax_map(problem, list(cfg.ill_placed_pose), cfg.wmax.n_per_side)),
    }
    vmax = max(float(m.w_max.max()) for _, m in maps.values())
    for name, (pose, m) in maps.items():
        label = ", ".join(f"{float(v):.3f}" for v in pose)
        plot_wmax(m, f"{name.replace('_', '-')} pose [{label}]", out / f"wmax_{name}.png", vmax)
    (out / "wmax.json").write_text(json.dumps({
        name: {"pose": dict(zip(FIELDS, np.asarray(pose, dtype=float).tolist())),
               "zero_w_fraction": m.zero_fraction, "Ma": float(evo.evaluate(problem, pose).M_a),
               "w_max_mean": float(m.w_max.mean()), "n_per_side": cfg.wmax.n_per_side}
        for name, (pose, m) in maps.items()
    }, indent=2))

    plot_convergence([np.asarray(h)[: int(g)] for h, g in zip(res.history, res.generations)],
                     cma_hist, {"grid optimum": float(grid.fitness), "refined grid": float(ref.fitness)},
                     out / "convergence.png")

    f_ga = np.asarray(res.best_fitness)
    tol = float(np.max(np.asarray(codec.resolution)[:2]))  # x = 0 / y = 0 is not on the lattice
    checks = [pose_checks(problem, x, p_init, tol) for x in np.asarray(res.best_x)]
    references = {"grid": float(grid.fitness), "refined_grid": float(ref.fitness)}
    summary = {
        "ga_fitness": f_ga.tolist(),
        **{f"ga_ratio_to_{k}": (f_ga / v).round(5).tolist() for k, v in references.items()},
        **{f"ga_runs_within_{cfg.accept_ratio}_of_{k}": int(np.sum(f_ga >= cfg.accept_ratio * v)) for k, v in references.items()},
        "ga_batch_seconds": t_batch,
        "ga_compile_and_first_batch_seconds": t_compile,
        "ga_generations": np.asarray(res.generations).tolist(),
        "ga_evaluations": np.asarray(res.evaluations).tolist(),
        "best_pose_checks": checks,
        "all_bases_in_near_quarter": all(c["base_in_near_quarter"] for c in checks),
        "all_docking_points_in_near_quarter": all(c["docking_point_in_near_quarter"] for c in checks),
        "all_face_task_area": all(c["faces_task_area"] for c in checks),
        "zero_w_fraction": {k: m.zero_fraction for k, (_, m) in maps.items()},
        "load_average": os.getloadavg(),
        "device": str(jax.devices()[0]),
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    log.info("GA/grid ratios %s (refined grid: %s); zero-w best %.3f, ill-placed %.3f; outputs in %s",
             summary["ga_ratio_to_grid"], summary["ga_ratio_to_refined_grid"],
             maps["best"][1].zero_fraction, maps["ill_placed"][1].zero_fraction, out)
    return summary


if __name__ == "__main__":
    main()
