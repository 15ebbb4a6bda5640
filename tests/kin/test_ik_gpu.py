"""The GPU kernel of damped least squares IK (uvms_jax.kin._ik_gpu), run emulated on the CPU.

Oracles: the package's array path (rotation_log, spd_solve, dls_step, the XLA loop of dls_ik),
NumPy's solver, and forward kinematics of the results. The Triton lowering itself is checked by
lowering for CUDA (no GPU needed to lower)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import kin
from uvms_jax.kin import _ik, _ik_gpu
from uvms_jax.kin._lie import rotation_log

ITERATIONS, DAMPING = 25, 0.5


@pytest.fixture(scope="module")
def chain():
    return kin.with_dtype(kin.bravo7(), jnp.float32)  # the kernel's dtype (the tests run with x64 on)


def _rows(R):
    return [[R[..., i, j] for j in range(3)] for i in range(3)]


def _rodrigues(axis, theta):
    """Rotations about unit ``axis (n, 3)`` by ``theta (n,)``, in NumPy (the oracle)."""
    K = np.zeros((len(theta), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    K -= np.swapaxes(K, 1, 2)
    return np.eye(3) + np.sin(theta)[:, None, None] * K + (1 - np.cos(theta))[:, None, None] * K @ K


@pytest.mark.parametrize("angle", [None, 1e-7, np.pi - 1e-3, np.pi])
def test_rotation_log_of_random_axes(angle):
    """The kernel's orientation error (rotation_log, one implementation on scalars) inverts
    Rodrigues' formula about random axes, small angles and angles up to π (the sign of the axis
    is free at π)."""
    rng = np.random.default_rng(1)
    axis = rng.normal(size=(200, 3))
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    theta = rng.uniform(0, np.pi - 1e-3, 200) if angle is None else np.full(200, angle)
    got = np.asarray(rotation_log(jnp.asarray(_rodrigues(axis, theta))))
    want = theta[:, None] * axis
    if angle == np.pi:
        want *= np.sign(np.sum(got * want, axis=-1, keepdims=True))
    np.testing.assert_allclose(got, want, atol=1e-6)


def test_spd_solve_against_numpy():
    rng = np.random.default_rng(2)
    M = rng.normal(size=(50, 6, 6))
    A = M @ np.swapaxes(M, 1, 2) + 0.1 * np.eye(6)
    b = rng.normal(size=(50, 6))
    x = kin.spd_solve(jnp.asarray(A), jnp.asarray(b))
    np.testing.assert_allclose(np.asarray(x), np.linalg.solve(A, b[..., None])[..., 0], rtol=1e-8, atol=1e-10)


def _problem(chain, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(chain.lower), np.asarray(chain.upper)
    T = kin.fk(chain, jnp.asarray(rng.uniform(lo, hi, (n, chain.n_joints)), jnp.float32))
    q0 = jnp.asarray(rng.uniform(lo, hi, (n, chain.n_joints)), jnp.float32)
    return T, q0


@pytest.mark.parametrize("limits", ["clip", "wrap"])
def test_one_step_on_scalars_is_dls_step(chain, limits):
    T, q = _problem(chain, 200, 3)
    q = _ik._keep(chain, q, limits)
    want = np.asarray(_ik.dls_step(chain, T, q, DAMPING, limits))
    geometry = [[float(x) for x in row] for row in np.asarray(chain.twists)]
    top = np.asarray(chain.T_base_tool0)[:3]
    got = _ik_gpu.dls_step_scalars(
        geometry, ([list(r[:3]) for r in top], list(top[:, 3])), list(np.asarray(chain.lower)),
        list(np.asarray(chain.upper)), tuple(k == "revolute" for k in chain.kinds),
        (_rows(T[:, :3, :3]), [T[:, i, 3] for i in range(3)]), [q[:, i] for i in range(chain.n_joints)], DAMPING, limits)
    got = np.stack([np.asarray(x) for x in got], axis=-1)
    turn = 2 * np.pi  # a wrapped angle on either side of the wrap point is the same joint position
    diff = np.abs(got - want)
    np.testing.assert_array_less(np.minimum(diff, np.abs(diff - turn)), 1e-4)


@pytest.mark.parametrize("limits", ["clip", "wrap"])
def test_kernel_solves_as_the_xla_loop(chain, limits):
    """25 iterations from random seeds: the kernel and the XLA loop reach the same targets, and
    where both converge they end at the same joint values (round-off only: non-converging
    seeds may part ways, DLS amplifies round-off there)."""
    T, q0 = _problem(chain, 512, 4)
    q0 = _ik._keep(chain, q0, limits)

    def loop(T, q):
        return jax.lax.fori_loop(0, ITERATIONS, lambda _, q: _ik.dls_step(chain, T, q, DAMPING, limits), q)

    xla = np.asarray(jax.jit(loop)(T, q0))
    kernel = np.asarray(_ik_gpu.dls_ik_kernel(chain, T, q0, ITERATIONS, DAMPING, limits, loop, interpret=True))
    reach_xla = np.asarray(kin.reaches(T, kin.fk(chain, jnp.asarray(xla))))
    reach_kernel = np.asarray(kin.reaches(T, kin.fk(chain, jnp.asarray(kernel))))
    assert reach_xla.sum() >= 50  # enough converged seeds for the comparison to mean something
    assert np.mean(reach_xla == reach_kernel) >= 0.98
    both = reach_xla & reach_kernel
    diff = np.abs(kernel - xla)[both]
    np.testing.assert_array_less(np.minimum(diff, np.abs(diff - 2 * np.pi)), 1e-3)


def test_kernel_shapes_broadcast_as_dls_ik(chain):
    """Targets (P, k, 1) against seeds (S, n), as docking calls it: (P, k, S, n)."""
    T, _ = _problem(chain, 6, 5)
    seeds = jnp.asarray(np.random.default_rng(6).uniform(np.asarray(chain.lower), np.asarray(chain.upper), (4, chain.n_joints)), jnp.float32)
    T = T.reshape(3, 2, 1, 4, 4)
    loop = lambda T, q: jax.lax.fori_loop(0, 3, lambda _, q: _ik.dls_step(chain, T, q, DAMPING, "wrap"), q)  # noqa: E731
    q = _ik_gpu.dls_ik_kernel(chain, T, jnp.broadcast_to(seeds, (3, 2, 4, chain.n_joints)), 3, DAMPING, "wrap", loop,
                              interpret=True)
    assert q.shape == (3, 2, 4, chain.n_joints)
    want = loop(T, jnp.broadcast_to(seeds, (3, 2, 4, chain.n_joints)))
    np.testing.assert_allclose(np.asarray(q), np.asarray(want), atol=1e-4)


@pytest.mark.parametrize("limits", ["clip", "wrap"])
def test_kernel_lowers_to_triton(chain, limits):
    """Every operation of the kernel has a Triton lowering (lowered for CUDA on any machine)."""
    T, q0 = _problem(chain, 8, 7)

    def loop(T, q):
        return jax.lax.fori_loop(0, ITERATIONS, lambda _, q: _ik.dls_step(chain, T, q, DAMPING, limits), q)

    solve = lambda T, q: _ik_gpu.dls_ik_kernel(chain, T, q, ITERATIONS, DAMPING, limits, loop)  # noqa: E731
    text = jax.jit(solve).trace(T, q0).lower(lowering_platforms=("cuda",)).as_text()
    assert "triton" in text.lower()
