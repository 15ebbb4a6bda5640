"""The immutable pick-and-place scheduling problem (thesis ch. 4.7, docs/theory.md §5).

Node roles. A problem has ``n`` nodes: one start, one goal, ``N`` objects and ``M`` bases.
The thesis numbering (Table 5.1) is 0 start, 1–4 objects, 5–8 bases, 9 goal; in general any
node that is neither start, goal nor an object (a key of ``compat``) is a base.

The move rules are written once, in ``_rules.py``. A schedule is
``start, o1, b1, [start], o2, b2, …, oN, bN, goal``: ``2N + 2`` nodes plus at most ``N − 1``
optional returns to the start, so at most ``3N + 1`` nodes. ``cost[i, j]`` is the cost of
the move ``i → j``; NaN marks a move that is not allowed (for example no trajectory was
found). Costs are non-negative (min-max normalised metrics are).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Mapping, NamedTuple, Sequence

import jax
import numpy as np

from uvms_jax.sched._rules import BASE, GOAL, OBJECT, PAD, START, allowed_next, as_bits, bit_nodes
from uvms_jax.sched._rules import consumed, next_table
from uvms_jax.sched._rules import static_rules

PAD_NODE = -1  # how padding is written in user-facing paths


class HostView(NamedTuple):
    """A problem as plain Python values (``PickPlaceProblem.host``).

    Attributes:
      next: the bit view of ``next_ok`` (``next[phase][node]``, bit ``j`` = node ``j``), for
        ``allowed_next``.
      consumed: bit mask of the object and base nodes (entered at most once).
      bases: bit mask of the base nodes (entering one places an object).
      cost: ``move_cost`` rows as floats.
      kind: node kinds as ints.
    """

    next: tuple
    consumed: int
    bases: int
    cost: tuple
    kind: tuple


@dataclass(frozen=True, eq=False)
class PickPlaceProblem:
    """A pick-and-place scheduling instance (immutable pytree; build it with ``from_matrix``).

    Every array is a pytree leaf, so instances with the same sizes and the same start and
    goal share compiled code (a GRASP run per random instance compiles once); only
    ``start`` and ``goal`` are static. Python-side views (``objects``, ``bases``,
    ``compat``) are for use outside ``jit``.

    Attributes:
      cost: ``(n, n)`` move costs [dimensionless], NaN = forbidden move.
      move_cost: ``(n + 1, n + 1)`` cost of each move allowed by the static move rules
        (compatibility included, occupancy not) and not NaN, ``inf`` otherwise. Index ``n`` is
        the padding node: ``goal → pad`` and ``pad → pad`` cost 0, so a schedule padded after
        its goal sums to its cost.
      rule: ``(n + 1, n + 1)`` bool, the static move rules (ignoring NaN costs).
      next_ok: ``(2, n + 1, n + 1)`` bool, ``_rules.next_table``: the moves allowed with
        objects left (0) and with all placed (1), occupancy aside; ask it through
        ``_rules.allowed_next``.
      kind: ``(n + 1,)`` int8 node kinds (START, OBJECT, BASE, GOAL, PAD).
      object_nodes: ``(N,)`` object nodes, ascending.
      base_nodes: ``(M,)`` base nodes, ascending.
      start, goal: node indices (static).
    """

    cost: np.ndarray
    move_cost: np.ndarray
    rule: np.ndarray
    next_ok: np.ndarray
    kind: np.ndarray
    object_nodes: np.ndarray
    base_nodes: np.ndarray
    start: int
    goal: int

    @property
    def n_nodes(self) -> int:
        return self.cost.shape[0]

    @property
    def n_objects(self) -> int:
        return self.object_nodes.shape[0]

    @property
    def n_bases(self) -> int:
        return self.base_nodes.shape[0]

    @property
    def max_path_len(self) -> int:
        """Longest possible schedule: ``3N + 1`` nodes (a return to start between deliveries)."""
        return 3 * self.n_objects + 1

    @property
    def objects(self) -> tuple[int, ...]:
        """Object nodes, ascending (outside ``jit``)."""
        return tuple(int(v) for v in self.object_nodes)

    @property
    def bases(self) -> tuple[int, ...]:
        """Base nodes, ascending (outside ``jit``)."""
        return tuple(int(v) for v in self.base_nodes)

    @property
    def allowed_bases(self) -> tuple[tuple[int, ...], ...]:
        """Per object (order of ``objects``), its allowed base nodes (outside ``jit``)."""
        rule = np.asarray(self.rule)
        return tuple(tuple(int(b) for b in np.flatnonzero(rule[o, : self.n_nodes])) for o in self.objects)

    @property
    def compat(self) -> dict[int, tuple[int, ...]]:
        """Object node → allowed base nodes (outside ``jit``)."""
        return dict(zip(self.objects, self.allowed_bases))

    @functools.cached_property
    def host(self) -> "HostView":
        """The problem as plain Python values, for the pure-Python solvers (outside ``jit``);
        computed once per instance."""
        kind = np.asarray(self.kind)
        return HostView(
            next=as_bits(self.next_ok),
            consumed=as_bits(consumed(kind)),
            bases=as_bits(kind == BASE),
            cost=tuple(tuple(float(c) for c in row) for row in np.asarray(self.move_cost)),
            kind=tuple(int(k) for k in kind),
        )

    @classmethod
    def from_matrix(
        cls,
        cost,
        compat: Mapping[int, Sequence[int]],
        start: int = 0,
        goal: int | None = None,
    ) -> "PickPlaceProblem":
        """Builds and validates a problem from a cost matrix and an object → bases map.

        Args:
          cost: ``(n, n)`` move costs, NaN = forbidden; finite entries must be ``>= 0``.
            Entries for moves the rules never allow (e.g. start → base) are ignored.
          compat: object node → allowed base nodes, e.g. the thesis
            ``{1: (5, 6), 2: (5, 6), 3: (7,), 4: (8,)}``.
          start: start node.
          goal: goal node; ``None`` means the last node (``n − 1``, node 9 in the thesis).

        Raises:
          ValueError: wrong shape, infinite or negative costs, unknown or clashing nodes, an
            object without a base, or a cost matrix that leaves no feasible schedule.
        """
        cost = _checked_cost(cost)
        n = cost.shape[0]
        start, goal = _checked_ends(start, n - 1 if goal is None else goal, n)
        objects, bases, allowed = _checked_compat(compat, n, start, goal)

        kind = np.full(n + 1, BASE, dtype=np.int8)
        kind[start], kind[goal], kind[n] = START, GOAL, PAD
        kind[objects] = OBJECT
        rule = static_rules(n, start, goal, objects, bases, allowed)
        padded = np.full((n + 1, n + 1), np.nan)
        padded[:n, :n] = cost
        padded[goal, n] = padded[n, n] = 0.0
        move_cost = np.where(rule & np.isfinite(padded), padded, np.inf)
        tables = dict(cost=cost, move_cost=move_cost, rule=rule, next_ok=next_table(move_cost, kind), kind=kind,
                      object_nodes=np.array(objects, dtype=np.int32), base_nodes=np.array(bases, dtype=np.int32))
        for a in tables.values():  # a problem's tables never change (cached views rely on it)
            a.setflags(write=False)
        problem = cls(**tables, start=start, goal=goal)
        _check_feasible(problem)
        return problem


def _checked_cost(cost) -> np.ndarray:
    """``(n, n)`` float64 copy of a cost matrix (n ≥ 4, finite entries ≥ 0, NaN = forbidden)."""
    cost = np.array(cost, dtype=np.float64)
    if cost.ndim != 2 or cost.shape[0] != cost.shape[1]:
        raise ValueError(f"cost matrix must be square (n, n); got shape {cost.shape}")
    n = cost.shape[0]
    if n < 4:
        raise ValueError(f"cost matrix needs at least 4 nodes (start, object, base, goal); got {n}")
    if np.isinf(cost).any():
        raise ValueError("cost matrix contains ±inf; mark forbidden moves with NaN")
    if (cost[np.isfinite(cost)] < 0).any():
        raise ValueError("cost matrix contains negative costs; costs must be >= 0")
    return cost


def _checked_ends(start, goal, n: int) -> tuple[int, int]:
    """``(start, goal)`` as ints: two different nodes of an ``n``-node matrix."""
    for name, node in (("start", start), ("goal", goal)):
        if not (isinstance(node, (int, np.integer)) and 0 <= node < n):
            raise ValueError(f"{name} node {node!r} is not a node of the {n}-node cost matrix")
    if start == goal:
        raise ValueError(f"start and goal must be different nodes; both are {start}")
    return int(start), int(goal)


def _checked_compat(compat: Mapping[int, Sequence[int]], n: int, start: int,
                    goal: int) -> tuple[list[int], tuple[int, ...], list[tuple[int, ...]]]:
    """The objects (sorted), the bases (every other node but start and goal) and each object's
    allowed bases (sorted) of an object → bases map."""
    if not compat:
        raise ValueError("compat is empty: the problem needs at least one object")
    items = {}
    for o, raw in compat.items():
        o = _node(o, n, "object")
        if o in items:
            raise ValueError(f"compat names object node {o} twice")
        items[o] = raw
    objects = sorted(items)
    for o in objects:
        if o in (start, goal):
            raise ValueError(f"object node {o} is also the start or goal node")
    bases = tuple(i for i in range(n) if i not in (start, goal) and i not in objects)
    allowed = []
    for o in objects:
        bs = sorted(_node(b, n, f"base (of object {o})") for b in items[o])
        if not bs:
            raise ValueError(f"object node {o} has no allowed base")
        if len(set(bs)) != len(bs):
            raise ValueError(f"object node {o} lists a base twice: {bs}")
        for b in bs:
            if b not in bases:
                raise ValueError(
                    f"object node {o} lists node {b} as a base, but node {b} is the "
                    "start, the goal or an object"
                )
        allowed.append(tuple(bs))
    return objects, bases, allowed


jax.tree_util.register_dataclass(
    PickPlaceProblem,
    data_fields=["cost", "move_cost", "rule", "next_ok", "kind", "object_nodes", "base_nodes"],
    meta_fields=["start", "goal"],
)


def _node(x, n: int, what: str) -> int:
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer)):
        raise ValueError(f"{what} node {x!r} is not an integer node index")
    if not 0 <= x < n:
        raise ValueError(f"unknown {what} node {x}: the cost matrix has nodes 0..{n - 1}")
    return int(x)


def _check_feasible(problem: PickPlaceProblem) -> None:
    """Raises ValueError when no schedule reaches the goal; cheap checks first, then a DFS.

    The DFS follows ``allowed_next`` over (position, visited objects and bases) with memoised
    dead ends, so it visits each such state at most once and stops at the goal.
    """
    mc = problem.move_cost
    objs, s, g = problem.objects, problem.start, problem.goal
    if not np.isfinite(mc[s, list(objs)]).any():
        raise ValueError(f"no feasible schedule: every move from the start node {s} is NaN")
    for o, bs in zip(objs, problem.allowed_bases):
        if not np.isfinite(mc[o, list(bs)]).any():
            raise ValueError(f"no feasible schedule: object {o} has a NaN cost to every allowed base {bs}")
    if not np.isfinite(mc[list(problem.bases), g]).any():
        raise ValueError(f"no feasible schedule: every move into the goal node {g} is NaN")
    h = problem.host
    n_obj = problem.n_objects
    dead: set = set()

    def dfs(pos: int, visited: int, placed: int) -> bool:
        if pos == g:
            return True
        if (pos, visited) in dead:
            return False
        for v in bit_nodes(allowed_next(h.next, pos, visited, placed, n_obj)):
            bit = 1 << v
            if dfs(v, visited | (bit & h.consumed), placed + ((bit & h.bases) > 0)):
                return True
        dead.add((pos, visited))
        return False

    if not dfs(s, 0, 0):
        raise ValueError(
            "no feasible schedule: the NaN entries of the cost matrix (with the compatibility "
            "map and one object per base) leave no way to place every object and reach the goal"
        )


def as_padded_paths(paths, length: int | None = None) -> np.ndarray:
    """Packs node sequences into a ``(B, L)`` int32 array padded with ``-1``.

    Args:
      paths: a sequence of node sequences (ragged allowed).
      length: ``L``; default the longest path.
    """
    paths = [list(p) for p in paths]
    L = max(len(p) for p in paths) if length is None else length
    out = np.full((len(paths), L), PAD_NODE, dtype=np.int32)
    for i, p in enumerate(paths):
        if len(p) > L:
            raise ValueError(f"path {i} has {len(p)} nodes, more than the padded length {L}")
        out[i, : len(p)] = p
    return out


def path_cost(problem: PickPlaceProblem, path: Sequence[int]) -> float:
    """Cost of one schedule in float64 (sum of ``cost`` over its moves, padding ignored).

    Does not check the move rules (use ``score`` for that); NaN moves give NaN.
    """
    p = [int(v) for v in path if v != PAD_NODE]
    if len(p) < 2:
        return 0.0
    return float(problem.cost[p[:-1], p[1:]].sum())
