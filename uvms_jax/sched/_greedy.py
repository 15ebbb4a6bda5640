"""The thesis's greedy "Dijkstra" scheduler (thesis 4.7.1, Algorithm 1)."""

from __future__ import annotations

import time

from uvms_jax.sched._problem import BASE, OBJECT, START, PickPlaceProblem, path_cost
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
    adj = problem.adjacency
    n_obj = problem.n_objects
    visited = bytearray(problem.n_nodes)
    pos, placed = problem.start, 0
    path = [pos]
    stuck = False
    while pos != problem.goal:
        best, best_c, best_k = -1, float("inf"), -1
        for v, c, k in adj[pos]:
            if k == OBJECT or k == BASE:
                ok = not visited[v]
            elif k == START:
                ok = placed < n_obj
            else:  # goal
                ok = placed == n_obj
            if ok and c < best_c:
                best, best_c, best_k = v, c, k
        if best < 0:
            stuck = True
            break
        pos = best
        visited[pos] = 1
        placed += best_k == BASE
        path.append(pos)
    cost = float("inf") if stuck else path_cost(problem, path)
    return Schedule(tuple(path), cost, time.perf_counter() - t0, "greedy", {"stuck": stuck})
