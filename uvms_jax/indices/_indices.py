"""Dexterity indices of a Jacobian (docs/theory.md §2): manipulability, KCI, normalised Jacobian, torques.

Every index is a function of the ``r = min(m, n)`` singular values ``σ1 ≥ … ≥ σr`` of a
Jacobian ``J: (..., m, n)`` (m task rows, n joints), so it is defined for every shape:

- ``w = σ1 ⋯ σr``: ``sqrt(det J Jᵀ)`` when ``m ≤ n`` (Yoshikawa), ``sqrt(det Jᵀ J)`` when
  ``m > n`` — an arm with fewer joints than task dimensions is scored by the volume its n
  joint rates span, not by a determinant that is 0 because of the shape alone.
- ``KCI = σr / σ1`` (the inverse of the matrix condition number, as ``numpy.linalg.cond``).

The task space is a choice of rows of the 6-row geometric Jacobian (``task=``): ``"full"``,
``"position"``, ``"orientation"`` or row names from ``vx vy vz wx wy wz`` (or indices 0–5).
"""

from __future__ import annotations

import functools
from typing import Sequence

import jax
import jax.numpy as jnp
from jax import Array

from uvms_jax.indices import _gpu
from uvms_jax.kin import Chain, check_joint_array, jacobian_rows

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


def _gram(J: Array) -> Array:
    """``J Jᵀ`` as a fused multiply-sum (fast for small matrices in large batches)."""
    return jnp.sum(J[..., :, None, :] * J[..., None, :, :], axis=-1)


def _safe_sqrt(x: Array) -> Array:
    """``sqrt(max(x, 0))`` whose gradient is 0, not inf/NaN, at and below zero (double where)."""
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def _gram_rows(rows) -> list:
    """The smaller Gram matrix of J given as m rows of n scalars (see
    :func:`uvms_jax.kin.jacobian_rows`): ``J Jᵀ`` (m × m) if ``m ≤ n``, else ``Jᵀ J`` (n × n).
    Both have the squared singular values of J as eigenvalues, and no zero ones from the shape."""
    m, n = len(rows), len(rows[0])
    if m <= n:
        return [[sum(rows[a][k] * rows[b][k] for k in range(n)) for b in range(m)] for a in range(m)]
    return [[sum(rows[k][a] * rows[k][b] for k in range(m)) for b in range(n)] for a in range(n)]


def manipulability_from_rows(rows):
    """``w = ∏ diag(chol(G)) = sqrt(det G)`` for J as m rows of n scalars, G its smaller Gram
    matrix (``J Jᵀ`` if ``m ≤ n``, else ``Jᵀ J``): the product of the min(m, n) singular values.

    The Cholesky factorisation is unrolled on scalars, so over a batch it is one fused
    elementwise kernel. A pivot that is not positive (rank-deficient J) gives 0 for that
    factor and for every later entry that divides by it: w stays finite, is 0 at
    singularities, and has finite gradients there.
    """
    A = _gram_rows(rows)
    m = len(A)
    L = [[None] * m for _ in range(m)]
    w = 1.0
    for j in range(m):
        d = _safe_sqrt(A[j][j] - sum((L[j][k] ** 2 for k in range(j)), start=0.0))
        inv_d = jnp.where(d > 0, 1.0 / jnp.where(d > 0, d, 1.0), 0.0)
        w = w * d
        for i in range(j + 1, m):
            L[i][j] = (A[i][j] - sum((L[i][k] * L[j][k] for k in range(j)), start=0.0)) * inv_d
        L[j][j] = d
    return w


def _rows(J: Array) -> list:
    return [[J[..., a, k] for k in range(J.shape[-1])] for a in range(J.shape[-2])]


@jax.jit
def _manipulability(J: Array) -> Array:
    return manipulability_from_rows(_rows(J))


def manipulability(J, task=None) -> Array:
    """Manipulability ``w = σ1 ⋯ σr``, ``r = min(m, n)``, shape ``(...)``.

    ``sqrt(det J Jᵀ)`` (Yoshikawa) for ``m ≤ n``; ``sqrt(det Jᵀ J)`` for ``m > n`` (fewer
    joints than task dimensions). From an unrolled Cholesky factorisation of the smaller Gram
    matrix (no SVD, no pivoting). ``w ≥ 0``, exactly 0 at singular configurations, with
    finite gradients there. For w of a chain at many configurations,
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
    J = jacobian_rows(chain, q)
    return kci_from_rows([J[r] for r in rows])


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


JACOBI_SWEEPS = 8  # cyclic sweeps; quadratic convergence reaches float64 round-off on 6×6 by ~6


def _jacobi(A, vectors: bool) -> tuple[list, list | None]:
    """Cyclic Jacobi on a small symmetric matrix as nested scalar lists: its eigenvalues and,
    with ``vectors``, the eigenvectors as the columns of ``V`` (nested lists, ``A V = V Λ``)."""
    m = len(A)

    def sweep(_, state):
        A, V = ([list(row) for row in M] if M is not None else None for M in state)
        for p in range(m - 1):
            for q in range(p + 1, m):
                apq, d = A[p][q], A[q][q] - A[p][p]
                den = jnp.abs(d) + _safe_sqrt(d * d + 4.0 * apq * apq)
                t = jnp.where(den > 0, 2.0 * apq * jnp.where(d < 0, -1.0, 1.0) / jnp.where(den > 0, den, 1.0), 0.0)
                c = 1.0 / jnp.sqrt(1.0 + t * t)
                s = t * c
                for r in range(m):
                    if r not in (p, q):
                        arp, arq = A[r][p], A[r][q]
                        A[r][p] = A[p][r] = c * arp - s * arq
                        A[r][q] = A[q][r] = s * arp + c * arq
                A[p][p], A[q][q] = A[p][p] - t * apq, A[q][q] + t * apq
                A[p][q] = A[q][p] = jnp.zeros_like(apq)
                if V is not None:  # the same plane rotation, applied to the columns p and q of V
                    for r in range(m):
                        vrp, vrq = V[r][p], V[r][q]
                        V[r][p], V[r][q] = c * vrp - s * vrq, s * vrp + c * vrq
        return A, V

    flat = jnp.broadcast_arrays(*[x for row in A for x in row])
    A = [list(flat[i * m : (i + 1) * m]) for i in range(m)]
    one, zero = jnp.ones_like(flat[0]), jnp.zeros_like(flat[0])
    V = [[one if i == j else zero for j in range(m)] for i in range(m)] if vectors else None
    # One sweep is unrolled; the sweeps run in a loop to keep compile time small.
    A, V = jax.lax.fori_loop(0, JACOBI_SWEEPS, sweep, (A, V))
    return [A[i][i] for i in range(m)], V


@jax.custom_jvp
def symmetric_eigenvalues_from_rows(A) -> list:
    """Eigenvalues of a small symmetric matrix given as nested scalar lists (cyclic Jacobi).

    Unrolled on scalars, so a batch is one fused elementwise kernel (batched LAPACK/cuSOLVER
    calls are slow for 6×6 and cuSOLVER's batched ``syevj`` rejects some batch shapes). Each
    rotation zeroes ``a_pq`` with ``t = 2 a_pq sgn(d) / (|d| + sqrt(d² + 4 a_pq²))``,
    ``d = a_qq − a_pp`` (Golub & Van Loan §8.5, written without dividing by ``a_pq``).

    Derivatives use the eigenvectors, ``dλ_i = v_iᵀ dA v_i`` (exact for simple eigenvalues),
    instead of differentiating through the sweeps: the same numbers in a program a tenth the
    size, which XLA compiles in seconds rather than half a minute.

    Returns the m eigenvalues, unordered.
    """
    return _jacobi(A, vectors=False)[0]


@symmetric_eigenvalues_from_rows.defjvp
def _symmetric_eigenvalues_jvp(primals, tangents):
    (A,), (dA,) = primals, tangents
    lam, V = _jacobi(A, vectors=True)
    m = len(A)
    dlam = [sum(V[r][i] * dA[r][s] * V[s][i] for r in range(m) for s in range(m)) for i in range(m)]
    return lam, dlam


def kci_from_rows(rows):
    """KCI ``σ_r / σ_1 = sqrt(λ_min / λ_max)`` of the smaller Gram matrix, J as m rows of n scalars."""
    eig = symmetric_eigenvalues_from_rows(_gram_rows(rows))
    lmin, lmax = functools.reduce(jnp.minimum, eig), functools.reduce(jnp.maximum, eig)
    ratio = jnp.maximum(lmin, 0.0) / jnp.where(lmax > 0, lmax, 1.0)
    return jnp.where(lmax > 0, _safe_sqrt(ratio), 0.0)


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
