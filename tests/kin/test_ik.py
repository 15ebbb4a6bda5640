"""Closed-form and numerical IK: round trips, branch validity against brute force."""

import jax
import numpy as np
import pytest

from uvms_jax import kin

POS_TOL = 1e-8  # [m] float64 round trip
ROT_TOL = 1e-7  # [rad]


def random_in_limits(chain, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(chain.lower), np.asarray(chain.upper)
    return lo + rng.random((n, chain.n_joints)) * (hi - lo)


def fk_flat(chain, q):
    """The oracle FK ``(..., 4, 4)`` of ``q (..., n)`` as NumPy, computed on the flat batch
    padded to a multiple of 256 configurations: one compiled FK serves every batch shape of
    this file (the shape handling under test is the IK's, not the FK's)."""
    flat = np.asarray(q).reshape(-1, chain.n_joints)
    padded = np.zeros((-(-len(flat) // 256) * 256, chain.n_joints))
    padded[: len(flat)] = flat
    return np.array(kin.fk(chain, padded))[: len(flat)].reshape(np.shape(q)[:-1] + (4, 4))


# elbow_ik under a caller's jit (the pose checks see tracers), shared by two tests.
jit_elbow_ik = jax.jit(kin.elbow_ik)


# Batch shapes and call paths shared with the other tests of this file (one target and 12
# targets eagerly, 5 × 30 targets under jit), so each compiled IK program serves two tests.
@pytest.mark.parametrize(("shape", "under_jit"), [((), False), ((12,), False), ((5, 30), True)])
def test_elbow_ik_round_trip_on_every_valid_branch(shape, under_jit):
    arm = kin.docking_arm()
    q = random_in_limits(arm, int(np.prod(shape, dtype=int)), seed=0).reshape(shape + (6,))
    T = fk_flat(arm, q)
    sol = (jit_elbow_ik if under_jit else kin.elbow_ik)(arm, T)
    assert sol.q.shape == shape + (8, 6) and sol.valid.shape == shape + (8,)
    valid = np.asarray(sol.valid)
    assert valid.any(axis=-1).all(), "the generating configuration must be among the branches"
    T_back = fk_flat(arm, np.where(valid[..., None], sol.q, 0.0))
    T_rep = np.broadcast_to(T[..., None, :, :], T_back.shape)
    np.testing.assert_allclose(T_back[valid], T_rep[valid], atol=POS_TOL)
    assert np.isnan(np.asarray(sol.q)[~valid]).all()
    # The generating configuration itself is recovered by one branch (modulo 2π: joints
    # whose range exceeds 2π have two representatives, the branch takes the lower one).
    diff = np.angle(np.exp(1j * (np.asarray(sol.q) - np.asarray(q)[..., None, :])))
    dist = np.where(valid, np.abs(diff).max(-1), np.inf)
    assert (dist.min(axis=-1) < 1e-6).all()


def test_elbow_branch_mask_matches_brute_force_check():
    """The mask equals a plain NumPy check of every raw algebraic branch: inside the limits
    (modulo 2π) and FK(q) = T."""
    from uvms_jax.kin._ik import elbow_branches

    arm = kin.docking_arm()
    lo, hi = np.asarray(arm.lower), np.asarray(arm.upper)
    rng = np.random.default_rng(2)
    # Mix reachable targets and targets ≥ 1 m from the base, beyond the 0.8 m reach of the
    # shoulder (0.1 m above the base).
    q = random_in_limits(arm, 150, seed=2)
    T = fk_flat(arm, q)
    far = T[100:, :3, 3]
    T[100:, :3, 3] = far / np.linalg.norm(far, axis=-1, keepdims=True) * rng.uniform(1.0, 3.0, (50, 1))
    raw = np.asarray(jax.jit(jax.vmap(elbow_branches, in_axes=(None, 0)))(arm, T).q)  # unmasked angles
    T_raw = fk_flat(arm, raw)
    # A (5, 30) batch: the compiled IK of the round-trip test's (5, 30) case.
    valid = np.asarray(jit_elbow_ik(arm, T.reshape(5, 30, 4, 4)).valid).reshape(150, 8)
    inside = np.all((raw >= lo) & (raw <= hi), axis=-1)  # (150, 8)
    reaches = np.abs(T_raw - T[:, None]).max(axis=(-1, -2)) < 1e-7
    for i in range(len(T)):
        for b in range(8):
            assert bool(valid[i, b]) == (inside[i, b] and reaches[i, b]), (i, b)
    assert not valid[100:].any(), "targets beyond reach must have no valid branch"


def _mod_2pi_key(q):
    return tuple(np.round(np.mod(q + 1e-7, 2 * np.pi), 4))


def test_elbow_ik_finds_every_solution_numerical_ik_finds():
    """Completeness: distinct in-limit solutions found by damped least squares from many
    random seeds (an independent algorithm) are all among the closed-form valid branches."""
    arm = kin.docking_arm()
    q = random_in_limits(arm, 12, seed=3)
    T = fk_flat(arm, q)
    closed = kin.elbow_ik(arm, T)
    numeric = kin.numeric_ik(jax.random.key(0), arm, T, n_seeds=128, iterations=200, all_seeds=True)
    closed_q, closed_valid = np.asarray(closed.q), np.asarray(closed.valid)
    numeric_q, numeric_valid = np.asarray(numeric.q), np.asarray(numeric.valid)
    n_found = 0
    for i in range(len(T)):
        branches = {_mod_2pi_key(x) for x in closed_q[i][closed_valid[i]]}
        for x in numeric_q[i][numeric_valid[i]]:
            assert _mod_2pi_key(x) in branches, (i, x)
            n_found += 1
    assert n_found > 100  # the oracle actually found solutions


@pytest.mark.parametrize("model", [kin.bravo7, kin.uvms12])
def test_numeric_ik_round_trip(model):
    chain = model()
    q = random_in_limits(chain, 16, seed=4)
    if chain.name == "uvms12":
        q[:, :3] = np.clip(q[:, :3], -1.0, 1.0)
    T = fk_flat(chain, q)
    sol = kin.numeric_ik(jax.random.key(1), chain, T, n_seeds=32, iterations=150)
    assert sol.q.shape == (16, chain.n_joints)
    valid = np.asarray(sol.valid)
    assert valid.mean() >= 0.9
    np.testing.assert_allclose(fk_flat(chain, np.asarray(sol.q)[valid]), T[valid], atol=1e-6)
    assert np.all(np.asarray(sol.q)[valid] >= np.asarray(chain.lower)) and np.all(np.asarray(sol.q)[valid] <= np.asarray(chain.upper))


def test_unreachable_target_is_masked():
    arm = kin.docking_arm()
    T = np.eye(4)
    T[:3, 3] = [3.0, 0.0, 0.0]  # far beyond the 0.8 m reach
    sol = kin.elbow_ik(arm, T)
    assert not np.asarray(sol.valid).any() and np.isnan(np.asarray(sol.q)).all()
    num = kin.numeric_ik(jax.random.key(0), arm, T, n_seeds=8, iterations=50)
    assert not bool(num.valid) and np.isnan(np.asarray(num.q)).all()


def test_ik_bad_input():
    arm = kin.docking_arm()
    with pytest.raises(ValueError, match=r"\(\.\.\., 4, 4\)"):
        kin.elbow_ik(arm, np.eye(3))
    with pytest.raises(ValueError, match="NaN"):
        kin.elbow_ik(arm, np.full((4, 4), np.nan))
    with pytest.raises(ValueError, match="6R"):
        kin.elbow_ik(kin.uvms12(), np.eye(4))
