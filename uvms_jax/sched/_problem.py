"""The immutable pick-and-place scheduling problem (thesis ch. 4.7, SPEC §5).

Node roles. A problem has ``n`` nodes: one start, one goal, ``N`` objects and ``M`` bases.
The thesis numbering (Table 5.1) is 0 start, 1–4 objects, 5–8 bases, 9 goal; in general any
node that is neither start, goal nor an object (a key of ``compat``) is a base.

Move rules (thesis 4.7 and Fig. 4.12), with gripper capacity one and one object per base:

* start → an object not yet placed;
* object → one of its allowed bases that is still free (the delivery);
* base (after a delivery) → an unplaced object, or the start while objects remain;
* base → goal only once every object is placed — and then only the goal;
* goal ends the schedule.

A schedule is therefore ``start, o1, b1, [start], o2, b2, …, oN, bN, goal``: ``2N + 2``
nodes plus at most ``N − 1`` optional returns to the start, so at most ``3N + 1`` nodes.
``cost[i, j]`` is the cost of the move ``i → j``; NaN marks a move that is not allowed (for
example no trajectory was found). Costs are non-negative (min-max normalised metrics are).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Mapping, Sequence

import jax
import numpy as np

# Node kinds; PAD is the extra node index ``n`` used to pad schedules to a fixed length.
START, OBJECT, BASE, GOAL, PAD = 0, 1, 2, 3, 4
PAD_NODE = -1  # how padding is written in user-facing paths


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
      kind: ``(n + 1,)`` int8 node kinds (START, OBJECT, BASE, GOAL, PAD).
      object_nodes: ``(N,)`` object nodes, ascending.
      base_nodes: ``(M,)`` base nodes, ascending.
      start, goal: node indices (static).
    """

    cost: np.ndarray
    move_cost: np.ndarray
    rule: np.ndarray
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
    def adjacency(self) -> tuple[tuple[tuple[int, float, int], ...], ...]:
        """Per node, the ``(next node, cost, next kind)`` moves allowed by the static rules.

        Ascending in the next node's index.

        Plain Python, for the pure-Python solvers (greedy, A*); computed once per instance.
        """
        n = self.n_nodes
        mc = np.asarray(self.move_cost)
        return tuple(
            tuple(
                (int(j), float(mc[i, j]), int(self.kind[j]))
                for j in range(n)
                if np.isfinite(mc[i, j])
            )
            for i in range(n)
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
        goal = n - 1 if goal is None else goal
        for name, node in (("start", start), ("goal", goal)):
            if not (isinstance(node, (int, np.integer)) and 0 <= node < n):
                raise ValueError(f"{name} node {node!r} is not a node of the {n}-node cost matrix")
        if start == goal:
            raise ValueError(f"start and goal must be different nodes; both are {start}")
        start, goal = int(start), int(goal)

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

        kind = np.full(n + 1, BASE, dtype=np.int8)
        kind[start], kind[goal], kind[n] = START, GOAL, PAD
        kind[objects] = OBJECT
        rule = _static_rules(n, start, goal, objects, bases, allowed)
        padded = np.full((n + 1, n + 1), np.nan)
        padded[:n, :n] = cost
        padded[goal, n] = padded[n, n] = 0.0
        move_cost = np.where(rule & np.isfinite(padded), padded, np.inf)
        for a in (cost, move_cost, rule, kind):
            a.setflags(write=False)
        object_nodes = np.array(objects, dtype=np.int32)
        base_nodes = np.array(bases, dtype=np.int32)
        for a in (object_nodes, base_nodes):
            a.setflags(write=False)
        problem = cls(
            cost=cost,
            move_cost=move_cost,
            rule=rule,
            kind=kind,
            object_nodes=object_nodes,
            base_nodes=base_nodes,
            start=start,
            goal=goal,
        )
        _check_feasible(problem)
        return problem


jax.tree_util.register_dataclass(
    PickPlaceProblem,
    data_fields=["cost", "move_cost", "rule", "kind", "object_nodes", "base_nodes"],
    meta_fields=["start", "goal"],
)


def _node(x, n: int, what: str) -> int:
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer)):
        raise ValueError(f"{what} node {x!r} is not an integer node index")
    if not 0 <= x < n:
        raise ValueError(f"unknown {what} node {x}: the cost matrix has nodes 0..{n - 1}")
    return int(x)


def _static_rules(n, start, goal, objects, bases, allowed) -> np.ndarray:
    """``(n + 1, n + 1)`` bool: moves allowed by the rules, before costs and occupancy."""
    rule = np.zeros((n + 1, n + 1), dtype=bool)
    rule[start, objects] = True
    for o, bs in zip(objects, allowed):
        rule[o, list(bs)] = True
    for b in bases:
        rule[b, objects] = True
        rule[b, start] = True
        rule[b, goal] = True
    rule[goal, n] = rule[n, n] = True
    return rule


def _check_feasible(problem: PickPlaceProblem) -> None:
    """Raises ValueError when no schedule reaches the goal; cheap checks first, then a DFS.

    The DFS runs over (placed objects, used bases, current base) with memoised dead ends, so
    it visits each such state at most once and stops at the first complete schedule.
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
    ok = np.isfinite(mc)
    to_obj = {}  # position -> objects reachable directly or through the start
    for p in (s, *problem.bases):
        direct = ok[p, list(objs)]
        via = ok[p, s] & ok[s, list(objs)] if p != s else np.zeros(len(objs), bool)
        to_obj[p] = [k for k in range(len(objs)) if direct[k] or via[k]]
    deliver = [[b for b in bs if ok[o, b]] for o, bs in zip(objs, problem.allowed_bases)]
    full = (1 << len(objs)) - 1
    dead: set = set()

    def dfs(placed: int, used: frozenset, pos: int) -> bool:
        if placed == full:
            return bool(ok[pos, g])
        key = (placed, used, pos)
        if key in dead:
            return False
        for k in to_obj[pos]:
            if placed >> k & 1:
                continue
            for b in deliver[k]:
                if b not in used and dfs(placed | 1 << k, used | {b}, b):
                    return True
        dead.add(key)
        return False

    if not dfs(0, frozenset(), s):
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
