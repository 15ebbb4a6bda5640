"""Which Jacobian an index is computed from: its form (geometric or spatial) and normalisation.

The dexterity paper computes w and KCI from the spatial-twist Jacobian (its eq. 6, columns
``ξ'_i = Ad(e^{ξ1θ1}…e^{ξ(i−1)θ(i−1)}) ξ_i``) normalised by its eq. 7, ``J = U J_st G⁻¹``
with ``G = diag(1/θ̇_max)`` and ``U = diag(1/ṙ_max)``. The project's default is the geometric
Jacobian (rows: tool-point linear velocity, angular velocity) without normalisation.

The two forms differ only in the linear rows: ``v_spatial = v_tool + p_tool × ω`` (the velocity
of the body point at the base origin instead of the tool point), a change by the 6 × 6 matrix
``[[I, p̂], [0, I]]`` of determinant 1. Hence w is the same in both forms, but the singular
values, hence KCI, are not: with the spatial form KCI depends on where the tool is relative to
the base origin, i.e. on the vehicle joints θ1…θ4, and falls as the vehicle moves away
(docs/theory.md §7).

Both forms are computed by one fused kernel (``kin.jacobian_rows`` on scalars, never storing a
batched J): for the geometric form without normalisation this is exactly
``indices.manipulability_of`` / ``indices.kci_of``, the project's fastest analytic path.
"""

from __future__ import annotations

import dataclasses
import math
from functools import partial
from typing import Callable

import jax
from jax import Array

from uvms_jax import indices, kin

JACOBIAN_FORMS = ("geometric", "spatial")


@dataclasses.dataclass(frozen=True)
class IndexForm:
    """Jacobian form and normalisation of an index (hashable: a static argument of jitted code).

    Attributes:
      jacobian: "geometric" (project default) or "spatial" (dexterity paper eq. 6).
      joint_speed_max: ``(n_joints,)`` θ̇_max of eq. 7 [m/s, rad/s], or None (G = I).
      task_speed_max: ``(6,)`` ṙ_max of eq. 7 [m/s ×3, rad/s ×3], or None (U = I).
    """

    jacobian: str = "geometric"
    joint_speed_max: tuple[float, ...] | None = None
    task_speed_max: tuple[float, ...] | None = None

    def __post_init__(self):
        if self.jacobian not in JACOBIAN_FORMS:
            raise ValueError(f"unknown Jacobian form {self.jacobian!r}; expected one of {JACOBIAN_FORMS}")
        for name in ("joint_speed_max", "task_speed_max"):
            v = getattr(self, name)
            if v is None:
                continue
            v = tuple(float(x) for x in v)
            if not all(math.isfinite(x) and x > 0 for x in v):
                raise ValueError(f"{name} must hold positive finite speeds, got {v}")
            object.__setattr__(self, name, v)
        if self.task_speed_max is not None and len(self.task_speed_max) != 6:
            raise ValueError(f"task_speed_max needs 6 entries (3 linear, 3 angular), got {len(self.task_speed_max)}")

    @property
    def is_fused_default(self) -> bool:
        """True where the index is exactly ``indices.manipulability_of`` / ``indices.kci_of``."""
        return self.jacobian == "geometric" and self.joint_speed_max is None and self.task_speed_max is None

    def check_chain(self, chain: kin.Chain) -> None:
        """Raise ValueError if ``joint_speed_max`` does not have one entry per joint of ``chain``."""
        if self.joint_speed_max is not None and len(self.joint_speed_max) != chain.n_joints:
            raise ValueError(f"joint_speed_max needs {chain.n_joints} entries (one per joint of "
                             f"{chain.name!r}), got {len(self.joint_speed_max)}")

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def _rows(chain: kin.Chain, q: Array, form: IndexForm) -> list:
    """Jacobian of ``form`` at ``q: (..., n)`` as 6 rows × n scalars of the batch shape (eq. 6–7)."""
    rows = kin.spatial_jacobian_rows(chain, q) if form.jacobian == "spatial" else kin.jacobian_rows(chain, q)
    if form.joint_speed_max is not None:  # · G⁻¹ = · diag(θ̇_max)
        rows = [[x * s for x, s in zip(row, form.joint_speed_max)] for row in rows]
    if form.task_speed_max is not None:  # U · = diag(1/ṙ_max) ·
        rows = [[x / s for x in row] for row, s in zip(rows, form.task_speed_max)]
    return rows


def index_of(chain: kin.Chain, q, index: str, form: IndexForm = IndexForm()) -> Array:
    """w or KCI of ``chain`` at ``q: (..., n_joints)`` [m, rad] for the Jacobian ``form``, ``(...)``.

    The geometric form without normalisation is ``indices.manipulability_of`` /
    ``indices.kci_of``; other forms run the same fused reductions on their own rows.
    """
    if index not in ("w", "kci"):
        raise ValueError(f"unknown index {index!r}; expected 'w' or 'kci'")
    q = kin.check_joint_array(chain, q)
    if form.is_fused_default:
        return indices.manipulability_of(chain, q) if index == "w" else indices.kci_of(chain, q)
    form.check_chain(chain)
    return _fused(chain, q, index, form)


@partial(jax.jit, static_argnames=("index", "form"))
def _fused(chain: kin.Chain, q: Array, index: str, form: IndexForm) -> Array:
    rows = _rows(chain, q, form)
    return indices.manipulability_from_rows(rows) if index == "w" else indices.kci_from_rows(rows)


def index_fn(chain: kin.Chain, index: str, form: IndexForm = IndexForm()) -> Callable[[Array], Array]:
    """``q: (..., n_joints) → (...)`` analytic index of ``form``, compiled (the fastest analytic path)."""
    if index not in ("w", "kci"):
        raise ValueError(f"unknown index {index!r}; expected 'w' or 'kci'")
    form.check_chain(chain)
    # No jit around the chain here: index_of's own jitted paths take it as an argument (one
    # compile per shape), and on a GPU a chain with known numbers takes the Pallas kernel of
    # `indices`, which a traced chain would bypass.
    return partial(index_of, chain, index=index, form=form)
