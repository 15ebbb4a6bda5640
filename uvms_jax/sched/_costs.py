"""Edge metrics → normalised metrics → cost matrix (thesis 4.7.4, eqs. 4.15–4.17)."""

from __future__ import annotations

from typing import Sequence

import numpy as np

#: The five per-edge metrics, in this order everywhere (weights too), thesis 4.7.4:
#: planning time [s], joint movement Σ|Δq| [rad], end-effector distance Σ|Δp| [m],
#: security = minimum clearance to obstacles [m] (more is better), max joint torque [N·m].
METRICS = ("planning_time", "joint_movement", "ee_distance", "security", "max_torque")
#: The column of each metric in a planner's ``edges.csv`` (one row per move: planner, src,
#: dst, success, then these), in ``METRICS`` order: security is the minimum clearance.
EDGE_CSV_COLUMNS = ("planning_time_s", "joint_movement", "ee_distance", "min_clearance", "max_torque")
#: Metrics where a larger raw value is better, scored so that it costs less.
HIGHER_IS_BETTER = ("security",)


def metric_tensor(src, dst, values, n_nodes: int) -> np.ndarray:
    """Scatters per-edge metric rows into a ``(5, n, n)`` tensor (NaN where no edge).

    Args:
      src, dst: ``(E,)`` int node indices of each edge.
      values: ``(E, 5)`` raw metrics in ``METRICS`` order; a row with a NaN marks a failed
        plan (the move becomes forbidden).
      n_nodes: ``n``.

    Raises:
      ValueError: mismatched lengths, unknown nodes, or an edge given twice.
    """
    src = np.asarray(src, dtype=np.int64)
    dst = np.asarray(dst, dtype=np.int64)
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] != len(METRICS):
        raise ValueError(f"edge metrics must have shape (E, {len(METRICS)}) for {METRICS}; got {values.shape}")
    if not (src.shape == dst.shape == values.shape[:1]):
        raise ValueError(f"src {src.shape}, dst {dst.shape} and metrics {values.shape} disagree on E")
    for name, a in (("src", src), ("dst", dst)):
        bad = (a < 0) | (a >= n_nodes)
        if bad.any():
            raise ValueError(f"unknown {name} node {int(a[bad][0])}: nodes are 0..{n_nodes - 1}")
    flat = src * n_nodes + dst
    uniq, cnt = np.unique(flat, return_counts=True)
    if (cnt > 1).any():
        e = int(uniq[cnt > 1][0])
        raise ValueError(f"edge {e // n_nodes}->{e % n_nodes} is given more than once")
    out = np.full((len(METRICS), n_nodes, n_nodes), np.nan)
    out[:, src, dst] = values.T
    return out


def normalise_metrics(metrics) -> np.ndarray:
    """Min-max normalisation of each metric over all edges that have it (eq. 4.15).

    ``N = (x − min) / (max − min)`` in [0, 1]; for security (``HIGHER_IS_BETTER``)
    ``N = (max − x) / (max − min)`` so larger clearance costs less. A metric that is the
    same on every edge normalises to 0. An edge missing any metric is NaN in all.

    Args:
      metrics: ``(5, n, n)`` raw metrics (``METRICS`` order), NaN = no edge.

    Returns:
      ``(5, n, n)`` normalised metrics.
    """
    m = np.asarray(metrics, dtype=np.float64)
    if m.ndim != 3 or m.shape[0] != len(METRICS) or m.shape[1] != m.shape[2]:
        raise ValueError(f"metrics must have shape ({len(METRICS)}, n, n); got {m.shape}")
    if np.isinf(m).any():
        raise ValueError("metrics contain ±inf; mark missing edges with NaN")
    edge = np.all(np.isfinite(m), axis=0)
    out = np.full(m.shape, np.nan)
    for k, name in enumerate(METRICS):
        x = m[k][edge]
        if x.size == 0:
            continue
        lo, hi = x.min(), x.max()
        span = hi - lo
        z = np.zeros_like(x) if span == 0 else ((hi - x) if name in HIGHER_IS_BETTER else (x - lo)) / span
        out[k][edge] = z
    return out


def cost_matrix(normalised, weights: Sequence[float]) -> np.ndarray:
    """``C = Σ_k K_k · N_k`` (eqs. 4.16–4.17): the ``(n, n)`` cost matrix, NaN = no edge.

    Args:
      normalised: ``(5, n, n)`` from ``normalise_metrics``.
      weights: 5 non-negative weights ``K`` in ``METRICS`` order (thesis Table 4.3: 1/5
        each; scenarios in Tables 5.6–5.9 and A.1–A.5).

    Raises:
      ValueError: wrong number of weights, negative or non-finite weights, all zero.
    """
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (len(METRICS),):
        raise ValueError(f"need {len(METRICS)} weights for {METRICS}; got shape {w.shape}")
    if not np.isfinite(w).all() or (w < 0).any():
        raise ValueError(f"weights must be finite and >= 0; got {w.tolist()}")
    if w.sum() == 0:
        raise ValueError("all weights are zero")
    n = np.asarray(normalised, dtype=np.float64)
    return np.tensordot(w, n, axes=1)


def path_metric_sums(normalised, path: Sequence[int]) -> np.ndarray:
    """``(5,)`` sums of each normalised metric over a schedule's moves (thesis Table 5.2's
    ``N_metric`` column)."""
    p = list(path)
    n = np.asarray(normalised)
    return n[:, p[:-1], p[1:]].sum(axis=1)


def path_totals(metrics, path: Sequence[int]) -> dict[str, float]:
    """Raw metrics ``(5, n, n)`` (:data:`METRICS` order, not normalised, so that two scenes
    compare) along a schedule's moves: sums of planning time [s], joint movement [rad] and tool
    path [m], the smallest clearance [m] and the largest joint torque [N·m]."""
    p = list(path)
    legs = dict(zip(METRICS, np.asarray(metrics)[:, p[:-1], p[1:]]))  # each (moves,)
    return {"planning_time_s": float(np.sum(legs["planning_time"])),
            "joint_movement_rad": float(np.sum(legs["joint_movement"])),
            "ee_distance_m": float(np.sum(legs["ee_distance"])), "min_clearance_m": float(np.min(legs["security"])),
            "max_torque_Nm": float(np.max(legs["max_torque"]))}


def mirror_goal(metrics, start: int, goal: int) -> np.ndarray:
    """Copies the metrics of moves into ``start`` to the same moves into ``goal`` where the
    latter are missing (the thesis's goal is the start position, Table 5.1)."""
    m = np.array(metrics, dtype=np.float64)
    missing = np.isnan(m[:, :, goal])
    m[:, :, goal] = np.where(missing, m[:, :, start], m[:, :, goal])
    return m
