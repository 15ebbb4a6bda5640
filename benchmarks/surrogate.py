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

``--grid N`` also times w over the first N points of a joint grid (8 or 16 values per input
joint of FFBN-w, θ5…θ11, across the range of the sampled configurations; the other joints held at
one sampled configuration). The analytic kernel reads the grid's configurations from memory,
stored before timing; FFBN-w computes each configuration from its int32 grid index inside its
own program, as a dense evaluation would, so it reads 4 bytes per sample instead of 48. Both
give the same configurations (checked). This measures what each evaluator costs once its
input is in registers: a stored float32 batch of 12 joints caps any network near 7e10/s on an
H100 (3.35 TB/s / 48 B).

Usage: python benchmarks/surrogate.py [--device cpu|gpu] [--batches 1e3,1e4,1e5,1e6] [--networks DIR]
                                     [--jacobian geometric|spatial] [--grid 1e7]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from pathlib import Path

from uvms_jax.files import json_text


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
    parser.add_argument("--grid", type=float, default=None, help="also time w over this many joint-grid points")
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
    grid = (None if args.grid is None
            else _time_grid(int(args.grid), base, fns["analytic_w"], nets["ffbn_w"], args.repeats))
    sizes = {name: (net.hidden if name.startswith("ffbn") else net.n_centres) for name, net in nets.items()}
    print(json_text({
        "benchmark": "surrogate", "command": " ".join(["python benchmarks/surrogate.py", *sys.argv[1:]]),
        "device": jax.devices()[0].device_kind, "platform": jax.devices()[0].platform,
        "python": platform.python_version(), "jax": jax.__version__, "dtype": "float32", "networks": source,
        "hidden_units": sizes, "chunk": chunk, "jacobian": args.jacobian,
        "analytic": "fused kernel (indices.manipulability_of / kci_of, or the same on spatial rows)", "results": results,
        "grid": grid,
    }))


def _time_grid(n: int, base, analytic_w, ffbn_w, repeats: int) -> dict:
    """w at the first ``n`` points of a joint grid over FFBN-w's inputs (see the module
    docstring): the analytic kernel on the stored configurations, FFBN-w on stored
    configurations and from grid indices."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from uvms_jax import surrogate

    inputs = ffbn_w.inputs
    lo, hi = jnp.min(base[:, list(inputs)], axis=0), jnp.max(base[:, list(inputs)], axis=0)
    # A power-of-two number of values per joint, so a joint's grid step is a bit field of the
    # index (a shift and a mask; integer division would cost more than the network).
    total_bits = max(1, (n - 1).bit_length())
    bits = [total_bits // len(inputs) + (k < total_bits % len(inputs)) for k in range(len(inputs))]
    shifts = np.cumsum([0, *bits[:-1]])
    if total_bits > 31:
        raise ValueError(f"--grid {n} needs more than 31 index bits")

    def configurations(i):  # int32 grid indices (N,) -> (N, n_joints): bit field k of i sets input k
        # Built column by column (no scatter), so XLA fuses it with whatever reads it.
        columns = [jnp.broadcast_to(v, i.shape) for v in base[0]]
        for k, j in enumerate(inputs):
            step = ((i >> int(shifts[k])) & ((1 << bits[k]) - 1)).astype(base.dtype)
            columns[j] = lo[k] + (hi[k] - lo[k]) / ((1 << bits[k]) - 1) * step
        return jnp.stack(columns, axis=-1)

    index = jnp.arange(n, dtype=jnp.int32)
    q = jax.jit(configurations)(index)
    generated = lambda i: ffbn_w.index_fn(configurations(i))
    np.testing.assert_allclose(jax.jit(generated)(index), jax.jit(ffbn_w.index_fn)(q), rtol=1e-5, atol=1e-5)
    rows = {
        "analytic_w_stored": surrogate.time_index_fn(analytic_w, q, repeats=repeats),
        "ffbn_w_stored": surrogate.time_index_fn(ffbn_w.index_fn, q, repeats=repeats),
        "ffbn_w_from_grid_index": surrogate.time_index_fn(generated, index, repeats=repeats),
    }
    out = {name: {"seconds": t["seconds"], "per_second": t["per_second"]} for name, t in rows.items()}
    for name in ("ffbn_w_stored", "ffbn_w_from_grid_index"):
        out[name]["speedup_vs_analytic"] = out["analytic_w_stored"]["seconds"] / out[name]["seconds"]
    return {"points": n, "values_per_joint": [1 << b for b in bits], "inputs": list(inputs), **out}


if __name__ == "__main__":
    main()
