"""Why the surrogate speed tables swing with the batch size: the index functions of
``benchmarks/surrogate.py`` timed in variants that separate the candidate causes.

The surrogate tables (docs/benchmarks/surrogates.md, ``make papers``) time each function at 1e3, 1e5 and 1e6
inputs, the largest in chunks of 1e5 through ``lax.map`` (``surrogate.time_index_fn``), with
calls issued back to back and one wait. Here, at each batch size (UVMS-12 configurations of the
paper's sampling, ``surrogate.tile_batch``, float32), every function is timed

- ``whole``: one jitted call on the whole batch, calls back to back, one wait per timed run;
- ``whole_wait_each``: the same, waiting for each call's result (the timer's part; batches
  below the tables' chunk, where a call is short enough for the wait to matter);
- ``map_<c>``: ``lax.map`` over chunks of ``c`` rows inside one jitted call (the tables' way);
- ``loop_<c>``: a Python loop of jitted calls over the batch pre-split into chunks of ``c``;
- ``reuse_<c>``: one chunk of ``c`` rows evaluated ``N / c`` times (cache-resident input), beside
  ``loop_<c>``'s distinct chunks (input streamed from memory), at the largest batch;

and ``single_thread`` repeats ``whole`` and ``map_<chunk>`` at the tables' chunk and the largest
batch in a child process with XLA's CPU thread pool cut to one thread. Rates are inputs/s: the median and the best of ``--repeats``
timed runs (on a shared machine the best is the steadier figure). Networks have the paper's
sizes (FFBN-w 8, FFBN-KCI 25, RBFN-w 149 units) with random weights: the cost of a network
does not depend on its weight values. ``--fns`` picks the functions (``analytic_kci``,
``rbfn_kci`` are slow at 1e6 and left out by default).

    PYTHONPATH=. JAX_PLATFORMS=cpu python benchmarks/surrogate_batches.py \\
        --out benchmarks/results/surrogate_batches_cpu.json

Usage: python benchmarks/surrogate_batches.py [--batches 1e3,...] [--chunks 1e4,1e5] [--fns a,b] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from uvms_jax.files import json_text, write_json

FUNCTIONS = ("analytic_w", "analytic_kci", "ffbn_w", "ffbn_kci", "rbfn_w", "rbfn_kci")
PAPER_UNITS = {"ffbn_w": 8, "ffbn_kci": 25, "rbfn_w": 149, "rbfn_kci": 142}
#: XLA flags of the one-thread child process (the CPU client's intra-op pool and Eigen's).
SINGLE_THREAD_FLAGS = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batches", default="1e3,1e4,1e5,3e5,1e6")
    ap.add_argument("--chunks", default="1e4,1e5", help="chunk sizes of the map/loop/reuse variants")
    ap.add_argument("--chunk", type=float, default=1e5, help="the tables' chunk size (single-thread child)")
    ap.add_argument("--fns", default="analytic_w,ffbn_w,ffbn_kci,rbfn_w")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--min-run-s", type=float, default=0.05, help="least length of one timed run [s]")
    ap.add_argument("--out", type=Path, default=None, help="also write the JSON object here")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    batches = [int(float(b)) for b in args.batches.split(",")]
    chunks = [int(float(c)) for c in args.chunks.split(",")]
    names = args.fns.split(",")
    if unknown := sorted(set(names) - set(FUNCTIONS)):
        raise ValueError(f"unknown functions {unknown}; expected some of {FUNCTIONS}")
    load = os.getloadavg()
    t0 = time.perf_counter()
    if args.child:
        print(json.dumps(_measure(names, batches, [int(args.chunk)], args, full=False)))
        return
    results = _measure(names, batches, chunks, args, full=True)
    big = sorted({n for n in (int(args.chunk), max(batches)) if n in batches})
    child = None if not big else subprocess.run(
        [sys.executable, __file__, "--child", "--batches", ",".join(map(str, big)), "--chunk", str(int(args.chunk)),
         "--fns", args.fns, "--repeats", str(args.repeats), "--min-run-s", str(args.min_run_s)],
        env={**os.environ, "XLA_FLAGS": f"{os.environ.get('XLA_FLAGS', '')} {SINGLE_THREAD_FLAGS}".strip()},
        capture_output=True, text=True, check=True)
    import jax

    record = {
        "benchmark": "surrogate_batches", "command": " ".join(["python benchmarks/surrogate_batches.py", *sys.argv[1:]]),
        "device": jax.devices()[0].device_kind, "platform": jax.devices()[0].platform, "cpu_count": os.cpu_count(),
        "python": platform.python_version(), "jax": jax.__version__, "dtype": "float32",
        "load_average_1min": {"start": load[0], "end": os.getloadavg()[0]},
        "networks": "random weights, paper sizes", "hidden_units": {n: PAPER_UNITS[n] for n in names if n in PAPER_UNITS},
        "unit": "inputs/s, median and best of the timed runs", "table_chunk": int(args.chunk),
        "results": results, "single_thread": {"xla_flags": SINGLE_THREAD_FLAGS, "results": None if child is None else json.loads(child.stdout)},
        "seconds": time.perf_counter() - t0,
    }
    print(json_text(record))
    if args.out is not None:
        write_json(args.out, record)


def _functions(names: list[str]) -> dict:
    """The index functions ``q: (N, 12) → (N,)`` of ``names``, built as ``benchmarks/surrogate.py`` does."""
    import jax
    import jax.numpy as jnp

    from uvms_jax import kin, surrogate

    chain, key = kin.uvms12(), jax.random.key(0)
    fns = {}
    for name in names:
        kind, index = name.split("_")
        key, k_data, k_net = jax.random.split(key, 3)
        if kind == "analytic":
            fns[name] = surrogate.analytic_index_fn(chain, index)
            continue
        data = surrogate.make_dataset(k_data, chain, surrogate.Sampling(), 200, index)
        if kind == "ffbn":
            net = surrogate.init_ffbn(k_net, PAPER_UNITS[name], data)
        else:
            net = surrogate.RBFN(
                centres=jax.random.uniform(k_net, (PAPER_UNITS[name], len(data.inputs)), minval=-1.0, maxval=1.0),
                weights=jax.random.normal(k_net, (PAPER_UNITS[name],)), bias=jnp.zeros(()), spread=jnp.asarray(2.0),
                x_norm=surrogate.fit_scaler(data.x), y_norm=surrogate.fit_scaler(data.y, axis=None),
                index=index, inputs=data.inputs)
        fns[name] = net.index_fn
    return fns


def _measure(names: list[str], batches: list[int], chunks: list[int], args, *, full: bool) -> dict:
    """``{fn: {batch: {variant: {"median", "best"}}}}`` (see the module docstring)."""
    import jax

    from uvms_jax import kin, surrogate

    base = surrogate.sample_configurations(jax.random.key(1), kin.uvms12(), surrogate.Sampling(), 1000)
    out = {}
    for name, fn in _functions(names).items():
        whole = jax.jit(fn)
        out[name] = {}
        for n in batches:
            q = surrogate.tile_batch(base, n)
            row = {"whole": _rate(lambda: whole(q), n, args)}
            if full and n < int(args.chunk):
                row["whole_wait_each"] = _rate(lambda: whole(q), n, args, wait_each=True)
            for c in chunks:
                if n <= c or n % c:
                    continue
                mapped = jax.jit(lambda q, c=c: jax.lax.map(fn, q.reshape(-1, c, q.shape[-1])).reshape(-1))
                row[f"map_{c}"] = _rate(lambda: mapped(q), n, args)
                if full:
                    parts = [q[i:i + c] for i in range(0, n, c)]
                    row[f"loop_{c}"] = _rate(lambda: [whole(p) for p in parts], n, args)
                    if n == max(batches):
                        row[f"reuse_{c}"] = _rate(lambda: [whole(parts[0]) for _ in parts], n, args)
            out[name][str(n)] = row
            print(f"{name} {n}: " + ", ".join(f"{k} {v['best']:.3g}" for k, v in row.items()), file=sys.stderr)
    return out


def _rate(call, n: int, args, *, wait_each: bool = False) -> dict:
    """Inputs/s of ``call()`` (one evaluation of ``n`` inputs; returns an array or a list of
    them): compiled and run once beforehand; each timed run issues as many calls as fill
    ``args.min_run_s`` and waits once at its end, or after every call with ``wait_each``."""
    import jax
    import numpy as np

    jax.block_until_ready(call())
    t0 = time.perf_counter()
    jax.block_until_ready(call())
    calls = max(1, int(args.min_run_s / max(time.perf_counter() - t0, 1e-9)))
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            res = call()
            if wait_each:
                jax.block_until_ready(res)
        jax.block_until_ready(res)
        times.append((time.perf_counter() - t0) / calls)
    return {"median": n / float(np.median(times)), "best": n / float(np.min(times))}


if __name__ == "__main__":
    main()
