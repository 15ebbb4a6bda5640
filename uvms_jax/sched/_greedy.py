"""The thesis's greedy "Dijkstra" scheduler (thesis 4.7.1, Algorithm 1)."""

from __future__ import annotations

import time

from uvms_jax.sched._problem import PickPlaceProblem, path_cost
from uvms_jax.sched._rules import allowed_next, bit_nodes
from uvms_jax.sched._schedule import Schedule


def greedy(problem: PickPlaceProblem) -> Schedule:
    """Always takes the cheapest allowed next move (``f(n) = g(n)``, thesis eq. 4.4).

    Ties go to the lowest node index. Occupancy (placed objects, used bases, goal only once
    all are placed) is updated after every move, as the thesis's occupation matrix is.
    If it reaches a node with no allowed move (possible when an object's bases are all taken)
    it stops there and returns that partial path with cost ``inf``.

    Returns:
      ``Schedule`` with ``info["stuck"]`` (bool).
    """
    t0 = time.perf_counter()
    h = problem.host
    n_obj = problem.n_objects
    pos, visited, placed = problem.start, 0, 0
    path = [pos]
    stuck = False
    while pos != problem.goal:
        row = h.cost[pos]
        best, best_c = -1, float("inf")
        for v in bit_nodes(allowed_next(h.next, pos, visited, placed, n_obj)):
            if row[v] < best_c:
                best, best_c = v, row[v]
        if best < 0:
            stuck = True
            break
        bit = 1 << best
        pos, visited, placed = best, visited | (bit & h.consumed), placed + ((bit & h.bases) > 0)
        path.append(pos)
    cost = float("inf") if stuck else path_cost(problem, path)
    return Schedule(tuple(path), cost, time.perf_counter() - t0, "greedy", {"stuck": stuck})
