"""Throughput of the index surrogates: analytic w / KCI vs FFBN vs RBFN, side by side in one process.

Prints one JSON object. All functions are jitted and timed in float32 on the same configurations
(UVMS-12, paper sampling of Fig. 7), compilation excluded, median of ``--repeats`` runs; batches
above ``--chunk`` are evaluated in chunks (``lax.map``) by every contender. The analytic index is
the project's fastest path, one fused kernel that never stores J (``indices.manipulability_of``
/ ``indices.kci_of``; with ``--jacobian spatial`` the same reductions on the paper's spatial
Jacobian, eq. 6), so every speed-up is against it.

Networks: ``--networks DIR`` loads ``ffbn_w``, ``ffbn_kci``, ``rbfn_w``, ``rbfn_kci`` saved by
``experiments/surrogate.py`` (``<run dir>/networks``); without it, networks of the paper's sizes
(FFBN-w 8, FFBN-KCI 25, RBFN-w 149, RBFN-KCI 142 hidden units) with random weights are timed —
the cost of a network does not depend on its weight values.

Usage: python benchmarks/surrogate.py [--device cpu|gpu] [--batches 1e3,1e4,1e5,1e6] [--networks DIR]
                                     [--jacobian geometric|spatial]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cpu", help="JAX platform: cpu, gpu/cuda (default cpu)")
    parser.add_argument("--batches", default="1e3,1e4,1e5,1e6")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--chunk", type=float, default=1e5, help="evaluate larger batches in chunks of this size")
    parser.add_argument("--networks", type=Path, default=None, help="directory with saved networks")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jacobian", choices=("geometric", "spatial"), default="geometric",
                        help="Jacobian form of the analytic index (spatial: the dexterity paper's eq. 6)")
    args = parser.parse_args()
    os.environ["JAX_PLATFORMS"] = {"gpu": "cuda"}.get(args.device, args.device)

    import jax
    import jax.numpy as jnp

    from uvms_jax import kin, surrogate

    batches = [int(float(b)) for b in args.batches.split(",")]
    chunk = int(args.chunk)
    chain = kin.uvms12()
    key = jax.random.key(args.seed)
    k_q, k_w, k_kci, k_net = jax.random.split(key, 4)
    base = surrogate.sample_configurations(k_q, chain, surrogate.Sampling(), 1000, jnp.float32)

    nets = {}
    if args.networks is not None:
        for name in ("ffbn_w", "ffbn_kci", "rbfn_w", "rbfn_kci"):
            nets[name] = surrogate.load_network(args.networks / name)
        source = str(args.networks)
    else:
        data = {i: surrogate.make_dataset(k, chain, surrogate.Sampling(), 1000, i) for i, k in (("w", k_w), ("kci", k_kci))}
        for name, size in (("ffbn_w", 8), ("ffbn_kci", 25), ("rbfn_w", 149), ("rbfn_kci", 142)):
            kind, index = name.split("_")
            k_net, sub = jax.random.split(k_net)
            if kind == "ffbn":
                nets[name] = surrogate.init_ffbn(sub, size, data[index])
            else:
                d = data[index]
                nets[name] = surrogate.RBFN(
                    centres=jax.random.uniform(sub, (size, len(d.inputs)), minval=-1.0, maxval=1.0),
                    weights=jax.random.normal(sub, (size,)), bias=jnp.zeros(()), spread=jnp.asarray(2.0),
                    x_norm=surrogate.fit_scaler(d.x), y_norm=surrogate.fit_scaler(d.y, axis=None),
                    index=index, inputs=d.inputs,
                )
        source = "random weights, paper sizes"

    form = surrogate.IndexForm(args.jacobian)
    fns = {f"analytic_{i}": surrogate.analytic_index_fn(chain, i, form) for i in ("w", "kci")}
    fns.update({name: net.index_fn for name, net in nets.items()})
    results = {}
    for n in batches:
        q = surrogate.tile_batch(base, n)
        c = surrogate.chunk_for(n, chunk)
        row = {}
        for name, fn in fns.items():
            t = surrogate.time_index_fn(fn, q, repeats=args.repeats, chunk=c)
            row[name] = {"seconds": t["seconds"], "per_second": t["per_second"]}
        for name in nets:
            row[name]["speedup_vs_analytic"] = row[f"analytic_{name.split('_')[1]}"]["seconds"] / row[name]["seconds"]
        results[str(n)] = row
    sizes = {name: (net.hidden if name.startswith("ffbn") else net.n_centres) for name, net in nets.items()}
    print(json.dumps({
        "benchmark": "surrogate", "device": jax.devices()[0].device_kind, "platform": jax.devices()[0].platform,
        "python": platform.python_version(), "jax": jax.__version__, "dtype": "float32", "networks": source,
        "hidden_units": sizes, "chunk": chunk, "jacobian": args.jacobian,
        "analytic": "fused kernel (indices.manipulability_of / kci_of, or the same on spatial rows)", "results": results,
    }))


if __name__ == "__main__":
    main()
