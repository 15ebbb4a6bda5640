"""FK and Jacobians against finite differences and against pytorch-kinematics on exported URDFs."""

import jax
import numpy as np
import pytest
import pytorch_kinematics as pk
import torch

from uvms_jax import kin

MODELS = {"docking_arm": kin.docking_arm, "uvms12": kin.uvms12, "bravo7": kin.bravo7}
N_RANDOM = 1000
ATOL_64 = 1e-9  # float64 vs float64 computations of the same model: only round-off differs
ATOL_ORACLE = 1e-6  # pytorch-kinematics parses URDF numbers as float32 before casting to float64
ATOL_32 = 2e-5  # float32 FK of sub-metre chains vs float64 reference
ATOL_BRAVO7 = 1e-4  # acceptance tolerance of the Bravo 7 check [m, rad]
FD_STEP = 1e-6
FD_ATOL = 1e-7  # central differences in float64: O(h²) truncation + round-off


def random_q(chain, n, seed=0, dtype=np.float64):
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(chain.lower), np.asarray(chain.upper)
    # The UVMS vehicle box is ±10 m; sample a physically sensible ±2 m instead.
    lo, hi = np.maximum(lo, -2.0), np.minimum(hi, 2.0) if chain.name == "uvms12" else hi
    return (lo + rng.random((n, chain.n_joints)) * (hi - lo)).astype(dtype)


def torch_chain(urdf: str):
    return pk.build_serial_chain_from_urdf(urdf, "tool").to(dtype=torch.float64)


@pytest.mark.parametrize("name", list(MODELS))
def test_fk_and_jacobian_match_pytorch_kinematics(name):
    chain = MODELS[name]()
    q = random_q(chain, N_RANDOM, seed=1)
    oracle = torch_chain(kin.to_urdf(chain))
    T_ref = oracle.forward_kinematics(torch.from_numpy(q)).get_matrix().numpy()
    J_ref = oracle.jacobian(torch.from_numpy(q)).numpy()
    T = np.asarray(jax.jit(kin.fk)(chain, q))
    J = np.asarray(jax.jit(kin.jacobian)(chain, q))
    np.testing.assert_allclose(T, T_ref, atol=ATOL_ORACLE)
    np.testing.assert_allclose(J, J_ref, atol=ATOL_ORACLE)


def test_bravo7_matches_pytorch_kinematics_on_spec_urdf():
    """Acceptance: the URDF written from the Bravo 7 table (docs/theory.md §1.3), in float64 and float32."""
    chain = kin.bravo7()
    oracle = torch_chain(kin.bravo7_urdf())
    q = random_q(chain, N_RANDOM, seed=2)
    T_ref = oracle.forward_kinematics(torch.from_numpy(q)).get_matrix().numpy()
    J_ref = oracle.jacobian(torch.from_numpy(q)).numpy()
    for dtype, atol in ((np.float64, ATOL_ORACLE), (np.float32, ATOL_32)):
        T = np.asarray(kin.fk(chain, q.astype(dtype)))
        J = np.asarray(kin.jacobian(chain, q.astype(dtype)))
        assert T.dtype == dtype and J.dtype == dtype
        np.testing.assert_allclose(T, T_ref, atol=atol)
        np.testing.assert_allclose(J, J_ref, atol=atol)
        assert np.abs(T - T_ref).max() < ATOL_BRAVO7 and np.abs(J - J_ref).max() < ATOL_BRAVO7


def _rotation_increment(R_plus, R_minus, R, h):
    """Angular velocity from central differences: (dR/dq) Rᵀ is skew(ω)."""
    W = (R_plus - R_minus) / (2 * h) @ np.swapaxes(R, -1, -2)
    return np.stack([W[..., 2, 1], W[..., 0, 2], W[..., 1, 0]], axis=-1)


@pytest.mark.parametrize("name", list(MODELS))
def test_jacobians_match_finite_differences(name):
    chain = MODELS[name]()
    q = random_q(chain, 50, seed=3)
    T = np.asarray(kin.fk(chain, q))
    J = np.asarray(kin.jacobian(chain, q))
    Js = np.asarray(kin.spatial_jacobian(chain, q))
    for i in range(chain.n_joints):
        dq = np.zeros(chain.n_joints)
        dq[i] = FD_STEP
        Tp, Tm = np.asarray(kin.fk(chain, q + dq)), np.asarray(kin.fk(chain, q - dq))
        v_point = (Tp[:, :3, 3] - Tm[:, :3, 3]) / (2 * FD_STEP)
        omega = _rotation_increment(Tp[:, :3, :3], Tm[:, :3, :3], T[:, :3, :3], FD_STEP)
        np.testing.assert_allclose(J[:, :3, i], v_point, atol=FD_ATOL)
        np.testing.assert_allclose(J[:, 3:, i], omega, atol=FD_ATOL)
        # Spatial twist: (dT/dq) T⁻¹ = [ω̂ v; 0 0].
        dT = (Tp - Tm) / (2 * FD_STEP) @ np.linalg.inv(T)
        np.testing.assert_allclose(Js[:, :3, i], dT[:, :3, 3], atol=FD_ATOL)
        np.testing.assert_allclose(Js[:, 3:, i], omega, atol=FD_ATOL)


_VMAP_BATCH = 32  # ≥ the largest batch below
_fk_vmapped = jax.jit(jax.vmap(kin.fk, in_axes=(None, 0)))


@pytest.mark.parametrize("shape", [(), (7,), (2, 3), (4, 1, 5)])
def test_batch_shapes_and_batched_equals_looped(shape):
    chain = kin.uvms12()
    q = random_q(chain, int(np.prod(shape, dtype=int)), seed=4).reshape(shape + (12,))
    T = kin.fk(chain, q)
    J = kin.jacobian(chain, q)
    k = kin.kinematics(chain, q)
    assert T.shape == shape + (4, 4) and J.shape == shape + (6, 12)
    assert k.T_base_joint.shape == shape + (12, 4, 4)
    flat_q = q.reshape(-1, 12)
    looped = np.stack([np.asarray(kin.jacobian(chain, qi)) for qi in flat_q]).reshape(J.shape)
    np.testing.assert_allclose(J, looped, atol=ATOL_64)
    # Under an outer jit and vmap as well, on the flat batch padded to a fixed size (one
    # compiled program for every case).
    padded = np.zeros((_VMAP_BATCH, 12))
    padded[: len(flat_q)] = flat_q
    vm = np.asarray(_fk_vmapped(chain, padded))[: len(flat_q)].reshape(T.shape)
    np.testing.assert_allclose(T, vm, atol=ATOL_64)


def test_joint_frames_match_pytorch_kinematics_links():
    """Every joint frame equals the frame of the URDF link it moves (Bravo 7 table URDF)."""
    chain = kin.bravo7()
    q = random_q(chain, 20, seed=5)
    frames = np.asarray(kin.kinematics(chain, q).T_base_joint)
    full = pk.build_chain_from_urdf(kin.bravo7_urdf()).to(dtype=torch.float64)
    th = np.concatenate([q, np.zeros((20, 1))], axis=1)  # jaws joint A at 0
    names = full.get_joint_parameter_names()
    order = [names.index(n) for n in ["G", "F", "E", "D", "C", "B", "A"]]
    th_ordered = np.zeros_like(th)
    th_ordered[:, order] = th
    links = full.forward_kinematics(torch.from_numpy(th_ordered))
    for i, j in enumerate(kin.BRAVO7_JOINTS):
        np.testing.assert_allclose(frames[:, i], links[f"link_{j.name}"].get_matrix().numpy(), atol=ATOL_ORACLE)


def test_bad_input_raises_clear_errors():
    chain = kin.docking_arm()
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 6\)"):
        kin.fk(chain, np.zeros((3, 5)))
    with pytest.raises(ValueError, match="NaN"):
        kin.jacobian(chain, np.full(6, np.nan))
    with pytest.raises(ValueError, match="inverted"):
        kin.make_chain(np.asarray(chain.twists), np.eye(4), [1.0] * 6, [0.0] * 6, ["revolute"] * 6)
    with pytest.raises(ValueError, match="unit"):
        kin.make_chain(2 * np.asarray(chain.twists), np.eye(4), [-1.0] * 6, [1.0] * 6, ["revolute"] * 6)


def test_mjcf_loads_in_mujoco_and_matches_fk():
    import mujoco

    chain = kin.bravo7()
    from uvms_jax import robot

    model = robot.robot_spec(robot.load_arm("bravo7")).compile()
    data = mujoco.MjData(model)
    site = model.site("tool").id
    q = random_q(chain, 50, seed=6)
    T = np.asarray(kin.fk(chain, q))
    for qi, Ti in zip(q, T):
        data.qpos[:] = qi
        mujoco.mj_kinematics(model, data)
        np.testing.assert_allclose(data.site_xpos[site], Ti[:3, 3], atol=1e-9)
        np.testing.assert_allclose(data.site_xmat[site].reshape(3, 3), Ti[:3, :3], atol=1e-9)


def test_gradient_in_the_geometry_matches_finite_differences():
    """The chain's twists and tool pose are traced leaves: d(FK, J)/d(geometry) is exact."""
    chain = kin.bravo7()
    q = random_q(chain, 8, seed=6)
    rng = np.random.default_rng(7)
    d_twists = rng.normal(size=np.shape(chain.twists))
    d_tool = np.zeros((4, 4))
    d_tool[:3, 3] = rng.normal(size=3)

    def f(s):
        moved = chain.replace(twists=chain.twists + s * d_twists, T_base_tool0=chain.T_base_tool0 + s * d_tool)
        T, J = kin.fk(moved, q), kin.jacobian(moved, q)
        return jax.numpy.sum(T[..., :3, :] ** 2) + jax.numpy.sum(jax.numpy.sin(J))

    grad = float(jax.jit(jax.grad(f))(0.0))
    f = jax.jit(f)  # one compiled program for both finite-difference points
    fd = (f(FD_STEP) - f(-FD_STEP)) / (2 * FD_STEP)
    np.testing.assert_allclose(grad, fd, rtol=1e-7, atol=FD_ATOL)


def test_one_compiled_program_serves_every_geometry():
    """No cache keyed on the numbers: a sweep over link lengths reuses one compiled FK."""
    from uvms_jax.kin import _fk

    q = np.zeros((3, 6))
    kin.fk(kin.docking_arm(), q)
    size = _fk._fk._cache_size()
    for l1 in (0.3, 0.35, 0.45, 0.5):
        T = kin.fk(kin.docking_arm(l1=l1, l2=0.4), q)
        np.testing.assert_allclose(np.asarray(T)[:, 0, 3], l1 + 0.4, atol=ATOL_64)
    assert _fk._fk._cache_size() == size


def test_spatial_jacobian_rows_are_the_spatial_jacobian():
    chain = kin.uvms12()
    q = np.random.default_rng(3).uniform(-1.0, 1.0, (5, chain.n_joints))
    rows = kin.spatial_jacobian_rows(chain, q)  # entries broadcast to the batch (constants stay scalars)
    J = np.stack([np.stack([np.broadcast_to(x, q.shape[:-1]) for x in r], -1) for r in rows], -2)
    np.testing.assert_allclose(J, kin.spatial_jacobian(chain, q), rtol=1e-12, atol=1e-12)
