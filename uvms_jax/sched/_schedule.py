"""The result every solver returns: a schedule (node path), its cost and the wall time."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping


@dataclass(frozen=True)
class Schedule:
    """A solved schedule.

    Attributes:
      path: node sequence from the start to the goal (thesis numbering, e.g.
        ``(0, 2, 5, 4, 8, 0, 1, 6, 3, 7, 9)``); a greedy run that gets stuck ends early.
      cost: total move cost (float64 sum over ``problem.cost``); ``inf`` if no schedule.
      wall_time_s: wall-clock time of the solver call [s] (JAX solvers: including the
        device sync; a first call also includes compilation).
      solver: solver name (``"greedy"``, ``"grasp"``, ``"astar"``, ``"exact"``).
      info: solver-specific extras (e.g. expanded nodes, per-iteration GRASP costs).
    """

    path: tuple[int, ...]
    cost: float
    wall_time_s: float
    solver: str
    info: Mapping[str, Any] = field(default_factory=dict)

    @property
    def feasible(self) -> bool:
        return self.cost != float("inf")

    def path_str(self) -> str:
        """The thesis's notation, e.g. ``"0-2-5-4-8-0-1-6-3-7-9"``."""
        return "-".join(str(v) for v in self.path)
