"""The docking fitness as a weighted sum of named terms: the one registry that every docking
problem sums (the paper's closed-form problem and the numerical-IK arm problem alike).

Eq. 8 and 15 of the docking paper are ``a·M_a − b·D`` inside the search set Wd, 0 outside:
the terms ``manipulability`` (``M_a``, eq. 1) and ``distance`` (``−D``, eq. 3) weighed by the
scene's ``a`` and ``b``. A new term is one :func:`register_fitness_term` call, from anywhere;
a scene's settings then name it with a weight (``terms: [{name: ..., weight: ...}]``).
Terms are pure ``jax.numpy`` functions, so every fitness stays traceable (``jit``, ``vmap``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Callable, NamedTuple, Protocol

import jax.numpy as jnp
from flax import struct
from jax import Array


class FitnessInputs(NamedTuple):
    """What a fitness term sees of candidate poses, each field ``(...)`` over the candidates.

    Attributes:
      pose: ``(..., 4)`` candidate poses ``[x, y, z, ψ]`` [m, rad].
      M_a: ``(...)`` area manipulability, eq. 1.
      D: ``(...)`` distance of the docking point from its initial position, eq. 3 [m].
    """

    pose: Array
    M_a: Array
    D: Array


#: ``term(inputs) -> (...)``: one term's value per candidate (larger is better before weighing).
TermFn = Callable[[FitnessInputs], Array]

#: name → term, in the order a problem sums them. Read it, extend it with :func:`register_fitness_term`.
FITNESS_TERMS: dict[str, TermFn] = {}

#: The terms of eq. 8, weighed by a scene's ``a`` and ``b`` (in this order).
PAPER_TERMS = ("manipulability", "distance")


def register_fitness_term(name: str, term: TermFn) -> TermFn:
    """Add a fitness term under ``name`` (a ValueError if the name is taken or not an
    identifier); a scene's ``terms`` can then name it. Returns it."""
    if not (isinstance(name, str) and name.isidentifier()):
        raise ValueError(f"a fitness term's name must be an identifier, got {name!r}")
    if name in FITNESS_TERMS:
        raise ValueError(f"a fitness term named {name!r} is already registered")
    if not callable(term):
        raise ValueError(f"fitness term {name!r} must be a function of FitnessInputs, got {term!r}")
    FITNESS_TERMS[name] = term
    return term


register_fitness_term("manipulability", lambda x: x.M_a)  # eq. 1, weight a
register_fitness_term("distance", lambda x: -x.D)  # eq. 3, weight b


@struct.dataclass
class Objective:
    """The weighted sum of fitness terms that a docking problem maximises (a pytree).

    Attributes:
      weights: ``(t,)`` one weight per term.
      terms: the ``t`` term functions (static: a problem compiles once per set of terms).
      names: their registered names (static).
    """

    weights: Array
    terms: tuple[TermFn, ...] = struct.field(pytree_node=False)
    names: tuple[str, ...] = struct.field(pytree_node=False)

    def __call__(self, inputs: FitnessInputs, feasible: Array) -> Array:
        """``(...)`` eq. 15: ``Σ weight · term`` inside Wd (``feasible``), 0 outside."""
        total = self.weights[0] * self.terms[0](inputs)
        for i in range(1, len(self.terms)):
            total = total + self.weights[i] * self.terms[i](inputs)
        return jnp.where(feasible, total, 0.0)

    def weight(self, name: str) -> Array:
        """``()`` the weight of the term ``name`` (a ValueError if the objective has none)."""
        if name not in self.names:
            raise ValueError(f"the objective has no term {name!r}; it has {list(self.names)}")
        return self.weights[self.names.index(name)]


def make_objective(weights: Mapping[str, float], dtype=None) -> Objective:
    """The :class:`Objective` of registered terms ``name → weight`` (at least one).

    Raises:
      ValueError: no terms, or a name that is not registered.
    """
    if not weights:
        raise ValueError("a docking objective needs at least one fitness term")
    unknown = [n for n in weights if n not in FITNESS_TERMS]
    if unknown:
        raise ValueError(f"unknown fitness terms {unknown}; registered: {list(FITNESS_TERMS)}")
    names = tuple(weights)
    return Objective(jnp.asarray([weights[n] for n in names], dtype=dtype or jnp.zeros(()).dtype),
                     tuple(FITNESS_TERMS[n] for n in names), names)


def paper_weights(a: float, b: float, terms: Mapping[str, float] | None = None) -> dict[str, float]:
    """``name → weight``: eq. 8's ``manipulability`` (``a``) and ``distance`` (``b``), then
    ``terms`` (further registered terms and their weights).

    Raises:
      ValueError: ``terms`` names one of eq. 8's terms (its weight is ``a`` or ``b``).
    """
    twice = [n for n in (terms or {}) if n in PAPER_TERMS]
    if twice:
        raise ValueError(f"fitness terms {twice} are weighed by the scene's a and b, not by its terms")
    return {"manipulability": a, "distance": b, **(terms or {})}


class Problem(Protocol):
    """What the optimisers (grid search, GA, CMA-ES) need of a docking problem: a box of
    candidate poses and a traceable fitness over it."""

    @property
    def pose_low(self) -> Array:
        """``(4,)`` lower corner of the candidate box [m, rad]."""

    @property
    def pose_high(self) -> Array:
        """``(4,)`` upper corner of the candidate box [m, rad]."""

    def fitness(self, pose: Array) -> Array:
        """``(...)`` fitness (maximised) of candidate poses ``(..., 4)``."""
