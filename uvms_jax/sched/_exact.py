"""Exact scheduling by dynamic programming over (placed objects, used bases, position)."""

from __future__ import annotations

import time
from math import comb

import numpy as np

from uvms_jax.sched._problem import PickPlaceProblem, path_cost
from uvms_jax.sched._schedule import Schedule

#: Largest DP layer (gathered candidates) the solver builds, in float64 entries (~1.6 GB).
MAX_LAYER_ENTRIES = 200_000_000


def exact(problem: PickPlaceProblem) -> Schedule:
    """The optimal schedule (the ground truth for the other solvers).

    State after ``k`` deliveries: ``(P, U, b)`` — the set ``P`` of placed objects, the set
    ``U`` of used bases (``|P| = |U| = k``; with compatibility and one object per base the
    used bases matter, not only their number) and the base ``b ∈ U`` the arm stands at.
    One DP step picks an unplaced object ``o`` — directly or through the start, whichever is
    cheaper (``min(C[b, o], C[b, start] + C[start, o])``; every schedule move that is not a
    delivery is such a pick, so this loses nothing) — and delivers it to a free allowed
    base ``b'``. The value ``D_{k+1}[P', U', b'] = min_o A_k[P' − o, U' − b', o] + C[o, b']``
    with ``A_k[P, U, o] = min_b D_k[P, U, b] + pick(b, o)`` is computed one layer at a time
    with vectorised NumPy gathers (float64). The answer adds the last move into the goal.

    Complexity: ``Σ_k C(N, k) C(M, k) · N · M`` — 18.5 M candidates for 10 objects and 10
    bases.

    Raises:
      ValueError: the DP would be too large (``MAX_LAYER_ENTRIES``); use ``astar``/``grasp``.

    Returns:
      ``Schedule`` with ``info["states"]`` (number of ``(P, U, b)`` states).
    """
    t0 = time.perf_counter()
    N, M = problem.n_objects, problem.n_bases
    peak = max(comb(N, c) * comb(M, c) * c * c for c in range(min(N, M) + 1))
    if peak > MAX_LAYER_ENTRIES:
        raise ValueError(
            f"exact DP too large for {N} objects and {M} bases ({peak:,} candidates in one "
            f"layer > {MAX_LAYER_ENTRIES:,}); use astar or grasp"
        )
    mc = np.asarray(problem.move_cost, dtype=np.float64)
    objs, bases = np.array(problem.objects), np.array(problem.bases)
    s, goal = problem.start, problem.goal
    c_start_obj = mc[s, objs]  # (N,)
    direct = mc[np.ix_(bases, objs)]  # (M, N)
    through = mc[bases, s][:, None] + c_start_obj[None, :]
    via_start = through < direct
    pick = np.minimum(direct, through)  # (M, N)
    deliver = mc[np.ix_(objs, bases)].T  # (M, N): [b', o] = C[o, b']
    c_goal = mc[bases, goal]  # (M,)

    P = _Layers(N)
    U = _Layers(M)
    if N > M:
        return Schedule((), float("inf"), time.perf_counter() - t0, "exact", {"states": 0})
    D, arg_A, arg_D, n_states = _forward(P, U, c_start_obj, pick, deliver)
    total = D[0] + c_goal[U.members[N]]  # (nU, N slots): all objects placed
    iu, tb = np.unravel_index(int(np.argmin(total)), total.shape)
    if not np.isfinite(total[iu, tb]):
        return Schedule((), float("inf"), time.perf_counter() - t0, "exact", {"states": n_states})
    rev = _backtrack(P, U, arg_A, arg_D, int(iu), int(tb), via_start, (s, goal, objs, bases))
    path = tuple(reversed(rev))
    return Schedule(path, path_cost(problem, path), time.perf_counter() - t0, "exact", {"states": n_states})


def _forward(P: "_Layers", U: "_Layers", c_start_obj: np.ndarray, pick: np.ndarray,
             deliver: np.ndarray) -> tuple[np.ndarray, list, list, int]:
    """The DP's layers, one per number of delivered objects (:func:`exact`'s docstring).

    Layer c holds D_c[iP, iU, tb]: the cheapest way to have placed the objects of P (index iP
    among the sets of c objects) on the bases of U, standing at U's tb-th base. Sets are
    stored with their members (``P.members[c]``), so only predecessors that exist are
    gathered: (P − o, U − b) for o ∈ P, b ∈ U.

    Returns:
      the last layer ``D (1, nU, N)``, the argmins of each layer's pick (``arg_A``) and
      delivery (``arg_D``), and the number of finite states.
    """
    N = P.n
    A = c_start_obj[None, :, None]  # A_0[iP, o, iU]: layer 0 has only the start
    arg_A = [np.full((1, 1, N), -1, dtype=np.int16)]  # [iP, iU, o] slot picked from, -1 = start
    arg_D = [None]
    n_states = 1
    for c in range(1, N + 1):
        mp, mu = P.members[c], U.members[c]  # (nP, c), (nU, c)
        # stage 1: rows A[P − o, o, :] (nP, c, nU_prev); stage 2: columns U − b
        rows = A[P.prev[c], mp]
        cand = np.take(rows, U.prev[c], axis=2)  # (nP, c_o, nU, c_b)
        cand += np.take(deliver[mu], mp, axis=2).transpose(2, 3, 0, 1)  # [b, o] → [iP, to, iU, tb]
        arg_o = np.argmin(cand, axis=1).astype(np.int16)  # (nP, nU, c_b)
        D = np.take_along_axis(cand, arg_o[:, None].astype(np.intp), axis=1)[:, 0]
        del cand, rows
        arg_D.append(arg_o)
        n_states += int(np.isfinite(D).sum())
        if c < N:
            pk = pick[mu]  # (nU, c, N): from each used base to each object
            A = np.full((D.shape[0], D.shape[1], N), np.inf)
            arg = np.full(A.shape, -1, dtype=np.int16)
            for tb in range(c):
                v = D[:, :, tb, None] + pk[None, :, tb, :]
                better = v < A
                A = np.where(better, v, A)
                arg = np.where(better, np.int16(tb), arg)
            arg_A.append(arg)
            A = np.ascontiguousarray(A.transpose(0, 2, 1))  # [iP, o, iU] for row gathers
    return D, arg_A, arg_D, n_states


def _backtrack(P: "_Layers", U: "_Layers", arg_A: list, arg_D: list, iu: int, tb: int, via_start: np.ndarray,
               nodes: tuple) -> list[int]:
    """The optimal schedule's nodes, goal first, from the DP's argmins and the best final
    state ``(all objects, U's iu-th set, its tb-th base)``; ``nodes`` is ``(start, goal,
    object nodes, base nodes)``."""
    s, goal, objs, bases = nodes
    rev = [goal]
    ip = 0
    for c in range(P.n, 0, -1):
        to = int(arg_D[c][ip, iu, tb])
        o = int(P.members[c][ip, to])
        j = int(U.members[c][iu, tb])
        rev += [int(bases[j]), int(objs[o])]
        ip, iu = int(P.prev[c][ip, to]), int(U.prev[c][iu, tb])
        tb = int(arg_A[c - 1][ip, iu, o])
        if tb >= 0 and via_start[int(U.members[c - 1][iu, tb]), o]:
            rev.append(s)
    rev.append(s)
    return rev

class _Layers:
    """Subsets of ``n`` items grouped by size ``c``: ``members[c]`` ``(count, c)`` sorted
    items of each subset, ``prev[c]`` ``(count, c)`` index (in group ``c − 1``) of the subset
    without each member."""

    def __init__(self, n: int):
        self.n = n
        masks = np.arange(1 << n, dtype=np.int64)
        bits = (masks[:, None] >> np.arange(n)) & 1
        pop = bits.sum(axis=1)
        index = np.zeros(1 << n, dtype=np.int64)
        self.members, self.prev = [], []
        for c in range(n + 1):
            g = masks[pop == c]
            index[g] = np.arange(len(g))
            members = np.nonzero(bits[g])[1].reshape(len(g), c)
            self.members.append(members)
            self.prev.append(index[g[:, None] ^ (1 << members)] if c else members)
