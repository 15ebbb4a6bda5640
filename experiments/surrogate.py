"""Surrogate networks for the dexterity indices w and KCI (issue 4; SPEC §4; dexterity paper §3–4).

Builds datasets D1 (θ1…θ11 → KCI) and D2 (θ5…θ11 → w) with the paper's sampling (Fig. 7), runs
the design loops (FFBN: grow hidden neurons; RBFN: spread search) until the maximum relative
test error ``max |(T − S)/T|`` (eq. 21) is below E, and times every network against the
analytic index (float32, jitted, compilation excluded). Writes into the Hydra run directory:

  report.json                 per network: hidden units, spread, max relative test error,
                              operation counts, design time, time for 1e3 / 1e5 / 1e6 inputs
                              vs the analytic index; acceptance figures of issue 4
  ffbn_w_design.png, ffbn_kci_design.png   test error vs hidden neurons (Fig. 10/14)
  rbfn_w_design.png, rbfn_kci_design.png   test error and units vs spread (Fig. 8/12)
  training.png                training mse of each selected network (Figs. 9/11/13/15)
  data/  networks/            datasets (npz + json) and networks (npz + json)

  python experiments/surrogate.py                    # paper-sized
  python experiments/surrogate.py surrogate=small    # ~1-2 minute demo
"""

from __future__ import annotations

import json
import logging
import math
import platform
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

from uvms_jax import kin, surrogate  # noqa: E402

log = logging.getLogger(__name__)

# Paper Table 4 (operations) and Table 5 (seconds for 1000 inputs, Matlab on an i7-3930K).
PAPER = {
    "ffbn_w": {"hidden_units": 8, "operation_count": 184, "seconds_1000": 0.0057},
    "ffbn_kci": {"hidden_units": 25, "operation_count": 775, "seconds_1000": 0.0057},
    "rbfn_w": {"hidden_units": 149, "operation_count": 4172, "seconds_1000": 0.0152},
    "rbfn_kci": {"spread": 8.9, "operation_count": 3976, "seconds_1000": 0.0152},
    "analytic_w": {"operation_count": 21810, "seconds_1000": 0.7043},
    "analytic_kci": {"operation_count": 21594, "seconds_1000": 0.7283},
}


def sampling_from_cfg(s: DictConfig) -> surrogate.Sampling:
    rad = math.radians
    return surrogate.Sampling(
        mode=s.mode, task_point=tuple(s.task_point), r_min=s.r_min, r_max=s.r_max, phi=rad(s.phi_deg),
        heading=rad(s.heading_deg), nominal_arm=tuple(rad(v) for v in s.nominal_arm_deg),
        half_range=rad(s.half_range_deg), step=rad(s.step_deg), continuous=s.continuous,
    )


def make_sets(key, chain, sampling, index: str, cfg: DictConfig, out: Path):
    """Train and test sets of one index from one jitted draw; saved with their config."""
    n_train, n_test = int(cfg.data.n_train[index]), int(cfg.data.n_test)
    t0 = time.perf_counter()
    ds = surrogate.make_dataset(key, chain, sampling, n_train + n_test, index, jnp.dtype(cfg.train_dtype))
    ds.y.block_until_ready()
    seconds = time.perf_counter() - t0
    train, test = ds.split(n_train)
    name = "d1" if index == "kci" else "d2"
    for part, d in (("train", train), ("test", test)):
        surrogate.save_dataset(out / "data" / f"{name}_{part}", d, seed=int(cfg.seed), chain=chain.name)
    log.info("dataset %s (%s): %d train + %d test in %.1f s (compile included); %s in [%.4g, %.4g]",
             name, index, n_train, n_test, seconds, index, float(ds.y.min()), float(ds.y.max()))
    return train, test, seconds


def design(name: str, key, train, test, cfg: DictConfig) -> surrogate.Design:
    kind, index = name.split("_")
    if kind == "ffbn":
        f = cfg.ffbn
        return surrogate.design_ffbn(
            key, train, test, error_goal=f.error_goal, max_hidden=int(f.max_hidden[index]),
            hidden_step=int(f.hidden_step), trainer=f.trainer, target_mse=float(f.target_mse[index]),
            max_epochs=int(f.max_epochs), adam_steps=int(f.adam.steps), adam_learning_rate=float(f.adam.learning_rate),
        )
    r = cfg.rbfn
    return surrogate.design_rbfn(
        train, test, error_goal=r.error_goal, spread_start=r.spread_start, spread_step=r.spread_step,
        spread_max=r.spread_max, target_mse=float(r.target_mse[index]), max_centres=int(r.max_centres[index]),
    )


def timing_batch(test, n: int) -> jax.Array:
    """``(n, 12)`` float32 configurations: the test configurations repeated."""
    q = jnp.asarray(test.q, jnp.float32)
    return jnp.tile(q, (-(-n // q.shape[0]), 1))[:n]


def _chunk(n: int, chunk: int) -> int | None:
    return chunk if n > chunk and n % chunk == 0 else None


def time_pair(net_fn, ana: dict, q, chunk: int, repeats: int) -> dict:
    """Network timing next to an analytic timing ``ana`` taken on the same batch in this run."""
    c = _chunk(q.shape[0], chunk)
    net = surrogate.time_index_fn(net_fn, q, repeats=repeats, chunk=c)
    return {"network_s": net["seconds"], "analytic_s": ana["seconds"], "speedup": ana["seconds"] / net["seconds"],
            "network_per_s": net["per_second"], "analytic_per_s": ana["per_second"], "chunk": c}


def plot_ffbn(name: str, d: surrogate.Design, goal: float, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    sizes = [s.size for s in d.steps]
    ax.semilogy(sizes, [s.test_error for s in d.steps], "o-", label="max relative test error")
    ax.axhline(goal, color="r", ls="--", label=f"E = {goal:g}")
    ax.set(xlabel="hidden neurons", ylabel="max |(T − S)/T|", title=f"{name.upper()} design process")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_rbfn(name: str, d: surrogate.Design, goal: float, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    spreads = [s.spread for s in d.steps]
    ax.semilogy(spreads, [s.test_error for s in d.steps], "o-", label="max relative test error")
    ax.axhline(goal, color="r", ls="--", label=f"E = {goal:g}")
    ax.set(xlabel="spread (normalised inputs)", ylabel="max |(T − S)/T|", title=f"{name.upper()} design process")
    ax2 = ax.twinx()
    ax2.plot(spreads, [s.size for s in d.steps], "s:", color="gray", label="units")
    ax2.set_ylabel("RBF units")
    ax.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_training(designs: dict, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(6, 4))
    for name, d in designs.items():
        label = "unit" if name.startswith("rbfn") else "epoch"
        ax.semilogy(np.arange(len(d.history)), d.history, label=f"{name} (per {label})")
    ax.set(xlabel="epoch / added unit", ylabel="training mse [index units²]", title="Training of the selected networks")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def acceptance(report: dict, acc: DictConfig, goal: float) -> dict:
    nets = report["networks"]
    out = {}
    if "ffbn_w" in nets:
        n = nets["ffbn_w"]
        out["ffbn_w_error_ok"] = n["max_rel_test_error"] < goal and n["hidden_units"] <= acc.ffbn_w_max_hidden
        out["ffbn_w_design_seconds"] = n["design_seconds"]
        out["ffbn_w_design_time_ok"] = n["design_seconds"] < acc.ffbn_w_design_seconds
    if "ffbn_kci" in nets:
        n = nets["ffbn_kci"]
        out["ffbn_kci_error_ok"] = n["max_rel_test_error"] < goal and n["hidden_units"] <= acc.ffbn_kci_max_hidden
    if "rbfn_w" in nets:
        out["rbfn_w_error_ok"] = nets["rbfn_w"]["max_rel_test_error"] < goal
    for index, need in (("w", acc.speedup_w_at_1e5), ("kci", acc.speedup_kci_at_1e5)):
        t = nets.get(f"ffbn_{index}", {}).get("timing", {}).get("100000")
        if t is not None:
            out[f"ffbn_{index}_speedup_at_1e5"] = t["speedup"]
            out[f"ffbn_{index}_speedup_ok"] = t["speedup"] >= need
    return out


@hydra.main(version_base="1.3", config_path="../configs", config_name="surrogate")
def main(cfg: DictConfig) -> None:
    if jnp.dtype(cfg.train_dtype) == jnp.float64:
        jax.config.update("jax_enable_x64", True)
    out = Path(HydraConfig.get().runtime.output_dir)
    chain = kin.uvms12()
    sampling = sampling_from_cfg(cfg.sampling)
    key = jax.random.key(int(cfg.seed))
    k_w, k_kci, k_ffbn, _ = jax.random.split(key, 4)
    wanted = list(cfg.networks)
    indices = sorted({n.split("_")[1] for n in wanted}, key=["w", "kci"].index)
    sets, data_info = {}, {}
    for index in indices:
        train, test, seconds = make_sets(k_w if index == "w" else k_kci, chain, sampling, index, cfg, out)
        sets[index] = (train, test)
        data_info[index] = {"n_train": len(train), "n_test": len(test), "seconds": seconds,
                            "y_min": float(jnp.minimum(train.y.min(), test.y.min())),
                            "y_max": float(jnp.maximum(train.y.max(), test.y.max())), "inputs": list(train.inputs)}

    designs, nets = {}, {}
    for i, name in enumerate(wanted):
        kind, index = name.split("_")
        train, test = sets[index]
        d = design(name, jax.random.fold_in(k_ffbn, i), train, test, cfg)
        designs[name] = d
        net = d.network
        surrogate.save_network(out / "networks" / name, net, design_seconds=d.seconds, met=d.met)
        goal = cfg[kind].error_goal
        (plot_ffbn if kind == "ffbn" else plot_rbfn)(name, d, goal, out / f"{name}_design.png")
        nets[name] = {
            "kind": kind, "index": index,
            "hidden_units": net.hidden if kind == "ffbn" else net.n_centres,
            "spread": None if kind == "ffbn" else float(net.spread),
            "max_rel_test_error": d.steps[-1].test_error if d.met else min(s.test_error for s in d.steps),
            "met_goal": d.met, "design_seconds": d.seconds, "networks_tried": len(d.steps),
            "train_mse": float(d.history[-1]), "operation_count": net.operation_count,
            "design_steps": [s._asdict() for s in d.steps], "paper": PAPER[name],
        }
        log.info("%s: %d units, max rel test error %.4f (%s), design %.1f s", name, nets[name]["hidden_units"],
                 nets[name]["max_rel_test_error"], "met" if d.met else "NOT met", d.seconds)
    plot_training(designs, out / "training.png")

    # Timing in float32 (GPU-friendly default), jitted, compilation excluded, side by side.
    analytic = {index: surrogate.analytic_index_fn(chain, index) for index in indices}
    analytic_info, analytic_times = {}, {}
    for index in indices:
        q = timing_batch(sets[index][1], 1000)
        analytic_info[index] = {"xla_flops_per_sample": surrogate.xla_flops_per_sample(analytic[index], q),
                                "paper": PAPER[f"analytic_{index}"], "timing": {}}
        for n in cfg.timing.batches:
            q = timing_batch(sets[index][1], int(n))
            t = surrogate.time_index_fn(analytic[index], q, repeats=int(cfg.timing.repeats),
                                        chunk=_chunk(int(n), int(cfg.timing.chunk)))
            analytic_times[index, int(n)] = t
            analytic_info[index]["timing"][str(int(n))] = t
            log.info("analytic %s at %d: %.3g s", index, n, t["seconds"])
    for name in wanted:
        index = nets[name]["index"]
        net = designs[name].network
        q = timing_batch(sets[index][1], 1000)
        nets[name]["xla_flops_per_sample"] = surrogate.xla_flops_per_sample(net.index_fn, q)
        timing = {}
        for n in cfg.timing.batches:
            q = timing_batch(sets[index][1], int(n))
            timing[str(int(n))] = time_pair(net.index_fn, analytic_times[index, int(n)], q, int(cfg.timing.chunk),
                                          int(cfg.timing.repeats))
            log.info("%s at %d: network %.3g s, analytic %.3g s, speed-up %.1f×", name, n,
                     timing[str(int(n))]["network_s"], timing[str(int(n))]["analytic_s"], timing[str(int(n))]["speedup"])
        nets[name]["timing"] = timing

    report = {
        "device": {"platform": jax.devices()[0].platform, "device_kind": jax.devices()[0].device_kind,
                   "cpu_count": __import__("os").cpu_count(), "python": platform.python_version(),
                   "jax": jax.__version__},
        "error_metric": "max over the test set of |(T - S) / T| (paper eq. 21); T analytic, S network",
        "timing_note": ("float32, jitted, compilation excluded, median of repeats, one process; analytic = "
                        "kin.jacobian + indices.manipulability / indices.kci; batches above timing.chunk run in "
                        "chunks (lax.map) for both network and analytic index"),
        "datasets": data_info, "analytic": analytic_info, "networks": nets,
        "config": OmegaConf.to_container(cfg, resolve=True),
    }
    report["acceptance"] = acceptance(report, cfg.acceptance, cfg.ffbn.error_goal)
    (out / "report.json").write_text(json.dumps(report, indent=2))
    log.info("acceptance: %s", report["acceptance"])
    log.info("report: %s", out / "report.json")


if __name__ == "__main__":
    main()
