"""Independent brute-force oracle: enumerates every feasible schedule (plain Python).

Written from the move rules in the thesis (4.7, Fig. 4.12), sharing no code with the
package: start → unplaced object; object → free allowed base; after a delivery an unplaced
object or the start (while objects remain); the goal once all are placed, then only it.
"""

from __future__ import annotations

import math


def all_schedules(cost, compat, start, goal):
    """Yields ``(path, cost)`` for every feasible schedule; ``cost`` is ``n × n`` nested
    lists (NaN = forbidden), ``compat`` maps object → allowed bases."""
    objects = set(compat)
    n_obj = len(objects)

    def ok(a, b):
        return not math.isnan(cost[a][b])

    def rec(path, total, placed, used, holding):
        pos = path[-1]
        if pos == goal:
            yield tuple(path), total
            return
        if holding is not None:  # must deliver
            for b in compat[holding]:
                if b not in used and ok(pos, b):
                    yield from rec(path + [b], total + cost[pos][b], placed | {holding}, used | {b}, None)
            return
        if len(placed) == n_obj:
            if pos != start and ok(pos, goal):
                yield from rec(path + [goal], total + cost[pos][goal], placed, used, None)
            return
        for o in sorted(objects - placed):
            if ok(pos, o):
                yield from rec(path + [o], total + cost[pos][o], placed, used, o)
        if pos != start and ok(pos, start):
            yield from rec(path + [start], total + cost[pos][start], placed, used, None)

    yield from rec([start], 0.0, frozenset(), frozenset(), None)


def brute_force_optimum(cost, compat, start, goal):
    """``(best cost, list of optimal paths, number of feasible schedules)``."""
    best, paths, count = math.inf, [], 0
    for path, c in all_schedules(cost, compat, start, goal):
        count += 1
        if c < best - 1e-12:
            best, paths = c, [path]
        elif abs(c - best) <= 1e-12:
            paths.append(path)
    return best, paths, count
