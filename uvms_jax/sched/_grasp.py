"""GRASP (thesis 4.7.2, Algorithms 2–4): every iteration in parallel, in one jitted call.

Per iteration (written for one iteration, batched with ``vmap``): a randomised greedy
construction over nodes (``construct``), then a swap local search, and the best iteration's
node path. Two local searches (``local_search=``):

- ``"deliveries"`` (default, ``local_search``): swaps whole deliveries (and bases or objects
  between them) instead of single nodes, takes the best improving swap per round, and
  re-decides each return to the start;
- ``"thesis"`` (``thesis_local_search``): the thesis's Algorithm 4 as written — single nodes
  of the path swapped with each of the next three, a swap kept when the schedule stays valid
  and gets cheaper (one pass, first improvement).

Per-step uniforms come from a counter-based hash of one threefry seed per iteration.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from uvms_jax.sched._problem import PAD_NODE, PickPlaceProblem, path_cost
from uvms_jax.sched._rules import BASE, OBJECT, allowed_next, consumed
from uvms_jax.sched._schedule import Schedule
from uvms_jax.sched._score import score

#: Thesis eq. 4.6: the values α is drawn from (uniformly, once per iteration).
THESIS_ALPHAS = (0.1, 0.2, 0.3, 0.4, 0.6, 0.7, 0.8, 0.9, 1.0)
#: Thesis 4.7.2.2: each element is swapped with up to three following ones.
THESIS_NEIGHBOURHOOD = 3
#: Local-search rounds (one best improving swap each). With 4, GRASP(1000) reached the
#: brute-force optimum on every tested instance (tests/sched/test_sched_solvers.py, 5 key
#: sets); with 2, on 95–98 %.
DEFAULT_ROUNDS = 4
#: Local searches: ours over deliveries (default) and the thesis's node swaps (Algorithm 4).
LOCAL_SEARCHES = ("deliveries", "thesis")
_RCL_EPS = 1e-4  # float32 α·|CL| = 2.9999998 must still give an RCL of 3


class Construction(NamedTuple):
    """One constructed schedule: ``path`` ``(L,)`` (padding node ``n``), ``cost``
    (``inf`` if stuck), and its deliveries in order, ``objs`` and ``bases`` ``(N,)``."""

    path: Array
    cost: Array
    objs: Array
    bases: Array


class GraspBatch(NamedTuple):
    """All GRASP iterations of one call.

    Attributes:
      paths: ``(I, L)`` int32 schedules (``L = 3N + 1``), padded with the padding node ``n``
        (``-1`` in user-facing paths); an iteration stuck in a dead end is incomplete.
      costs: ``(I,)`` float32 costs after local search, ``inf`` when stuck.
      construction_costs: ``(I,)`` float32 costs before local search.
    """

    paths: Array
    costs: Array
    construction_costs: Array


def construct(problem: PickPlaceProblem, alpha: Array, u: Array) -> Construction:
    """One randomised greedy construction (thesis Algorithm 3) for one iteration.

    At every step the candidate list CL holds the moves allowed now (occupancy included);
    the RCL is its ``max(1, ⌊α·|CL|⌋)`` cheapest members (eq. 4.5, ties by node index), and
    one of them is taken uniformly at random.

    Args:
      problem: the instance (its ``move_cost`` and ``kind`` leaves are used).
      alpha: scalar α ∈ (0, 1].
      u: ``(L − 1,)`` uniforms in ``[0, 1)``, one per step.

    Returns:
      ``Construction``: the node path, its cost (``inf`` if it got stuck) and its
      deliveries in order.
    """
    W = jnp.asarray(problem.move_cost, jnp.float32)
    kind = jnp.asarray(problem.kind)
    table = jnp.asarray(problem.next_ok)
    takes = consumed(kind)
    n1 = W.shape[0]
    n_obj = problem.n_objects
    # each row's moves sorted by cost once (stable: ties by node index); a step then only
    # masks the sorted row by the allowed moves and counts, O(n) instead of ranking, O(n²)
    order = jnp.argsort(W, axis=1, stable=True).astype(jnp.int32)
    # cumulative count as a float matmul: faster on the CPU than cumsum or an int matmul
    counts_before = jnp.tril(jnp.ones((n1, n1), jnp.float32))

    slot = jnp.arange(n_obj)

    def step(carry, u_t):
        pos, visited, placed, objs, bases = carry
        row_order = order[pos]
        cand = allowed_next(table, pos, visited, placed, n_obj)[row_order]  # CL, cheapest first
        cum = (counts_before @ cand.astype(jnp.float32)).astype(jnp.int32)  # CL among first i+1
        n_cand = cum[-1]
        r = jnp.maximum(1, jnp.floor(alpha * n_cand + _RCL_EPS).astype(jnp.int32))
        pick = jnp.minimum(jnp.floor(u_t * r).astype(jnp.int32), r - 1)
        nxt = row_order[jnp.argmax(cum > pick)]
        nxt = jnp.where(n_cand > 0, nxt, n1 - 1).astype(jnp.int32)  # stuck: pad → cost inf
        k = kind[nxt]
        visited = visited | ((jnp.arange(n1) == nxt) & takes)
        # the deliveries, recorded as they are made (no compaction of the path later)
        objs = jnp.where((slot == placed) & (k == OBJECT), nxt, objs)
        bases = jnp.where((slot == placed) & (k == BASE), nxt, bases)
        return (nxt, visited, placed + (k == BASE), objs, bases), nxt

    none = jnp.full(n_obj, n1 - 1, jnp.int32)
    init = (jnp.int32(problem.start), jnp.zeros(n1, bool), jnp.int32(0), none, none)
    (_, _, _, objs, bases), rest = jax.lax.scan(step, init, u)
    path = jnp.concatenate([jnp.array([problem.start], jnp.int32), rest.astype(jnp.int32)])
    return Construction(path, _cost(W, path), objs, bases)


def local_search(
    problem: PickPlaceProblem,
    objs: Array,
    bases: Array,
    cost: Array,
    neighbourhood: int = THESIS_NEIGHBOURHOOD,
    rounds: int = DEFAULT_ROUNDS,
) -> tuple[Array, Array, Array]:
    """Swap local search (thesis 4.7.2.2, Algorithm 4) on one schedule.

    The elements swapped are the deliveries (an object with its base — the thesis's reason
    for a neighbourhood of more than two nodes): delivery ``k`` is tried against each of
    the next ``neighbourhood`` deliveries by swapping the two deliveries, only their bases,
    or only their objects. A swap is valid when every move of the new schedule is allowed
    (compatibility, free bases and NaN costs are all in ``move_cost``). Returns to the start
    between deliveries are re-decided for every candidate: the arm goes through the start
    exactly when that is cheaper than the direct move. Each round evaluates every swap at
    once from the few moves it changes and applies the best improving one (best
    improvement instead of the thesis's first improvement: the same neighbourhood, but
    all candidates in one vectorised step).

    Schedule cost in delivery form, with ``bx = [start, b_0 … b_{N−1}]`` (where the arm
    comes from) and ``ox = [o_0 … o_{N−1}, goal]`` (where it goes next):
    ``Σ_k C[o_k, b_k] + Σ_{k=0..N} pick[bx_k, ox_k]``, ``pick[b, o] = min(C[b, o],
    C[b, start] + C[start, o])``.

    Args:
      objs, bases: ``(N,)`` the schedule's deliveries in order (``Construction``).
      cost: its cost (``inf`` = stuck: returned unchanged).
      neighbourhood: how many following deliveries each one is swapped with (thesis: 3).
      rounds: improving swaps applied at most (static).

    Returns:
      ``(objs, bases, cost)`` after the search; ``to_path`` gives the node path.
    """
    W = jnp.asarray(problem.move_cost, jnp.float32)
    s, g = problem.start, problem.goal
    via_start = W[:, s][:, None] + W[s, :][None, :]
    pick = jnp.minimum(W, via_start)  # [b, o]; pick[start, o] = C[start, o] (C[s, s] = inf)
    mv = _swap_moves(problem.n_objects, neighbourhood)

    o, b = objs, bases
    ok = jnp.isfinite(cost)

    def terms(o, b):
        bx = jnp.concatenate([jnp.array([s]), b])
        ox = jnp.concatenate([o, jnp.array([g])])
        return bx, ox, W[o, b], pick[bx, ox]

    def body(_, ob):
        o, b = ob
        bx, ox, w, pk = terms(o, b)
        # Change of cost of every candidate swap from the few moves it touches. The static
        # selections are written as slices (``ox[i]``) that XLA fuses into one loop; only
        # the two table lookups remain gathers.
        w_from = jnp.stack([ox[i] for i in mv.w_o])
        w_to = jnp.stack([bx[i] for i in mv.w_b])
        p_from = jnp.stack([bx[i] for i in mv.p_b])
        p_to = jnp.stack([ox[i] for i in mv.p_o])
        new_w, new_p = W[w_from, w_to], pick[p_from, p_to]
        delta = jnp.stack(
            [
                sum(new_w[t] - w[k] for t, k in ws) + sum(new_p[t] - pk[k] for t, k in ps)
                for ws, ps in mv.touched
            ]
        )
        m = jnp.argmin(delta)
        better = delta[m] < 0  # inf: invalid swap; NaN (stuck schedule): never taken
        perm_o, perm_b = jnp.asarray(mv.perm_o)[m], jnp.asarray(mv.perm_b)[m]
        return jnp.where(better, o[perm_o], o), jnp.where(better, b[perm_b], b)

    if rounds > 0:
        o, b = jax.lax.fori_loop(0, rounds, body, (o, b))
    bx, ox, w, pk = terms(o, b)
    return o, b, jnp.where(ok, w.sum() + pk.sum(), cost)  # the cost of ``to_path(o, b)``


def thesis_local_search(problem: PickPlaceProblem, path: Array, cost: Array,
                        neighbourhood: int = THESIS_NEIGHBOURHOOD) -> tuple[Array, Array]:
    """The thesis's local search (4.7.2.2, Algorithm 4) on one node path.

    Every position ``i`` of the path after the start, in order, is swapped with each of the
    next ``neighbourhood`` positions; a swap is kept when the new path is a valid schedule
    (``score``: move rules, occupancy, NaN costs) and cheaper than the current one (the
    thesis's "if change is valid … if costNewPath < costOriginalPath"). One pass.

    Args:
      path: ``(L,)`` node path padded with the padding node ``n`` (as ``construct`` gives).
      cost: its cost (``inf`` = stuck: returned unchanged).

    Returns:
      ``(path, cost)`` after the pass.
    """
    n, L = problem.n_nodes, path.shape[0]
    pairs = np.array([(i, j) for i in range(1, L) for j in range(i + 1, min(i + neighbourhood, L - 1) + 1)]
                     or [(0, 0)], np.int32)

    def body(k, pc):
        p, c = pc
        i, j = pairs[k, 0], pairs[k, 1]
        cand = p.at[i].set(p[j]).at[j].set(p[i])
        new = score(problem, jnp.where(cand >= n, PAD_NODE, cand)).cost
        better = new < c
        return jnp.where(better, cand, p), jnp.where(better, new, c)

    if pairs.shape[0] == 1 and pairs[0, 0] == pairs[0, 1]:
        return path, cost
    pairs = jnp.asarray(pairs)
    return jax.lax.fori_loop(0, pairs.shape[0], body, (path, cost))


def to_path(problem: PickPlaceProblem, objs: Array, bases: Array) -> Array:
    """Node path ``(L,)`` (padding node ``n``) of a delivery sequence: ``start`` + per
    delivery (``start`` when going through it is cheaper, object, base) + ``goal``."""
    W = jnp.asarray(problem.move_cost, jnp.float32)
    s, g, L = problem.start, problem.goal, problem.max_path_len
    pad = W.shape[0] - 1
    prev, nxt = bases[:-1], objs[1:]
    via = jnp.concatenate([jnp.zeros(1, bool), W[prev, s] + W[s, nxt] < W[prev, nxt]])
    seg = jnp.stack([jnp.where(via, s, pad), objs, bases], axis=1).reshape(-1)
    nodes = jnp.concatenate([jnp.array([s]), seg, jnp.array([g])]).astype(jnp.int32)
    return _compact(nodes, nodes != pad, L, pad)


class _Moves(NamedTuple):
    """Static description of the ``K`` swap moves of the local search.

    Attributes:
      perm_o, perm_b: ``(K, N)`` new order of the objects / bases.
      w_o, w_b: for every object→base move a swap creates, the index in ``ox`` of its
        object and in ``bx`` of its base.
      p_b, p_o: for every pick move a swap creates, the index in ``bx`` of the base it
        leaves and in ``ox`` of the object (or goal) it goes to.
      touched: per swap, ``(ws, ps)``: pairs (slot in the lists above, position of the
        current move it replaces) for object→base moves and for pick moves.
    """

    perm_o: np.ndarray
    perm_b: np.ndarray
    w_o: tuple[int, ...]
    w_b: tuple[int, ...]
    p_b: tuple[int, ...]
    p_o: tuple[int, ...]
    touched: tuple


def _swap_moves(n: int, neighbourhood: int) -> _Moves:
    ident = np.arange(n)
    rows = []
    for i in range(n):
        for j in range(i + 1, min(i + neighbourhood, n - 1) + 1):
            sw = ident.copy()
            sw[[i, j]] = sw[[j, i]]
            rows += [(sw, sw), (ident, sw), (sw, ident)]  # delivery, bases only, objects only
    if not rows:  # one delivery: a no-op move keeps the shapes non-empty
        rows = [(ident, ident)]
    w_o, w_b, p_b, p_o, touched = [], [], [], [], []
    for po, pb in rows:
        moved_o, moved_b = po != ident, pb != ident
        # a whole-delivery swap keeps every object→base move
        w = [] if (po == pb).all() else [k for k in range(n) if moved_o[k] or moved_b[k]]
        # pick move k (from bx_k = b_{k-1} to ox_k = o_k) changes if b_{k-1} or o_k moved
        p = [k for k in range(n + 1) if (k < n and moved_o[k]) or (k > 0 and moved_b[k - 1])]
        ws = []
        for k in w:
            ws.append((len(w_o), k))
            w_o.append(int(po[k]))
            w_b.append(int(pb[k]) + 1)
        ps = []
        for k in p:
            ps.append((len(p_b), k))
            p_b.append(0 if k == 0 else int(pb[k - 1]) + 1)
            p_o.append(int(po[k]) if k < n else n)
        touched.append((tuple(ws), tuple(ps)))
    if not w_o:  # keep the lookup shapes non-empty
        w_o, w_b = [0], [1]
    return _Moves(np.stack([r[0] for r in rows]), np.stack([r[1] for r in rows]),
                  tuple(w_o), tuple(w_b), tuple(p_b), tuple(p_o), tuple(touched))


def _compact(x: Array, keep: Array, size: int, fill: int) -> Array:
    """The kept entries of ``x`` in order, in a ``(size,)`` array padded with ``fill``.

    Written as a one-hot select (``size × len(x)``) because a stable sort is several times
    slower on the CPU for these tiny arrays.
    """
    rank = jnp.cumsum(keep) - 1
    hit = keep[None, :] & (rank[None, :] == jnp.arange(size)[:, None])
    return jnp.where(hit.any(axis=1), jnp.sum(jnp.where(hit, x[None, :], 0), axis=1), fill)


def _cost(W: Array, path: Array) -> Array:
    return W[path[:-1], path[1:]].sum()


def _uniforms(seed: Array, n: int) -> Array:
    """``(n,)`` uniforms in [0, 1) from a uint32 seed: a counter-based integer hash
    (Wellons's lowbias32). Drawing every per-step uniform with threefry costs more than the
    whole construction on a CPU; one threefry seed per iteration keeps runs reproducible
    from the caller's key."""
    x = seed ^ (jnp.arange(1, n + 1, dtype=jnp.uint32) * jnp.uint32(0x9E3779B9))
    x = x ^ (x >> 16)
    x = x * jnp.uint32(0x7FEB352D)
    x = x ^ (x >> 15)
    x = x * jnp.uint32(0x846CA68B)
    x = x ^ (x >> 16)
    return (x >> 8).astype(jnp.float32) * jnp.float32(2.0**-24)


@dataclass(frozen=True)
class GraspOptions:
    """The settings of one GRASP call, checked once; hashable, so they are the one static
    argument of the jitted cores (one compilation per node layout and options).

    Attributes:
      iterations: ``I``, independent iterations (thesis: 1000), ≥ 1.
      alphas: α values, each in (0, 1]; each iteration draws one uniformly (thesis eq. 4.6).
      neighbourhood: how many following deliveries (``"thesis"``: nodes) each one is swapped
        with, ≥ 1 (thesis 4.7.2.2: 3).
      rounds: improving swaps of the delivery search at most, ≥ 0 (unused by ``"thesis"``).
      local_search: ``"deliveries"`` (ours) or ``"thesis"`` (Algorithm 4), see the module doc.

    Raises:
      ValueError: ``iterations < 1``, an α outside (0, 1], ``neighbourhood < 1``,
        ``rounds < 0`` or an unknown ``local_search``.
    """

    iterations: int = 1000
    alphas: tuple[float, ...] = THESIS_ALPHAS
    neighbourhood: int = THESIS_NEIGHBOURHOOD
    rounds: int = DEFAULT_ROUNDS
    local_search: str = "deliveries"

    def __post_init__(self):
        it, alphas, nb, rounds = self.iterations, self.alphas, self.neighbourhood, self.rounds
        if isinstance(it, bool) or not isinstance(it, (int, np.integer)) or it < 1:
            raise ValueError(f"GRASP needs at least one iteration; got {it!r}")
        if not alphas or any(not 0.0 < a <= 1.0 for a in alphas):
            raise ValueError(f"GRASP α values must lie in (0, 1]; got {alphas}")
        if isinstance(nb, bool) or not isinstance(nb, (int, np.integer)) or nb < 1:
            raise ValueError(f"GRASP local-search neighbourhood must be an integer >= 1; got {nb!r}")
        if isinstance(rounds, bool) or not isinstance(rounds, (int, np.integer)) or rounds < 0:
            raise ValueError(f"GRASP local-search rounds must be an integer >= 0; got {rounds!r}")
        if self.local_search not in LOCAL_SEARCHES:
            raise ValueError(f"unknown GRASP local search {self.local_search!r}; choose from {LOCAL_SEARCHES}")
        # plain Python values: numpy integers or a list of α would not hash as static arguments
        object.__setattr__(self, "iterations", int(it))
        object.__setattr__(self, "alphas", tuple(float(a) for a in alphas))
        object.__setattr__(self, "neighbourhood", int(nb))
        object.__setattr__(self, "rounds", int(rounds))


def grasp_batch(key: Array, problem: PickPlaceProblem, iterations: int = 1000, **options) -> GraspBatch:
    """Runs ``iterations`` independent GRASP iterations in parallel (``vmap``), jitted.

    Args:
      key: PRNG key; each iteration draws its α (uniform over ``alphas``) and a seed for
        its per-step uniforms (``_uniforms``).
      problem: the instance.
      iterations: ``I``.
      **options: keyword-only ``alphas``, ``neighbourhood``, ``rounds``, ``local_search``,
        see ``GraspOptions`` (defaults: the thesis's α and neighbourhood, ``DEFAULT_ROUNDS``,
        the delivery search).

    Returns:
      ``GraspBatch`` of ``I`` schedules.

    Raises:
      ValueError: bad settings (see ``GraspOptions``).
    """
    return _grasp_batch(key, problem, GraspOptions(iterations, **options))


@partial(jax.jit, static_argnames="options")
def _grasp_batch(key, problem, options):
    built, paths, cost = _iterations(key, problem, options)
    paths = jnp.where(jnp.isfinite(cost)[:, None], paths, built.path)  # stuck: as constructed
    return GraspBatch(paths, cost, built.cost)


def _iterations(key, problem, options: GraspOptions):
    """Construction and local search of every iteration: constructions, node paths, costs."""
    L, I, alphas = problem.max_path_len, options.iterations, options.alphas
    k_alpha, k_seed = jax.random.split(key)
    alpha = jnp.asarray(alphas, jnp.float32)[jax.random.randint(k_alpha, (I,), 0, len(alphas))]
    seeds = jax.random.bits(k_seed, (I,), jnp.uint32)
    u = jax.vmap(_uniforms, in_axes=(0, None))(seeds, L - 1)
    built = jax.vmap(construct, in_axes=(None, 0, 0))(problem, alpha, u)
    if options.local_search == "thesis":
        ls = partial(thesis_local_search, neighbourhood=options.neighbourhood)
        paths, cost = jax.vmap(ls, in_axes=(None, 0, 0))(problem, built.path, built.cost)
        return built, paths, cost
    ls = partial(local_search, neighbourhood=options.neighbourhood, rounds=options.rounds)
    objs, bases, cost = jax.vmap(ls, in_axes=(None, 0, 0, 0))(problem, built.objs, built.bases, built.cost)
    return built, jax.vmap(to_path, in_axes=(None, 0, 0))(problem, objs, bases), cost


@partial(jax.jit, static_argnames="options")
def _grasp_best(key, problem, options):
    _, paths, cost = _iterations(key, problem, options)
    i = jnp.argmin(cost)
    return paths[i], cost[i]


def grasp(key: Array, problem: PickPlaceProblem, iterations: int = 1000, **options) -> Schedule:
    """Best schedule of ``iterations`` GRASP iterations (thesis Algorithm 2).

    All iterations run in parallel in one jitted call (as in ``grasp_batch``), compiled once
    per (node layout, ``GraspOptions``) and reused. The returned cost is recomputed in
    float64 from the path.

    Args:
      key: PRNG key.
      problem: the instance.
      iterations: number of GRASP iterations (thesis: 1000).
      **options: keyword-only ``alphas``, ``neighbourhood``, ``rounds``, ``local_search``,
        see ``grasp_batch``.

    Returns:
      ``Schedule`` (cost ``inf`` if every iteration got stuck).

    Raises:
      ValueError: bad settings (see ``GraspOptions``).
    """
    settings = GraspOptions(iterations, **options)
    t0 = time.perf_counter()
    path, cost = _grasp_best(key, problem, settings)
    path = np.asarray(path)
    wall = time.perf_counter() - t0
    info = {"iterations": settings.iterations, "local_search": settings.local_search}
    if not np.isfinite(float(cost)):
        return Schedule((), float("inf"), wall, "grasp", info)
    nodes = unpad(path, problem.n_nodes)
    return Schedule(nodes, path_cost(problem, nodes), wall, "grasp", info)


def unpad(path: np.ndarray, n_nodes: int) -> tuple[int, ...]:
    """Drops the padding node ``n`` (or ``-1``) from a schedule."""
    return tuple(int(v) for v in np.asarray(path) if v != n_nodes and v != PAD_NODE)
