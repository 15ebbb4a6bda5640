"""The pick-and-place move rules, written once (thesis 4.7 and Fig. 4.12, docs/theory.md §5).

With gripper capacity one and one object per base:

* start → an object not yet placed;
* object → one of its allowed bases that is still free (the delivery);
* base (after a delivery) → an unplaced object, or the start while objects remain;
* base → goal only once every object is placed — and then only the goal;
* goal ends the schedule (then only the padding node ``n``, at cost 0).

The rules are split in two. What does not depend on the search is one static table,
``next_table``: ``(2, n + 1, n + 1)`` bool, move ``i → j`` allowed by the rules and by a
finite cost, in phase 0 (objects remain: the start may be entered, the goal not) and phase 1
(every object placed: the goal, not the start). What the search has done is its state:
the position, ``visited`` (the objects picked and the bases used; never the start, goal or
padding) and ``n_placed``. ``allowed_next`` combines the two and is the only place where a
solver, the scorer or the feasibility check asks which move may come next: the jitted code
calls it on the array table (NumPy or JAX, ``visited`` a bool vector); greedy, A* and the
feasibility check call it on the bit view of the same table (``as_bits``, ``visited`` an
int bit mask), which is several times faster in pure Python.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

# Node kinds; PAD is the extra node index ``n`` used to pad schedules to a fixed length.
START, OBJECT, BASE, GOAL, PAD = 0, 1, 2, 3, 4


def static_rules(
    n: int,
    start: int,
    goal: int,
    objects: Sequence[int],
    bases: Sequence[int],
    allowed: Sequence[Sequence[int]],
) -> np.ndarray:
    """``(n + 1, n + 1)`` bool: moves the rules allow, before costs and occupancy.

    Args:
      n: number of nodes (index ``n`` is the padding node).
      start, goal: node indices.
      objects, bases: object and base nodes.
      allowed: per object (order of ``objects``), its allowed bases.
    """
    rule = np.zeros((n + 1, n + 1), dtype=bool)
    rule[start, list(objects)] = True
    for o, bs in zip(objects, allowed):
        rule[o, list(bs)] = True
    for b in bases:
        rule[b, list(objects)] = True
        rule[b, start] = True
        rule[b, goal] = True
    rule[goal, n] = rule[n, n] = True
    return rule


def next_table(move_cost: np.ndarray, kind: np.ndarray) -> np.ndarray:
    """``(2, n + 1, n + 1)`` bool: the moves allowed in phase 0 (objects remain) and phase 1
    (all placed), occupancy aside.

    Args:
      move_cost: ``(n + 1, n + 1)`` cost of each move the static rules allow with a finite
        cost, ``inf`` otherwise (``PickPlaceProblem.move_cost``).
      kind: ``(n + 1,)`` node kinds.
    """
    ok = np.isfinite(move_cost)
    return np.stack([ok & (kind != GOAL)[None, :], ok & (kind != START)[None, :]])


def consumed(kind: np.ndarray) -> np.ndarray:
    """``(n + 1,)`` bool: nodes a schedule enters at most once (objects and bases)."""
    return (kind == OBJECT) | (kind == BASE)


def as_bits(mask: np.ndarray):
    """The bit view of a bool array: its last axis as Python ints (bit ``j`` = entry ``j``),
    the leading axes as nested tuples."""
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim == 1:
        return sum(1 << int(j) for j in np.flatnonzero(mask))
    return tuple(as_bits(m) for m in mask)


def allowed_next(table, pos, visited, n_placed, n_objects: int):
    """The moves the rules allow next: the one move rule of every solver and check.

    Works unchanged on the array table inside or outside ``jit`` and on its bit view.

    Args:
      table: ``next_table`` ``(2, n + 1, n + 1)`` bool (NumPy or JAX), or its bit view
        ``as_bits(table)``.
      pos: current node.
      visited: objects picked and bases used: ``(n + 1,)`` bool, or an int bit mask for the
        bit view.
      n_placed: objects delivered so far.
      n_objects: ``N``.

    Returns:
      ``(n + 1,)`` bool (array table) or an int bit mask (bit view) of the allowed next nodes.
    """
    phase = (n_placed >= n_objects) * 1  # an int 0/1 for Python, NumPy and JAX alike
    return table[phase][pos] & ~visited


def bit_nodes(mask: int):
    """The nodes of a bit mask, ascending (bit ``j`` = node ``j``)."""
    while mask:
        low = mask & -mask
        yield low.bit_length() - 1
        mask ^= low
