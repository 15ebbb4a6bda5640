"""Dexterity indices against SVD / determinant oracles, singular safety, base invariance."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import indices, kin

RTOL = 1e-9  # float64 Cholesky vs SVD: round-off only


def random_q(chain, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = np.maximum(np.asarray(chain.lower), -2.0), np.minimum(np.asarray(chain.upper), 2.0)
    return lo + rng.random((n, chain.n_joints)) * (hi - lo)


@pytest.mark.parametrize("model", [kin.docking_arm, kin.uvms12, kin.bravo7])
@pytest.mark.parametrize("shape", [(50,), (5, 10)])
def test_w_equals_product_of_singular_values_and_sqrt_det(model, shape):
    chain = model()
    q = random_q(chain, int(np.prod(shape)), seed=0).reshape(shape + (chain.n_joints,))
    J = np.asarray(kin.jacobian(chain, q))
    w = np.asarray(jax.jit(indices.manipulability)(J))
    sigma = np.linalg.svd(J, compute_uv=False)
    np.testing.assert_allclose(w, sigma.prod(-1), rtol=RTOL, atol=1e-14)
    np.testing.assert_allclose(w, np.sqrt(np.linalg.det(J @ np.swapaxes(J, -1, -2))), rtol=1e-7)
    k = np.asarray(jax.jit(indices.kci)(J))
    np.testing.assert_allclose(k, sigma[..., -1] / sigma[..., 0], rtol=1e-7)
    assert np.all((k >= 0) & (k <= 1))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_fused_manipulability_equals_two_step(dtype):
    chain = kin.uvms12()
    q = random_q(chain, 60, seed=7).reshape(3, 20, 12).astype(dtype)
    two_step = np.asarray(indices.manipulability(kin.jacobian(chain, q)))
    fused = indices.manipulability_of(chain, q)
    assert fused.dtype == dtype and fused.shape == (3, 20)
    np.testing.assert_allclose(fused, two_step, rtol=1e-5 if dtype == np.float32 else 1e-12)
    # Traced chain (geometry as a jit argument) gives the same values.
    traced = jax.jit(indices.manipulability_of)(chain, q)
    np.testing.assert_allclose(traced, two_step, rtol=1e-5 if dtype == np.float32 else 1e-12)
    sigma = np.linalg.svd(np.asarray(kin.jacobian(chain, q.astype(np.float64))), compute_uv=False)
    kci = indices.kci_of(chain, q)
    assert kci.dtype == dtype
    np.testing.assert_allclose(kci, sigma[..., -1] / sigma[..., 0], rtol=1e-4 if dtype == np.float32 else 1e-10)


def test_indices_float32():
    chain = kin.uvms12()
    q = random_q(chain, 100, seed=1).astype(np.float32)
    J = kin.jacobian(chain, q)
    assert J.dtype == jnp.float32
    sigma = np.linalg.svd(np.asarray(J, dtype=np.float64), compute_uv=False)
    np.testing.assert_allclose(indices.manipulability(J), sigma.prod(-1), rtol=1e-4)
    np.testing.assert_allclose(indices.kci(J), sigma[:, -1] / sigma[:, 0], rtol=1e-3, atol=1e-5)


def test_singular_configurations_give_zero_w_and_finite_gradients():
    """Regression: w → 0 must not produce NaN values or gradients (safe sqrt / divide)."""
    arm = kin.docking_arm()
    singular = np.array(
        [
            [0.3, 0.2, 0.0, 0.1, 0.5, 0.2],  # elbow stretched (θ3 = 0)
            [0.3, 0.2, 0.4, 0.1, np.pi / 2, 0.2],  # wrist singular: axes 4 (z) and 6 (x) align
            [0.0, 0.0, 0.0, 0.0, np.pi / 2, 0.0],  # both
        ]
    )
    w = np.asarray(indices.manipulability(kin.jacobian(arm, singular)))
    assert np.all(w < 1e-8)  # round-off leaves a pivot of O(eps), whose square root is O(1e-8)
    zero = jnp.zeros((6, 6))
    assert float(indices.manipulability(zero)) == 0.0 and float(indices.kci(zero)) == 0.0
    for f in (indices.manipulability, indices.kci):  # each gradient one compiled program
        g = jax.jit(jax.grad(lambda q: f(kin.jacobian(arm, q)).sum()))(jnp.asarray(singular))
        assert np.all(np.isfinite(np.asarray(g)))
        assert np.all(np.isfinite(np.asarray(jax.jit(jax.grad(f))(zero))))


@pytest.mark.parametrize("index", ["manipulability", "kci"])
def test_gradient_matches_finite_differences(index):
    """w (through the Cholesky factors) and KCI (through the eigenvectors of J Jᵀ) against
    central differences of the index itself."""
    chain = kin.uvms12()
    q = jnp.asarray(random_q(chain, 1, seed=2)[0])
    f = jax.jit(lambda q: getattr(indices, index)(kin.jacobian(chain, q)))
    g = np.asarray(jax.grad(f)(q))
    h = 1e-6
    fd = np.array([(f(q + e) - f(q - e)) / (2 * h) for e in h * np.eye(12)])
    np.testing.assert_allclose(g, fd, atol=1e-7)


def test_base_invariance_of_uvms_manipulability():
    """docs/theory.md §1.2: det(JJᵀ) does not depend on θ1…θ4 (vehicle x, y, z, roll) — true for both
    the geometric and the spatial-twist Jacobian — nor on θ12; it does depend on θ5, θ6
    (vehicle pitch and yaw), so the paper's claim holds exactly for θ1…θ4 only."""
    chain = kin.uvms12()
    q = random_q(chain, 20, seed=3)
    for jac in (kin.jacobian, kin.spatial_jacobian):
        w0 = np.asarray(indices.manipulability(jac(chain, q)))
        for j in range(12):
            shifted = q.copy()
            shifted[:, j] += 0.7
            w = np.asarray(indices.manipulability(jac(chain, shifted)))
            change = np.abs(w / w0 - 1.0).max()
            if j in (0, 1, 2, 3, 11):
                assert change < 1e-9, (jac.__name__, j, change)
            if j in (4, 5):
                assert change > 1e-3, (jac.__name__, j, change)


def test_normalized_jacobian_scales_rows_and_columns():
    chain = kin.docking_arm()
    J = np.asarray(kin.jacobian(chain, random_q(chain, 4, seed=4)))
    qd_max = np.array([1.0, 0.5, 0.5, 2.0, 2.0, 3.0])
    rd_max = np.array([0.2, 0.2, 0.2, 1.0, 1.0, 1.0])
    Jn = np.asarray(indices.normalized_jacobian(J, qd_max, rd_max))
    np.testing.assert_allclose(Jn, np.diag(1 / rd_max) @ J @ np.diag(qd_max), rtol=1e-12)
    with pytest.raises(ValueError, match="speed limits"):
        indices.normalized_jacobian(J, qd_max[:5], rd_max)


def test_joint_torques_match_lever_arm_oracle():
    """τ_i = ω_i · ((p_tool − q_i) × F) for a pure force at the tool, from the joint frames."""
    chain = kin.bravo7()
    q = random_q(chain, 30, seed=5)
    wrench = np.asarray(indices.payload_wrench(mass=2.0, volume=0.0005))
    np.testing.assert_allclose(wrench[2], 1025.0 * 9.81 * 0.0005 - 2.0 * 9.81)
    tau = np.asarray(indices.joint_torques(kin.jacobian(chain, q), wrench))
    k = kin.kinematics(chain, q)
    frames, p_tool = np.asarray(k.T_base_joint), np.asarray(k.T_base_tool)[:, :3, 3]
    axes_local = np.array([j.axis for j in kin.BRAVO7_JOINTS])
    for i in range(6):
        axis = np.einsum("nij,j->ni", frames[:, i, :3, :3], axes_local[i])
        lever = p_tool - frames[:, i, :3, 3]
        expected = np.sum(axis * np.cross(lever, wrench[:3]), axis=-1)
        np.testing.assert_allclose(tau[:, i], expected, atol=1e-12)


def test_area_manipulability_matches_plain_loop():
    arm = kin.docking_arm()
    points = indices.control_points([0.0, 0.0, 0.0], 0.4, 3)
    assert points.shape == (9, 3)
    R = np.asarray(indices.approach_down(0.3))
    bases = []
    for x, z in [(-0.45, 0.2), (-0.4, 0.1), (-1.5, 0.0)]:
        T = np.eye(4)
        T[:3, :3] = np.array([[np.cos(0.3), -np.sin(0.3), 0], [np.sin(0.3), np.cos(0.3), 0], [0, 0, 1]])
        T[:3, 3] = [x, 0.05, z]
        bases.append(T)
    bases = np.stack(bases)
    Ma = np.asarray(indices.area_manipulability(arm, bases, points, R))
    for b, T_wb in enumerate(bases):
        best = []
        for p in points:
            T_wt = np.eye(4)
            T_wt[:3, :3], T_wt[:3, 3] = R, p
            sol = kin.elbow_ik(arm, np.linalg.inv(T_wb) @ T_wt)
            ws = [float(indices.manipulability(kin.jacobian(arm, qb))) for qb, ok in zip(np.asarray(sol.q), np.asarray(sol.valid)) if ok]
            best.append(max(ws) if ws else 0.0)
        np.testing.assert_allclose(Ma[b], min(best), rtol=1e-9, atol=1e-15)
    assert Ma[2] == 0.0  # 1.5 m away: out of reach
    assert Ma[0] > 0.0


def test_bad_jacobian_shape():
    with pytest.raises(ValueError, match=r"\(\.\.\., m, n\)"):
        indices.manipulability(np.zeros(6))
    with pytest.raises(ValueError, match="6-row"):
        indices.manipulability(np.zeros((3, 6)), task="position")
    with pytest.raises(ValueError, match="wrench"):
        indices.joint_torques(np.zeros((6, 6)), np.zeros(5))
