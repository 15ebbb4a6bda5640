"""Throughput of w and KCI: uvms_jax vs pytorch-kinematics, one process.

Prints one JSON object. Both sides evaluate the same chain (pytorch-kinematics loads the URDF
exported by ``uvms_jax.kin.to_urdf``) on the same device, in float32:
  uvms_jax: one jitted call ``manipulability_of(chain, q, task)`` (fused Jacobian + unrolled
            Gram–Schmidt) / ``kci_of(chain, q, task)`` (Jacobian + unrolled one-sided Jacobi);
            on a GPU these run as one Pallas kernel, and the XLA fusion they replace is timed
            too (``uvms_jax_xla_*``);
  gram:     the same paths with the previous index forms, which factor ``J Jᵀ`` instead of J
            (unrolled Cholesky for w, symmetric Jacobi for KCI): their speed, and both forms'
            float32 error near singular poses (``accuracy``);
  peer:     ``chain.jacobian(q)``, the task rows, then ``sqrt(det G)`` of the smaller Gram
            matrix G (J Jᵀ or Jᵀ J) / ``svdvals`` in torch.
The chain is the 12-DOF UVMS by default, or any arm imported with ``--urdf`` (e.g. a 4-DOF
arm with ``--task full`` exercises the ``sqrt(det Jᵀ J)`` path).

Usage: python benchmarks/kin_indices.py [--device cpu|cuda] [--batches 1e3,1e4,1e5,1e6]
       [--urdf FILE --base LINK --tip LINK] [--task full|position|orientation|vx,vy,vz,wz]
"""

from __future__ import annotations

import argparse
import functools
import platform
import time

import jax
import jax.numpy as jnp
import numpy as np
import pytorch_kinematics as pk
import torch

from uvms_jax import indices, kin, robot
from uvms_jax.files import json_text
from uvms_jax.indices import _gpu
from uvms_jax.indices._indices import _kci_of, _manipulability_of, _safe_inverse, _safe_sqrt, _vectors

jax.config.update("jax_enable_x64", True)  # the float64 reference of ``accuracy``; timings stay float32


def gram_of(rows) -> list:
    """The smaller Gram matrix of J given as rows of scalars (J Jᵀ, or Jᵀ J for a tall J)."""
    V = _vectors(rows)
    return [[sum(a * b for a, b in zip(u, v)) for v in V] for u in V]


def gram_w_from_rows(rows):
    """The previous w: ``∏ diag(chol(G))`` — an unrolled Cholesky of the Gram matrix."""
    G = gram_of(rows)
    m = len(G)
    L = [[None] * m for _ in range(m)]
    w = 1.0
    for j in range(m):
        d = _safe_sqrt(G[j][j] - sum((L[j][k] ** 2 for k in range(j)), start=0.0))
        w = w * d
        for i in range(j + 1, m):
            L[i][j] = (G[i][j] - sum((L[i][k] * L[j][k] for k in range(j)), start=0.0)) * _safe_inverse(d)
        L[j][j] = d
    return w


def gram_kci_from_rows(rows, sweeps: int = 8):
    """The previous KCI: ``sqrt(λmin / λmax)`` of the Gram matrix by cyclic symmetric Jacobi."""
    G = gram_of(rows)
    m = len(G)
    flat = jnp.broadcast_arrays(*[x for row in G for x in row])
    G = [list(flat[i * m : (i + 1) * m]) for i in range(m)]

    def sweep(_, A):
        A = [list(row) for row in A]
        for p in range(m - 1):
            for q in range(p + 1, m):
                apq, d = A[p][q], A[q][q] - A[p][p]
                t = 2.0 * apq * jnp.where(d < 0, -1.0, 1.0) * _safe_inverse(jnp.abs(d) + _safe_sqrt(d * d + 4.0 * apq * apq))
                c = 1.0 / jnp.sqrt(1.0 + t * t)
                s = t * c
                for r in range(m):
                    if r not in (p, q):
                        arp, arq = A[r][p], A[r][q]
                        A[r][p] = A[p][r] = c * arp - s * arq
                        A[r][q] = A[q][r] = s * arp + c * arq
                A[p][p], A[q][q] = A[p][p] - t * apq, A[q][q] + t * apq
                A[p][q] = A[q][p] = jnp.zeros_like(apq)
        return A

    A = jax.lax.fori_loop(0, sweeps, sweep, G)
    lam = [A[i][i] for i in range(m)]
    lmin, lmax = jnp.maximum(functools.reduce(jnp.minimum, lam), 0.0), functools.reduce(jnp.maximum, lam)
    return _safe_sqrt(lmin * _safe_inverse(lmax))


def accuracy(chain, rows: tuple, fns: dict, n: int) -> dict:
    """Max float32 error of each form against float64 singular values (numpy's SVD), over
    ``2 n`` near-singular poses and ``n`` uniform ones: w's relative to the set's largest w."""
    lo, hi = np.maximum(np.asarray(chain.lower), -1.0), np.minimum(np.asarray(chain.upper), 1.0)
    q = np.concatenate([*indices.near_singular_poses(chain, n, rows), lo + np.random.default_rng(1).random((n, chain.n_joints)) * (hi - lo)])
    sigma = np.linalg.svd(np.asarray(kin.jacobian(chain, q))[:, list(rows)], compute_uv=False)
    reference = {"w": sigma.prod(-1), "kci": sigma[:, -1] / sigma[:, 0]}
    q32 = jnp.asarray(q, jnp.float32)
    out = {"configurations": len(q), "median_sigma_min_near_singular": float(np.median(sigma[: 2 * n, -1]))}
    for (form, index), fn in fns.items():
        err = np.abs(np.asarray(fn(q32), np.float64) - reference[index]).max()
        out[f"{form}_{index}_max_abs_err"] = float(err / (reference["w"].max() if index == "w" else 1.0))
    return out


def best_time(fn, repeats: int, budget_s: float = 20.0) -> float:
    """Best wall time of ``fn()`` over ``repeats`` runs (after one warm-up), within a budget."""
    fn()
    times = []
    start = time.perf_counter()
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
        if time.perf_counter() - start > budget_s:
            break
    return min(times)


def measure_peer(q, check, w_fn, peer_w, peer_kci, tdev, sync, repeats) -> dict:
    """pytorch-kinematics throughput on the same configurations, and its agreement with ours."""
    n = q.shape[0]
    qt = torch.from_numpy(np.array(q)).to(tdev)
    ours = np.asarray(w_fn(jnp.asarray(check)))
    theirs = peer_w(torch.from_numpy(check.copy()).to(tdev)).cpu().numpy()
    # Relative to the largest w: near a singularity the peer's float32 det(J Jᵀ) is the less
    # accurate of the two, so a pointwise relative difference would measure the peer.
    out = {"max_diff_w_over_max_w": float(np.max(np.abs(ours - theirs)) / np.max(np.abs(theirs)))}
    with torch.no_grad():
        out["peer_w_per_s"] = n / best_time(lambda: (peer_w(qt), sync()), repeats)
        out["peer_kci_per_s"] = n / best_time(lambda: (peer_kci(qt), sync()), repeats)
    return out


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cpu", choices=["cpu", "cuda"])
    parser.add_argument("--batches", default="1e3,1e4,1e5,1e6")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--peer-max-batch", type=float, default=1e7, help="skip the peer above this batch")
    parser.add_argument("--urdf", default=None, help="benchmark this arm instead of the 12-DOF UVMS")
    parser.add_argument("--base", default=None, help="base link of --urdf (default: its root)")
    parser.add_argument("--tip", default=None, help="tip link of --urdf (default: its only leaf)")
    parser.add_argument("--task", default="full", help="full, position, orientation or rows, e.g. vx,vy,vz,wz")
    parser.add_argument("--accuracy-poses", type=int, default=2000, help="near-singular poses of the accuracy check")
    return parser


def _gram_fns(chain, rows_) -> dict:
    """The previous (Gram) forms of w and KCI through the same paths: one Pallas kernel on a
    GPU, else the XLA fusion of the unrolled Jacobian, as they ran."""
    gram_xla = {"w": lambda chain, q, rows: gram_w_from_rows([kin.jacobian_rows(chain, q)[r] for r in rows]),
                "kci": lambda chain, q, rows: gram_kci_from_rows([kin.jacobian_rows(chain, q)[r] for r in rows])}
    gram_form = {"w": gram_w_from_rows, "kci": gram_kci_from_rows}

    def gram_fn(index):
        if jax.default_backend() == "gpu":
            return jax.jit(lambda q: _gpu.index_on_gpu(gram_form[index], gram_xla[index], chain, q, rows_))
        return jax.jit(lambda q: gram_xla[index](chain, q, rows_))

    return {index: gram_fn(index) for index in gram_form}


def _peer_fns(chain, task_idx: list[int], device: str) -> tuple:
    """pytorch-kinematics' w and KCI of the chain on ``device``, the torch device and a sync."""
    tdev = torch.device(device)
    peer = pk.build_serial_chain_from_urdf(kin.to_urdf(chain), "tool").to(dtype=torch.float32, device=tdev)

    def peer_w(q):
        J = peer.jacobian(q)[:, task_idx]
        G = J @ J.transpose(-1, -2) if J.shape[-2] <= J.shape[-1] else J.transpose(-1, -2) @ J
        return torch.sqrt(torch.clamp(torch.linalg.det(G), min=0.0))

    def peer_kci(q):
        s = torch.linalg.svdvals(peer.jacobian(q)[:, task_idx])
        return s[..., -1] / s[..., 0]

    def sync():
        if device == "cuda":
            torch.cuda.synchronize()

    return peer_w, peer_kci, tdev, sync


def main() -> None:
    args = _parser().parse_args()
    batches = [int(float(b)) for b in args.batches.split(",")]
    task = args.task if args.task in ("full", "position", "orientation") else tuple(args.task.split(","))
    task_idx = list(indices.task_rows(task))

    chain = kin.uvms12() if args.urdf is None else robot.chain_from_urdf(args.urdf, base_link=args.base, tip_link=args.tip)
    lo = np.maximum(np.asarray(chain.lower), -1.0)
    hi = np.minimum(np.asarray(chain.upper), 1.0)
    w_fn = jax.jit(lambda q: indices.manipulability_of(chain, q, task))
    kci_fn = jax.jit(lambda q: indices.kci_of(chain, q, task))
    # On a GPU the two calls above run the Pallas kernel; the XLA fusion they replace, for comparison.
    rows_ = indices.task_rows(task)
    xla_fns = {"w": jax.jit(lambda q: _manipulability_of(chain, q, rows_)),
               "kci": jax.jit(lambda q: _kci_of(chain, q, rows_))}
    gram_fns = _gram_fns(chain, rows_)
    acc = accuracy(chain, rows_, {("uvms_jax", "w"): w_fn, ("uvms_jax", "kci"): kci_fn,
                                  ("gram", "w"): gram_fns["w"], ("gram", "kci"): gram_fns["kci"]}, args.accuracy_poses)

    peer_w, peer_kci, tdev, sync = _peer_fns(chain, task_idx, args.device)
    rows = []
    for n in batches:
        key = jax.random.key(n)
        q = jax.random.uniform(key, (n, chain.n_joints), jnp.float32, lo, hi)
        q.block_until_ready()
        row = {"batch": n}
        check = np.asarray(q[: min(n, 1000)])  # both sides must compute the same numbers
        t = best_time(lambda: w_fn(q).block_until_ready(), args.repeats)
        row["uvms_jax_w_per_s"] = n / t
        t = best_time(lambda: kci_fn(q).block_until_ready(), args.repeats)
        row["uvms_jax_kci_per_s"] = n / t
        for name, fn in gram_fns.items():
            row[f"gram_{name}_per_s"] = n / best_time(lambda: fn(q).block_until_ready(), args.repeats)
        if jax.default_backend() == "gpu":
            for name, fn in xla_fns.items():
                row[f"uvms_jax_xla_{name}_per_s"] = n / best_time(lambda: fn(q).block_until_ready(), args.repeats)
            head = q[:100000]
            for name, fn in (("w", w_fn), ("kci", kci_fn)):
                row[f"kernel_vs_xla_max_abs_diff_{name}"] = float(jnp.max(jnp.abs(fn(head) - xla_fns[name](head))))
        if n <= args.peer_max_batch:
            try:
                row.update(measure_peer(q, check, w_fn, peer_w, peer_kci, tdev, sync, args.repeats))
                row["w_speedup"] = row["uvms_jax_w_per_s"] / row["peer_w_per_s"]
                row["kci_speedup"] = row["uvms_jax_kci_per_s"] / row["peer_kci_per_s"]
            except torch.OutOfMemoryError as err:  # the peer materialises (B, frames, 4, 4)
                row["peer_error"] = str(err).splitlines()[0][:120]
            if args.device == "cuda":
                torch.cuda.empty_cache()
        rows.append(row)

    print(
        json_text(
            {
                "benchmark": "kin_indices",
                "chain": chain.name,
                "n_joints": chain.n_joints,
                "task": task_idx,
                "dtype": "float32",
                "jax_device": str(jax.devices()[0]),
                "torch_device": args.device,
                "machine": platform.machine(),
                "jax": jax.__version__,
                "torch": torch.__version__,
                "accuracy": acc,
                "results": rows,
            },
        )
    )


if __name__ == "__main__":
    main()
