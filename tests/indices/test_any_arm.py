"""w and KCI for any number of joints and a chosen task space, against numpy determinants and SVDs."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from uvms_jax import indices, kin, robot

RTOL = 1e-9  # float64 Cholesky / Jacobi vs LAPACK: round-off only


def _bravo_to(link: str) -> kin.Chain:
    """The first joints of the Bravo 7, up to ``link`` (4 joints to link_D, 5 to link_C)."""
    return robot.chain_from_urdf(kin.bravo7_urdf(), tip_link=link)


def random_q(chain, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = np.maximum(np.asarray(chain.lower), -2.0), np.minimum(np.asarray(chain.upper), 2.0)
    return lo + rng.random((n, chain.n_joints)) * (hi - lo)


@pytest.mark.parametrize("link,n", [("link_D", 4), ("link_C", 5)])
def test_fewer_joints_than_task_rows_gives_sqrt_det_JtJ(link, n):
    arm = _bravo_to(link)
    assert arm.n_joints == n
    q = random_q(arm, 40, seed=n)
    J = np.asarray(kin.jacobian(arm, q))  # (40, 6, n)
    w = np.asarray(indices.manipulability_of(arm, q))
    det_JtJ = np.linalg.det(np.swapaxes(J, -1, -2) @ J)
    np.testing.assert_allclose(w, np.sqrt(det_JtJ), rtol=1e-7)
    sigma = np.linalg.svd(J, compute_uv=False)  # (40, n)
    np.testing.assert_allclose(w, sigma.prod(-1), rtol=RTOL)
    np.testing.assert_allclose(indices.manipulability(J), w, rtol=RTOL)
    assert np.all(w > 1e-6)  # not the shape's 0: det J Jᵀ of a 6×n, n < 6, Jacobian is 0
    assert np.all(np.abs(np.linalg.det(J @ np.swapaxes(J, -1, -2))) < 1e-12)
    k = np.asarray(indices.kci_of(arm, q))
    np.testing.assert_allclose(k, sigma[:, -1] / sigma[:, 0], rtol=1e-7)
    np.testing.assert_allclose(indices.kci(J), k, rtol=1e-7)


def test_fewer_joints_indices_do_not_depend_on_the_base_orientation():
    """JᵀJ of a re-based arm is Jᵀ diag(R, R)ᵀ diag(R, R) J = JᵀJ."""
    arm = _bravo_to("link_D")
    mount = np.eye(4)
    mount[:3, :3] = Rotation.from_euler("XYZ", [0.4, -1.1, 2.0]).as_matrix()
    mount[:3, 3] = [0.3, -0.2, 0.5]
    rebased = kin.uvms(arm, mount=mount, vehicle_dofs=())
    q = random_q(arm, 40, seed=1)
    for index in (indices.manipulability_of, indices.kci_of):
        np.testing.assert_allclose(index(rebased, q), index(arm, q), rtol=1e-9)


def test_more_joints_than_task_rows_gives_sqrt_det_JJt():
    chain = kin.uvms(kin.bravo7(), vehicle_dofs=("x", "y", "z", "yaw"))  # 10 joints
    q = random_q(chain, 30, seed=2)
    J = np.asarray(kin.jacobian(chain, q))
    w = np.asarray(indices.manipulability_of(chain, q))
    np.testing.assert_allclose(w, np.sqrt(np.linalg.det(J @ np.swapaxes(J, -1, -2))), rtol=1e-7)
    sigma = np.linalg.svd(J, compute_uv=False)
    np.testing.assert_allclose(indices.kci_of(chain, q), sigma[:, -1] / sigma[:, 0], rtol=1e-7)


@pytest.mark.parametrize(
    "task,rows",
    [("position", [0, 1, 2]), ("orientation", [3, 4, 5]), (("vx", "vy", "vz", "wz"), [0, 1, 2, 5]), ((5, 0), [5, 0])],
)
def test_task_space_rows(task, rows):
    arm = _bravo_to("link_C")  # 5 joints: a 4-row task is wide, a 3-row one too
    q = random_q(arm, 40, seed=3)  # 40 as in the 5-joint case above: one compiled Jacobian serves both
    J_full = kin.jacobian(arm, q)
    J = np.asarray(J_full)[:, rows]
    sigma = np.linalg.svd(J, compute_uv=False)
    np.testing.assert_allclose(indices.manipulability_of(arm, q, task=task), sigma.prod(-1), rtol=RTOL)
    np.testing.assert_allclose(indices.kci_of(arm, q, task=task), sigma[:, -1] / sigma[:, 0], rtol=1e-7)
    np.testing.assert_allclose(indices.manipulability(J_full, task=task), sigma.prod(-1), rtol=RTOL)
    np.testing.assert_allclose(indices.singular_values(J_full, task=task), sigma, rtol=1e-9)


def test_full_task_is_the_default_and_named_rows_are_indices():
    assert indices.task_rows(None) == indices.task_rows("full") == (0, 1, 2, 3, 4, 5)
    assert indices.task_rows(("vx", "vy", "vz")) == indices.task_rows("position") == (0, 1, 2)
    for bad, match in (("pose", "unknown task"), (("vx", "v"), "unknown Jacobian row"), ((6,), "out of range"),
                       ((), "distinct"), (("vx", 0), "distinct")):
        with pytest.raises(ValueError, match=match):
            indices.task_rows(bad)


def test_tall_jacobian_zero_and_singular_have_finite_gradients():
    """Regression for the JᵀJ path: w = 0 and KCI = 0 at J = 0, with finite gradients."""
    zero = jnp.zeros((6, 4))
    for f in (indices.manipulability, indices.kci):
        value, grad = jax.jit(jax.value_and_grad(f))(zero)  # one compiled program for both
        assert float(value) == 0.0
        assert np.all(np.isfinite(np.asarray(grad)))
    arm = _bravo_to("link_D")
    q = jnp.zeros(4)  # folded Bravo at q = 0
    g = jax.jit(jax.grad(lambda q: indices.manipulability(kin.jacobian(arm, q))))(q)
    assert np.all(np.isfinite(np.asarray(g)))
