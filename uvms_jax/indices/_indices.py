"""Dexterity indices of a Jacobian (docs/theory.md §2): manipulability, KCI, normalised Jacobian, torques.

Every index is a function of the ``r = min(m, n)`` singular values ``σ1 ≥ … ≥ σr`` of a
Jacobian ``J: (..., m, n)`` (m task rows, n joints), so it is defined for every shape:

- ``w = σ1 ⋯ σr``: ``sqrt(det J Jᵀ)`` when ``m ≤ n`` (Yoshikawa), ``sqrt(det Jᵀ J)`` when
  ``m > n`` — an arm with fewer joints than task dimensions is scored by the volume its n
  joint rates span, not by a determinant that is 0 because of the shape alone.
- ``KCI = σr / σ1`` (the inverse of the matrix condition number, as ``numpy.linalg.cond``).

Both come from factorisations of J itself — Gram–Schmidt for w, one-sided Jacobi rotations
for KCI — never from ``J Jᵀ``, whose float32 eigenvalues near a singular pose are off by
~1e-7 of σ1² (so σr by ~3e-4 of σ1). They are written on scalars and unrolled, so a batch
is one fused elementwise kernel on a CPU and one Pallas kernel on a GPU (``_gpu``).

The task space is a choice of rows of the 6-row geometric Jacobian (``task=``): ``"full"``,
``"position"``, ``"orientation"`` or row names from ``vx vy vz wx wy wz`` (or indices 0–5).
"""

from __future__ import annotations

import functools
import operator
from typing import Sequence

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.indices import _gpu
from uvms_jax.kin import Chain, check_joint_array, jacobian, jacobian_rows

ROW_NAMES = ("vx", "vy", "vz", "wx", "wy", "wz")
TASKS = {"full": (0, 1, 2, 3, 4, 5), "position": (0, 1, 2), "orientation": (3, 4, 5)}


def task_rows(task: str | Sequence[str | int] | None) -> tuple[int, ...]:
    """Rows of the geometric Jacobian ``[v; ω]`` that span a task space.

    Args:
      task: ``None`` or ``"full"`` (all six), ``"position"`` (``vx vy vz``), ``"orientation"``
        (``wx wy wz``), or a sequence of row names (``"vx"`` … ``"wz"``) or indices 0–5,
        e.g. ``("vx", "vy", "vz", "wz")`` for position and heading.

    Raises:
      ValueError: unknown name, index out of range, repeated or no rows.
    """
    if task is None:
        return TASKS["full"]
    if isinstance(task, str):
        if task not in TASKS:
            raise ValueError(f"unknown task {task!r}; expected one of {sorted(TASKS)} or a sequence of rows {ROW_NAMES}")
        return TASKS[task]
    rows = []
    for r in task:
        if isinstance(r, str):
            if r not in ROW_NAMES:
                raise ValueError(f"unknown Jacobian row {r!r}; expected one of {ROW_NAMES}")
            rows.append(ROW_NAMES.index(r))
        elif int(r) == r and 0 <= int(r) < 6:
            rows.append(int(r))
        else:
            raise ValueError(f"Jacobian row index {r!r} out of range 0–5")
    if not rows or len(set(rows)) != len(rows):
        raise ValueError(f"a task needs distinct rows, got {tuple(task)}")
    return tuple(rows)


def _check_jacobian(J, task=None) -> Array:
    J = jnp.asarray(J)
    if J.ndim < 2:
        raise ValueError(f"J must have shape (..., m, n), got {J.shape}")
    if task is None:
        return J
    if J.shape[-2] != 6:
        raise ValueError(f"task= selects rows of a 6-row geometric Jacobian; J has shape {J.shape}")
    return J[..., list(task_rows(task)), :]


def _safe_sqrt(x: Array) -> Array:
    """``sqrt(max(x, 0))`` whose gradient is 0, not inf/NaN, at and below zero (double where)."""
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def _sum(terms):
    return functools.reduce(operator.add, terms)


def _dot(a: list, b: list):
    return _sum([x * y for x, y in zip(a, b)])


def _safe_inverse(x: Array) -> Array:
    """``1 / x``, and 0 where ``x ≤ 0`` (with finite gradients there)."""
    positive = x > 0
    return jnp.where(positive, 1.0 / jnp.where(positive, x, 1.0), 0.0)


def _vectors(rows) -> list:
    """J given as m rows of n scalars → its smaller side as r = min(m, n) vectors of
    k = max(m, n) scalars: the rows if ``m ≤ n``, else the columns. The r singular values of
    J are those of this r × k matrix (of Jᵀ when m > n), with no zeros from the shape."""
    m, n = len(rows), len(rows[0])
    return [list(row) for row in rows] if m <= n else [[rows[a][k] for a in range(m)] for k in range(n)]


def _triangular_factor(V: list) -> list:
    """``L`` of ``V = L Q`` (modified Gram–Schmidt, orthonormal rows of Q), r × r lower
    triangular as nested scalars: V's singular values on r × r instead of r × k numbers.

    MGS's triangular factor is backward stable (Björck 1967): its singular values carry an
    absolute error of a few ulps of ``σ1``, as those of V do — what the indices need."""
    V = [list(v) for v in V]
    r = len(V)
    zero = jnp.zeros_like(V[0][0])
    L = [[zero] * r for _ in range(r)]
    for i in range(r):
        norm = _safe_sqrt(_dot(V[i], V[i]))
        unit = [x * _safe_inverse(norm) for x in V[i]]
        L[i][i] = norm
        for j in range(i + 1, r):
            L[j][i] = _dot(V[j], unit)
            V[j] = [a - L[j][i] * b for a, b in zip(V[j], unit)]
    return L


def manipulability_from_rows(rows):
    """``w = σ1 ⋯ σr`` for J as m rows of n scalars, ``r = min(m, n)``: the volume spanned by
    the r vectors of J's smaller side, the product of their Gram–Schmidt residual lengths
    (``|det R|`` of a QR factorisation of J or Jᵀ; equal to ``sqrt(det J Jᵀ)`` for m ≤ n).

    The factorisation is of J itself, never of ``J Jᵀ``: forming ``J Jᵀ`` squares the
    condition number, which in float32 leaves w near singular poses with an absolute error
    of ~3e-4 of the largest w; this one stays within ~1e-6 (docs/theory.md §2). Unrolled on
    scalars, so over a batch it is one fused elementwise kernel. A residual of length 0
    (rank-deficient J) contributes 0 and is projected out of nothing: w stays finite, is 0 at
    singularities, and has finite gradients there.
    """
    V = _vectors(rows)
    w = 1.0
    for i in range(len(V)):
        length2 = _dot(V[i], V[i])
        w = w * _safe_sqrt(length2)
        inverse = _safe_inverse(length2)
        for j in range(i + 1, len(V)):
            c = _dot(V[j], V[i]) * inverse
            V[j] = [a - c * b for a, b in zip(V[j], V[i])]
    return w


def _rows(J: Array) -> list:
    return [[J[..., a, k] for k in range(J.shape[-1])] for a in range(J.shape[-2])]


@jax.jit
def _manipulability(J: Array) -> Array:
    return manipulability_from_rows(_rows(J))


def manipulability(J, task=None) -> Array:
    """Manipulability ``w = σ1 ⋯ σr``, ``r = min(m, n)``, shape ``(...)``.

    ``sqrt(det J Jᵀ)`` (Yoshikawa) for ``m ≤ n``; ``sqrt(det Jᵀ J)`` for ``m > n`` (fewer
    joints than task dimensions). From an unrolled Gram–Schmidt factorisation of J itself
    (accurate in float32 near singularities; no SVD, no pivoting). ``w ≥ 0``, 0 at singular
    configurations, with finite gradients there. For w of a chain at many configurations,
    :func:`manipulability_of` is much faster (it never stores J).

    Args:
      J: ``(..., m, n)`` Jacobian.
      task: rows of a 6-row geometric J to keep (see :func:`task_rows`); None: all rows of J.
    """
    return _manipulability(_check_jacobian(J, task))


@functools.partial(jax.jit, static_argnames="rows")
def _manipulability_of(chain: Chain, q: Array, rows: tuple[int, ...]) -> Array:
    J = jacobian_rows(chain, q)
    return manipulability_from_rows([J[r] for r in rows])


@functools.partial(jax.jit, static_argnames="rows")
def _kci_of(chain: Chain, q: Array, rows: tuple[int, ...]) -> Array:
    # J from the scanned pass, stored: the Jacobi sweeps need it whole, and XLA on a CPU would
    # copy the unrolled pass into each of J's 6 n entries (for the 12-DOF UVMS, 1.7× slower).
    J = jacobian(chain, q)
    return kci_from_rows([[J[..., r, k] for k in range(chain.n_joints)] for r in rows])


def _index_of(index_from_rows, xla_path, chain: Chain, q, task) -> Array:
    """An index of ``chain`` at ``q``: one Pallas kernel on a GPU (``_gpu``), XLA elsewhere."""
    q, rows = check_joint_array(chain, q), task_rows(task)
    if _gpu.applies(chain, q):
        return _gpu.index_on_gpu(index_from_rows, xla_path, chain, q, rows)
    return xla_path(chain, q, rows)


def manipulability_of(chain: Chain, q, task="full") -> Array:
    """w of ``chain`` at ``q: (..., n)`` in a task space — equal to
    ``manipulability(jacobian(chain, q), task)``, computed in one fused kernel that never
    stores J (the fast path for populations, grids and datasets).

    Args:
      chain: any chain; with fewer joints than task rows, w is ``sqrt(det Jᵀ J)``.
      q: ``(..., n)`` joint values [rad | m].
      task: ``"full"``, ``"position"``, ``"orientation"`` or rows (see :func:`task_rows`).
    """
    return _index_of(manipulability_from_rows, _manipulability_of, chain, q, task)


def kci_of(chain: Chain, q, task="full") -> Array:
    """KCI of ``chain`` at ``q: (..., n)`` in a task space, equal to
    ``kci(jacobian(chain, q), task)``, fused (arguments as :func:`manipulability_of`)."""
    return _index_of(kci_from_rows, _kci_of, chain, q, task)


#: Cyclic sweeps by dtype. Convergence is quadratic: on the test arms' near-singular poses
#: (tests/indices/test_float32_accuracy.py) the 5th sweep reaches float32 round-off and the
#: 6th float64's.
JACOBI_SWEEPS = {"float32": 5, "float64": 6}


def _jacobi_sweeps(V: list, with_rotations: bool) -> tuple[list, list | None]:
    """Hestenes' one-sided Jacobi on r vectors of k scalars: plane rotations of pairs of them
    until they are mutually orthogonal. Returns the rotated vectors B (their lengths are the
    singular values of V) and, ``with_rotations``, the orthogonal U (r × r) with ``U V = B``.

    Each rotation makes the pair (p, q) orthogonal with ``t = 2γ sgn(d) / (|d| + sqrt(d² + 4γ²))``,
    ``γ = v_p·v_q``, ``d = |v_q|² − |v_p|²`` (Golub & Van Loan §8.6.3, written without dividing
    by γ). The rotations act on the vectors themselves, not on their Gram matrix, so small
    singular values keep an absolute error of a few ulps of σ1 instead of sqrt(ulp)·σ1.
    """
    r = len(V)
    one, zero = jnp.ones_like(V[0][0]), jnp.zeros_like(V[0][0])
    U = [[one if i == j else zero for j in range(r)] for i in range(r)] if with_rotations else None

    def rotate(a: list, b: list, c, s) -> tuple[list, list]:
        return [c * x - s * y for x, y in zip(a, b)], [s * x + c * y for x, y in zip(a, b)]

    def sweep(_, state):
        V, U = ([list(v) for v in M] if M is not None else None for M in state)
        for p in range(r - 1):
            for q in range(p + 1, r):
                gamma, d = _dot(V[p], V[q]), _dot(V[q], V[q]) - _dot(V[p], V[p])
                den = jnp.abs(d) + _safe_sqrt(d * d + 4.0 * gamma * gamma)
                t = 2.0 * gamma * jnp.where(d < 0, -1.0, 1.0) * _safe_inverse(den)
                c = 1.0 / jnp.sqrt(1.0 + t * t)
                V[p], V[q] = rotate(V[p], V[q], c, t * c)
                if U is not None:
                    U[p], U[q] = rotate(U[p], U[q], c, t * c)
        return V, U

    # One sweep is unrolled; the sweeps run in a loop to keep compile time small.
    return jax.lax.fori_loop(0, JACOBI_SWEEPS.get(jnp.dtype(one.dtype).name, 6), sweep, (V, U))


@jax.custom_jvp
def _singular_values(V: list) -> list:
    """The r singular values (unordered) of r vectors of k ≥ r scalars (:func:`_vectors`).

    With k > r the vectors are first reduced to their r × r triangular factor (fewer numbers
    to rotate: 36 instead of 72 for a 12-joint chain). Derivatives use the singular vectors,
    ``dσ_i = u_iᵀ dV w_i`` (exact for simple singular values), instead of differentiating
    through the sweeps: the same numbers from a far smaller program, compiled in seconds.
    """
    if len(V[0]) > len(V):
        V = _triangular_factor(V)
    B, _ = _jacobi_sweeps(V, with_rotations=False)
    return [_safe_sqrt(_dot(b, b)) for b in B]


@_singular_values.defjvp
def _singular_values_jvp(primals, tangents):
    (V,), (dV,) = primals, tangents
    B, U = _jacobi_sweeps(V, with_rotations=True)
    sigma = [_safe_sqrt(_dot(b, b)) for b in B]
    r = len(V)
    # V = Σ_i u_i σ_i ŵ_iᵀ with u_i the rows of U and ŵ_i = b_i / σ_i: dσ_i = u_iᵀ dV ŵ_i.
    dsigma = [_sum([U[i][a] * _dot(dV[a], B[i]) for a in range(r)]) * _safe_inverse(sigma[i]) for i in range(r)]
    return sigma, dsigma


def kci_from_rows(rows):
    """KCI ``σr / σ1`` for J as m rows of n scalars (0 for J = 0), from one-sided Jacobi
    rotations of J's smaller side: accurate in float32 near singular poses, where the
    eigenvalues of ``J Jᵀ`` are not (docs/theory.md §2)."""
    V = _vectors(rows)
    flat = jnp.broadcast_arrays(*[x for v in V for x in v])
    k = len(V[0])
    sigma = _singular_values([list(flat[i * k : (i + 1) * k]) for i in range(len(V))])
    return functools.reduce(jnp.minimum, sigma) * _safe_inverse(functools.reduce(jnp.maximum, sigma))


@jax.jit
def _kci(J: Array) -> Array:
    return kci_from_rows(_rows(J))


def kci(J, task=None) -> Array:
    """Kinematic conditioning index ``σr / σ1`` ∈ [0, 1] over the ``r = min(m, n)`` singular
    values of ``J: (..., m, n)``, shape ``(...)``; 0 for ``J = 0``. ``task`` as in
    :func:`manipulability`."""
    return _kci(_check_jacobian(J, task))


def singular_values(J, task=None) -> Array:
    """The ``min(m, n)`` singular values ``(..., min(m, n))`` of ``J``, descending."""
    return jnp.linalg.svd(_check_jacobian(J, task), compute_uv=False)


def normalized_jacobian(J, joint_speed_max, task_speed_max) -> Array:
    """``J_n = U J G⁻¹`` with ``G = diag(1/θ̇_max)`` and ``U = diag(1/ṙ_max)`` (docs/theory.md §2).

    Args:
      J: ``(..., m, n)``.
      joint_speed_max: ``(n,)`` joint rate limits [rad/s or m/s].
      task_speed_max: ``(m,)`` task-space rate limits [m/s, rad/s].
    """
    J = _check_jacobian(J)
    joint_speed_max = jnp.asarray(joint_speed_max, dtype=J.dtype)
    task_speed_max = jnp.asarray(task_speed_max, dtype=J.dtype)
    if joint_speed_max.shape != J.shape[-1:] or task_speed_max.shape != J.shape[-2:-1]:
        raise ValueError(
            f"speed limits must have shapes {J.shape[-1:]} (joints) and {J.shape[-2:-1]} (task), "
            f"got {joint_speed_max.shape} and {task_speed_max.shape}"
        )
    return J * joint_speed_max / task_speed_max[:, None]


def joint_torques(J, wrench) -> Array:
    """Static joint torques ``τ = Jᵀ w_ext`` (thesis eq. 4.10), ``(..., n)`` [N·m or N].

    Args:
      J: ``(..., 6, n)`` geometric Jacobian (rows: linear, angular).
      wrench: ``(..., 6)`` external wrench at the tool point ``[f, m]`` [N, N·m], base frame.
    """
    J = _check_jacobian(J)
    wrench = jnp.asarray(wrench, dtype=J.dtype)
    if wrench.shape[-1] != J.shape[-2]:
        raise ValueError(f"wrench must have shape (..., {J.shape[-2]}), got {wrench.shape}")
    return jnp.sum(J * wrench[..., :, None], axis=-2)


def payload_wrench(mass: float, volume: float, rho: float = 1025.0, g: float = 9.81) -> Array:
    """Wrench ``[0, 0, F_b − F_g, 0, 0, 0]`` of a held object: buoyancy ``ρ g V`` minus weight ``m g``.

    Args: mass [kg], volume [m³], rho fluid density [kg/m³] (sea water by default), g [m/s²].
    """
    return jnp.array([0.0, 0.0, rho * g * volume - mass * g, 0.0, 0.0, 0.0])
