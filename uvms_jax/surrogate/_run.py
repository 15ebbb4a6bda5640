"""The surrogate design run: datasets, design loops, timing against the analytic index, report.

:func:`run_surrogates` builds the datasets D1 (θ1…θ11 → KCI) and D2 (θ5…θ11 → w) with the
paper's sampling (Fig. 7), runs the FFBN and RBFN design loops until the maximum relative test
error ``max |(T − S)/T|`` (eq. 21) is below E, and times every network against the analytic
index (float32, jitted, compilation excluded, side by side in one process). It returns a
:class:`SurrogateRun`; :func:`uvms_jax.surrogate.write_surrogates` writes it to files.
No files are touched here and ``jax_enable_x64`` is left as the caller set it.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import platform
import time
from typing import Any, Mapping

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax import kin
from uvms_jax.surrogate._dataset import Dataset, analytic_index, analytic_index_fn, make_dataset
from uvms_jax.surrogate._design import Design, design_ffbn, design_rbfn
from uvms_jax.surrogate._settings import SurrogateSettings, split_network_name
from uvms_jax.surrogate._timing import chunk_for, tile_batch, time_index_fn, xla_flops_per_sample

log = logging.getLogger(__name__)

ERROR_METRIC = "max over the test set of |(T - S) / T| (paper eq. 21); T analytic, S network"
TIMING_NOTE = ("float32, jitted, compilation excluded, median of repeats, one process; analytic = the "
               "project's fastest analytic path, one fused kernel that never stores J (indices.manipulability_of "
               "/ indices.kci_of for the geometric form; the same reductions on the spatial rows otherwise); "
               "batches above timing.chunk run in chunks (lax.map) for both network and analytic index")
# Dataset file stem of each index (paper: D1 → KCI, D2 → w).
DATASET_NAMES = {"kci": "d1", "w": "d2"}
# Timing batch of the acceptance speed-ups.
ACCEPTANCE_BATCH = "100000"


@dataclasses.dataclass(frozen=True)
class SurrogateRun:
    """Result of :func:`run_surrogates`; ``report`` is the content of results.json.

    Attributes:
      settings: the settings of the run.
      chain_name: name of the kinematic chain (recorded with the datasets).
      sets: per index ("w", "kci"): (train, test) datasets (dtype ``settings.train_dtype``).
      designs: per network name ("ffbn_w", …): the design loop's result.
      datasets: per index: n_train, n_test, seconds (sampling + labelling, compilation
        included), y_min, y_max [index units], inputs (joint indices).
      networks: per network name: kind, index, hidden_units, spread, max_rel_test_error,
        met_goal, design_seconds, networks_tried, train_mse, operation_count, design_steps,
        xla_flops_per_sample, timing (per batch size as a string:
        network_s, analytic_s, speedup, network_per_s, analytic_per_s, chunk) [s].
      analytic: per index: xla_flops_per_sample, timing (per batch size: seconds,
        min_seconds, compile_seconds, per_second).
      acceptance: acceptance figures (bools, seconds, speed-ups).
      device: platform, device kind, CPU count, Python and JAX versions.
    """

    settings: SurrogateSettings
    chain_name: str
    sets: Mapping[str, tuple[Dataset, Dataset]]
    designs: Mapping[str, Design]
    datasets: Mapping[str, dict]
    networks: Mapping[str, dict]
    analytic: Mapping[str, dict]
    acceptance: Mapping[str, Any]
    device: Mapping[str, Any]

    @property
    def report(self) -> dict:
        """results.json as a dict (same keys and order as written)."""
        return {
            "device": dict(self.device), "error_metric": ERROR_METRIC, "timing_note": TIMING_NOTE,
            "datasets": dict(self.datasets), "analytic": dict(self.analytic), "networks": dict(self.networks),
            "config": self.settings.to_dict(), "acceptance": dict(self.acceptance),
        }


def _device_info() -> dict:
    dev = jax.devices()[0]
    return {"platform": dev.platform, "device_kind": dev.device_kind, "cpu_count": os.cpu_count(),
            "python": platform.python_version(), "jax": jax.__version__}


def _train_dtype(settings: SurrogateSettings) -> jnp.dtype:
    dtype = jnp.dtype(settings.train_dtype)
    if dtype == jnp.float64 and not jax.config.jax_enable_x64:
        raise ValueError("train_dtype float64 needs jax_enable_x64; enable it at start, before any JAX work "
                         "(jax.config.update('jax_enable_x64', True)), or use train_dtype float32")
    return dtype


def _make_sets(key: Array, chain: kin.Chain, index: str, settings: SurrogateSettings) -> tuple[Dataset, Dataset, dict]:
    """Train and test sets of one index from one jitted draw, and their report entry."""
    n_train, n_test = settings.data.n_train[index], settings.data.n_test
    t0 = time.perf_counter()
    ds = make_dataset(key, chain, settings.sampling.to_sampling(), n_train + n_test, index, _train_dtype(settings),
                      form=settings.index_form)
    ds.y.block_until_ready()
    seconds = time.perf_counter() - t0
    train, test = ds.split(n_train)
    log.info("dataset %s (%s): %d train + %d test in %.1f s (compile included); %s in [%.4g, %.4g]",
             DATASET_NAMES[index], index, n_train, n_test, seconds, index, float(ds.y.min()), float(ds.y.max()))
    info = {"n_train": len(train), "n_test": len(test), "seconds": seconds,
            "y_min": float(jnp.minimum(train.y.min(), test.y.min())),
            "y_max": float(jnp.maximum(train.y.max(), test.y.max())), "inputs": list(train.inputs)}
    return train, test, info


def _design_network(key: Array, name: str, train: Dataset, test: Dataset, settings: SurrogateSettings) -> Design:
    kind, index = split_network_name(name)
    if kind == "ffbn":
        f = settings.ffbn
        return design_ffbn(
            key, train, test, error_goal=f.error_goal, max_hidden=f.max_hidden[index], hidden_step=f.hidden_step,
            trainer=f.trainer, target_mse=f.target_mse[index], max_epochs=f.max_epochs, adam_steps=f.adam.steps,
            adam_learning_rate=f.adam.learning_rate, together=f.together,
        )
    r = settings.rbfn
    return design_rbfn(
        train, test, error_goal=r.error_goal, spread_start=r.spread_start, spread_step=r.spread_step,
        spread_max=r.spread_max, target_mse=r.target_mse[index], max_centres=r.max_centres[index],
    )


def _network_info(name: str, d: Design) -> dict:
    kind, index = split_network_name(name)
    net = d.network
    return {
        "kind": kind, "index": index,
        "hidden_units": net.hidden if kind == "ffbn" else net.n_centres,
        "spread": None if kind == "ffbn" else float(net.spread),
        "max_rel_test_error": d.steps[-1].test_error if d.met else min(s.test_error for s in d.steps),
        "met_goal": d.met, "design_seconds": d.seconds, "networks_tried": len(d.steps),
        "train_mse": float(d.history[-1]), "operation_count": net.operation_count,
        "design_steps": [s._asdict() for s in d.steps],
    }


def _time_analytic(chain: kin.Chain, index: str, q_test: Array, settings: SurrogateSettings) -> dict:
    """The report's analytic entry of ``index``: XLA flops per sample and timing per batch size."""
    t_set, fn = settings.timing, analytic_index_fn(chain, index, settings.index_form)
    info = {"xla_flops_per_sample": _xla_count(chain, index, settings.index_form, tile_batch(q_test, 1000)),
            "timing": {}}
    for n in t_set.batches:
        t = info["timing"][str(n)] = time_index_fn(fn, tile_batch(q_test, n), repeats=t_set.repeats,
                                                   chunk=chunk_for(n, t_set.chunk))
        log.info("analytic %s at %d: %.3g s", index, n, t["seconds"])
    return info


def _xla_count(chain: kin.Chain, index: str, form, q: Array) -> float | None:
    """XLA's flops per sample of the analytic index's program compiled for the CPU, at ``q: (N,
    n_joints)``: one count on every machine. (A GPU runs the geometric form as a Pallas kernel,
    which XLA's cost analysis does not see into, and counts the spatial form's program differently.)"""
    try:
        cpu = jax.devices("cpu")[0]
    except RuntimeError:  # JAX_PLATFORMS leaves the CPU out: no count rather than another one
        log.warning("no CPU backend (JAX_PLATFORMS): the analytic %s is not counted", index)
        return None
    program = jax.jit(analytic_index, static_argnums=(2, 3))  # the chain as an argument: XLA's path
    chain, q = jax.device_put((chain, q), cpu)
    return xla_flops_per_sample(lambda q: program(chain, q, index, form), q)


def _time_network(name: str, fn, q_test: Array, analytic: Mapping[str, dict], settings: SurrogateSettings) -> dict:
    """XLA flops per sample and timing per batch size of a network, beside the analytic timing
    ``analytic`` (per batch size) taken on the same batches in this run."""
    t_set, timing = settings.timing, {}
    flops = xla_flops_per_sample(fn, tile_batch(q_test, 1000))
    for n in t_set.batches:
        c = chunk_for(n, t_set.chunk)
        net, ana = time_index_fn(fn, tile_batch(q_test, n), repeats=t_set.repeats, chunk=c), analytic[str(n)]
        timing[str(n)] = {"network_s": net["seconds"], "analytic_s": ana["seconds"],
                          "speedup": ana["seconds"] / net["seconds"], "network_per_s": net["per_second"],
                          "analytic_per_s": ana["per_second"], "chunk": c}
        log.info("%s at %d: network %.3g s, analytic %.3g s, speed-up %.1f×", name, n,
                 net["seconds"], ana["seconds"], timing[str(n)]["speedup"])
    return {"xla_flops_per_sample": flops, "timing": timing}


def acceptance_figures(networks: Mapping[str, dict], settings: SurrogateSettings) -> dict:
    """Acceptance figures from the report's ``networks`` entries: error goal and unit limits met,
    FFBN-w design time, FFBN speed-ups at 1e5 inputs (where those networks and batches ran)."""
    acc, goal = settings.acceptance, settings.ffbn.error_goal
    out = {}
    if "ffbn_w" in networks:
        n = networks["ffbn_w"]
        out["ffbn_w_error_ok"] = n["max_rel_test_error"] < goal and n["hidden_units"] <= acc.ffbn_w_max_hidden
        out["ffbn_w_design_seconds"] = n["design_seconds"]
        out["ffbn_w_design_time_ok"] = n["design_seconds"] < acc.ffbn_w_design_seconds
    if "ffbn_kci" in networks:
        n = networks["ffbn_kci"]
        out["ffbn_kci_error_ok"] = n["max_rel_test_error"] < goal and n["hidden_units"] <= acc.ffbn_kci_max_hidden
    if "rbfn_w" in networks:
        out["rbfn_w_error_ok"] = networks["rbfn_w"]["max_rel_test_error"] < goal
    for index, need in (("w", acc.speedup_w_at_1e5), ("kci", acc.speedup_kci_at_1e5)):
        t = networks.get(f"ffbn_{index}", {}).get("timing", {}).get(ACCEPTANCE_BATCH)
        if t is not None:
            out[f"ffbn_{index}_speedup_at_1e5"] = t["speedup"]
            out[f"ffbn_{index}_speedup_ok"] = t["speedup"] >= need
    return out


def run_surrogates(key: Array, chain: kin.Chain, settings: SurrogateSettings = SurrogateSettings()) -> SurrogateRun:
    """Design the surrogate networks of ``settings.networks`` and time them (dexterity paper §3–4).

    Args:
      key: PRNG key (datasets of w and KCI and the FFBN initialisations each get their own).
      chain: the 12-DOF UVMS (``kin.uvms12()``).
      settings: the run's settings; ``train_dtype`` float64 needs ``jax_enable_x64`` set by the caller.

    Returns:
      :class:`SurrogateRun` (datasets, designs and the report's entries).

    Raises:
      ValueError: float64 training without ``jax_enable_x64``, or a chain that is not the UVMS.
    """
    _train_dtype(settings)
    k_w, k_kci, k_ffbn, _ = jax.random.split(key, 4)
    sets, data_info = {}, {}
    for index in settings.indices:
        train, test, data_info[index] = _make_sets(k_w if index == "w" else k_kci, chain, index, settings)
        sets[index] = (train, test)

    designs, nets = {}, {}
    for i, name in enumerate(settings.networks):
        train, test = sets[split_network_name(name)[1]]
        d = designs[name] = _design_network(jax.random.fold_in(k_ffbn, i), name, train, test, settings)
        nets[name] = _network_info(name, d)
        log.info("%s: %d units, max rel test error %.4f (%s), design %.1f s", name, nets[name]["hidden_units"],
                 nets[name]["max_rel_test_error"], "met" if d.met else "NOT met", d.seconds)

    # Timing in float32 (GPU-friendly default), jitted, compilation excluded, side by side.
    analytic_info = {index: _time_analytic(chain, index, sets[index][1].q, settings) for index in settings.indices}
    for name in settings.networks:
        index = nets[name]["index"]
        nets[name].update(_time_network(name, designs[name].network.index_fn, sets[index][1].q,
                                        analytic_info[index]["timing"], settings))

    acceptance = acceptance_figures(nets, settings)
    log.info("acceptance: %s", acceptance)
    return SurrogateRun(settings=settings, chain_name=chain.name, sets=sets, designs=designs, datasets=data_info,
                        networks=nets, analytic=analytic_info, acceptance=acceptance, device=_device_info())
