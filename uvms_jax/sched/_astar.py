"""A* over schedule states with the thesis heuristic (thesis 4.7.3, eqs. 4.7–4.8)."""

from __future__ import annotations

import heapq
import time

from uvms_jax.sched._problem import PickPlaceProblem, path_cost
from uvms_jax.sched._rules import BASE, GOAL, OBJECT, allowed_next, bit_nodes
from uvms_jax.sched._schedule import Schedule


def astar(problem: PickPlaceProblem) -> Schedule:
    """Optimal schedule by A* with ``h = stepsLeft_min × cost_lowest`` (thesis eq. 4.8).

    A search state is (current node, set of visited objects and bases); ``f = g + h``
    (eq. 4.7). ``stepsLeft_min`` is the fewest moves that can still reach the goal — ``2r``
    from an object in hand and ``2r + 1`` from the start or a base, with ``r`` objects not
    yet delivered — and ``cost_lowest`` the cheapest allowed move of the instance. Since
    costs are ``>= 0`` the heuristic is admissible and consistent, so the first goal popped
    is optimal (unlike the thesis's implementation, which pruned successors against the
    open list and could miss the optimum, thesis 5.3.4). Ties are broken by insertion order,
    so results are deterministic.

    Returns:
      ``Schedule`` with ``info["expanded"]`` (states taken from the open list).
    """
    t0 = time.perf_counter()
    h = problem.host
    n = problem.n_nodes
    n_obj = problem.n_objects
    c_low = min((c for row in h.cost[:n] for c in row[:n] if c != float("inf")), default=0.0)
    sh = max(8, n.bit_length())
    low = (1 << sh) - 1
    start, goal = problem.start, problem.goal
    # state key = visited << sh | pos; visited holds one bit per picked object / used base
    root = start
    g_best = {root: 0.0}
    parent = {root: -1}
    heap = [(float(2 * n_obj + 1) * c_low, 0.0, 0, root, 0)]  # (f, g, tie, key, placed)
    tie = 1
    expanded = 0
    found = -1
    while heap:
        f, g, _, key, placed = heapq.heappop(heap)
        if g > g_best[key]:
            continue  # stale entry
        pos = key & low
        if pos == goal:
            found = key
            break
        expanded += 1
        visited = key >> sh
        row = h.cost[pos]
        for v in bit_nodes(allowed_next(h.next, pos, visited, placed, n_obj)):
            bit = 1 << v
            nkey = (visited | (bit & h.consumed)) << sh | v
            ng = g + row[v]
            old = g_best.get(nkey)
            if old is not None and old <= ng:
                continue
            g_best[nkey] = ng
            parent[nkey] = key
            k = h.kind[v]
            nplaced = placed + (k == BASE)
            left = n_obj - nplaced
            steps = 2 * left if k == OBJECT else (0 if k == GOAL else 2 * left + 1)
            heapq.heappush(heap, (ng + steps * c_low, ng, tie, nkey, nplaced))
            tie += 1
    if found < 0:  # from_matrix guarantees a schedule; kept for hand-built problems
        return Schedule((), float("inf"), time.perf_counter() - t0, "astar", {"expanded": expanded})
    path = []
    key = found
    while key != -1:
        path.append(key & low)
        key = parent[key]
    path.reverse()
    return Schedule(
        tuple(path), path_cost(problem, path), time.perf_counter() - t0, "astar", {"expanded": expanded}
    )
