"""The scheduling solvers by name: the one registry that the stage, its settings, the plots and
the report iterate. A new solver is one :func:`register_solver` call, from anywhere."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax

from uvms_jax.sched._astar import astar
from uvms_jax.sched._exact import exact
from uvms_jax.sched._grasp import grasp
from uvms_jax.sched._greedy import greedy
from uvms_jax.sched._problem import PickPlaceProblem
from uvms_jax.sched._schedule import Schedule

#: ``run(key, problem, grasp_kwargs) -> Schedule``: ``key`` a PRNG key (for randomised
#: solvers), ``grasp_kwargs`` the keyword arguments of :func:`~uvms_jax.sched.grasp` from the
#: stage's settings (solvers other than GRASP ignore them).
SolverFn = Callable[[jax.Array, PickPlaceProblem, dict[str, Any]], Schedule]


@dataclass(frozen=True)
class Solver:
    """A registered solver.

    Attributes:
      name: its key in :data:`SOLVERS` and in the settings' ``solvers`` list.
      run: see :data:`SolverFn`.
      label: its name in tables, plots and reports.
      line: matplotlib colour and line style (e.g. ``"r--"``) of its horizontal line in the GRASP
        sweep's figure; ``None``: not drawn there.
    """

    name: str
    run: SolverFn
    label: str
    line: str | None = None


#: name → :class:`Solver`, in the order tables list them. Read it, extend it with
#: :func:`register_solver`.
SOLVERS: dict[str, Solver] = {}


def register_solver(name: str, run: SolverFn, *, label: str | None = None, line: str | None = None) -> Solver:
    """Add a solver under ``name`` (a ValueError if the name is taken or not an identifier);
    it can then be named in ``sched.solvers``. Returns it."""
    if not (isinstance(name, str) and name.isidentifier()):
        raise ValueError(f"a solver's name must be an identifier, got {name!r}")
    if name in SOLVERS:
        raise ValueError(f"a solver named {name!r} is already registered")
    SOLVERS[name] = Solver(name, run, name if label is None else label, line)
    return SOLVERS[name]


register_solver("greedy", lambda key, problem, kw: greedy(problem), line="r--")
register_solver("grasp", lambda key, problem, kw: grasp(key, problem, **kw), label="GRASP")
register_solver("astar", lambda key, problem, kw: astar(problem), label="A*", line="g--")
register_solver("exact", lambda key, problem, kw: exact(problem), line="k:")
