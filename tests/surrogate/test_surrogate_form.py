"""Jacobian forms of the indices: the geometric default and the dexterity paper's spatial form (eq. 6–7)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import kin
from uvms_jax.surrogate import IndexForm, Sampling, analytic_index, analytic_index_fn, make_dataset

N = 64
# float64 throughout; the fused kernels and the stored-J oracle differ by rounding only.
ATOL = 1e-10


@pytest.fixture(scope="module", autouse=True)
def x64():
    with jax.enable_x64(True):
        yield


@pytest.fixture(scope="module")
def chain():
    return kin.uvms12()


def _d1(chain, key):
    """The paper's D1 (KCI of the spatial form), N samples; every call shares one compile."""
    return make_dataset(key, chain, Sampling(), N, "kci", jnp.float64, form=IndexForm("spatial"))


@pytest.fixture(scope="module")
def q(chain, x64):
    # The sampled q does not depend on the index labelled: this reuses the D1 test's compile.
    return _d1(chain, jax.random.key(1)).q


def _oracle(J, index):
    """Index from the singular values of a stored J (LAPACK SVD), independent of the fused kernels."""
    s = np.linalg.svd(np.asarray(J), compute_uv=False)
    return s.prod(-1) if index == "w" else s[..., -1] / s[..., 0]


@pytest.mark.parametrize("index", ["w", "kci"])
@pytest.mark.parametrize("jacobian", ["geometric", "spatial"])
def test_index_matches_svd_of_the_stored_jacobian(chain, q, index, jacobian):
    J = (kin.jacobian if jacobian == "geometric" else kin.spatial_jacobian)(chain, q)
    got = analytic_index(chain, q, index, IndexForm(jacobian))
    np.testing.assert_allclose(np.asarray(got), _oracle(J, index), atol=ATOL, rtol=1e-9)


@pytest.mark.slow  # compiles the KCI kernel once more, for the normalised form (~30 s on 2 cores)
def test_normalisation_is_eq_7(chain, q):
    rng = np.random.default_rng(0)
    joint, task = rng.uniform(0.2, 2.0, 12), rng.uniform(0.2, 2.0, 6)
    form = IndexForm("spatial", tuple(joint), tuple(task))
    J = np.diag(1.0 / task) @ np.asarray(kin.spatial_jacobian(chain, q)) @ np.diag(joint)  # U J G⁻¹
    for index in ("w", "kci"):
        np.testing.assert_allclose(np.asarray(analytic_index(chain, q, index, form)), _oracle(J, index),
                                   atol=ATOL, rtol=1e-9)


def test_spatial_kci_depends_on_the_vehicle_joints_geometric_does_not(chain, q):
    """The paper's KCI (spatial form) changes with θ1…θ4 and falls as the vehicle moves away;
    the geometric form's does not change (base invariance). w is the same in both forms."""
    moved = q.at[:, 0].add(2.0).at[:, 1].add(-1.0).at[:, 3].add(0.2)
    spatial, geometric = IndexForm("spatial"), IndexForm("geometric")
    k_s, k_s_moved = (analytic_index(chain, x, "kci", spatial) for x in (q, moved))
    k_g, k_g_moved = (analytic_index(chain, x, "kci", geometric) for x in (q, moved))
    np.testing.assert_allclose(np.asarray(k_g_moved), np.asarray(k_g), atol=ATOL)
    assert float(jnp.min(jnp.abs(k_s_moved - k_s))) > 1e-3
    far = q.at[:, 0].add(5.0)
    assert bool(jnp.all(analytic_index(chain, far, "kci", spatial) < k_s))
    np.testing.assert_allclose(np.asarray(analytic_index(chain, q, "w", spatial)),
                               np.asarray(analytic_index(chain, q, "w", geometric)), rtol=1e-10)


def test_spatial_kci_dataset_varies_with_theta_1_to_4(chain):
    """The D1 of the paper's form: KCI is not a function of θ5…θ11 alone (two samples that share
    θ5…θ11 but not θ1…θ4 get different KCI)."""
    d1 = _d1(chain, jax.random.key(2))
    shifted = d1.q.at[:, :4].set(d1.q[::-1, :4])  # θ1…θ4 of other samples, θ5…θ12 kept
    k_shifted = analytic_index(chain, shifted, "kci", d1.form)
    assert float(jnp.max(jnp.abs(k_shifted - d1.y))) > 0.02
    ranges = float(d1.y.min()), float(d1.y.max())
    assert 0.15 < ranges[0] < ranges[1] < 0.55  # the paper's KCI spans 0.20–0.50 (§4.4, Figs. 12–15)
    # (the geometric form's invariance to θ1…θ4 is checked in the test above)


def test_bad_forms_are_named():
    with pytest.raises(ValueError, match="Jacobian form"):
        IndexForm("body")
    with pytest.raises(ValueError, match="task_speed_max"):
        IndexForm("spatial", task_speed_max=(1.0, 1.0))
    with pytest.raises(ValueError, match="joint_speed_max"):
        IndexForm("spatial", joint_speed_max=(1.0, -1.0))
    with pytest.raises(ValueError, match="12 entries"):
        analytic_index_fn(kin.uvms12(), "w", IndexForm("spatial", joint_speed_max=(1.0,) * 6))
