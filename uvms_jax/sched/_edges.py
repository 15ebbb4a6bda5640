"""A solved schedule as the list of moves to plan and execute (independent of planners)."""

from __future__ import annotations

from typing import NamedTuple, Sequence

from uvms_jax.sched._problem import PickPlaceProblem, as_padded_paths
from uvms_jax.sched._rules import BASE, GOAL, OBJECT, START
from uvms_jax.sched._score import Reason, score

_ACTION = {OBJECT: "pick", BASE: "place", START: "return", GOAL: "finish"}


class ScheduleEdge(NamedTuple):
    """One move of a schedule.

    Attributes:
      src, dst: node indices.
      action: what reaching ``dst`` does: ``"pick"`` (an object), ``"place"`` (on a base),
        ``"return"`` (to the start), ``"finish"`` (the goal).
      obj: the object carried on this move (``place`` moves), else ``None``.
    """

    src: int
    dst: int
    action: str
    obj: int | None


def schedule_edges(problem: PickPlaceProblem, path: Sequence[int]) -> list[ScheduleEdge]:
    """Turns a schedule into its moves, e.g. ``0-2-5-…`` → ``[(0, 2, pick), (2, 5, place,
    obj=2), …]``.

    Raises:
      ValueError: the path is not a valid schedule of ``problem`` (checked with ``score``).
    """
    nodes = [int(v) for v in path]
    if len(nodes) < 2:
        raise ValueError(f"a schedule needs at least two nodes; got {nodes}")
    reason = Reason(int(score(problem, as_padded_paths([nodes])).reason[0]))
    if reason != Reason.OK:
        raise ValueError(f"not a valid schedule ({reason.name}): {'-'.join(map(str, nodes))}")
    kind = problem.kind
    return [
        ScheduleEdge(a, b, _ACTION[int(kind[b])], a if kind[b] == BASE else None)
        for a, b in zip(nodes[:-1], nodes[1:])
    ]
