"""The GPU kernel of the fused indices (a Pallas program), run emulated on the CPU: the same
numbers as the XLA path, for any batch size, task space and joint count, and the XLA path's
derivatives."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import indices, kin
from uvms_jax.indices import _gpu
from uvms_jax.indices._indices import _kci_of, _manipulability_of, kci_from_rows, manipulability_from_rows

KERNELS = {"w": (manipulability_from_rows, _manipulability_of), "kci": (kci_from_rows, _kci_of)}


def _q(chain, batch, seed=0, dtype=jnp.float32):
    lo, hi = np.maximum(chain.lower, -1.0), np.minimum(chain.upper, 1.0)
    return jnp.asarray(np.random.default_rng(seed).uniform(lo, hi, (batch, chain.n_joints)), dtype)


@pytest.mark.parametrize(("index", "make_chain"), [("w", kin.uvms12), ("kci", kin.docking_arm)])
def test_kernel_equals_xla_path(index, make_chain):
    """The same expression compiled two ways agrees to round-off in float64. In float32 (the
    GPU's type) the kernel is checked against the float64 value: KCI = √(λmin/λmax) from the
    eigenvalues of the 6 × 6 Gram matrix carries an absolute error up to about √(6 eps) near a
    singularity however the compiler orders the arithmetic, so two float32 programs need not
    agree bit for bit."""
    chain = make_chain()
    from_rows, xla = KERNELS[index]
    rows = indices.task_rows("full")
    q = _q(chain, _gpu.BLOCK + 37, dtype=jnp.float64)  # not a whole number of blocks: padding is cut off
    got = np.asarray(_gpu.index_on_gpu(from_rows, xla, chain, q, rows))
    want = np.asarray(xla(chain, q, rows))
    assert got.shape == (q.shape[0],) and got.dtype == np.float64
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-13)
    got32 = np.asarray(_gpu.index_on_gpu(from_rows, xla, chain, q.astype(jnp.float32), rows))
    assert got32.dtype == np.float32
    kci_atol = np.sqrt(6 * np.finfo(np.float32).eps)  # 8.5e-4; w: relative error only
    np.testing.assert_allclose(got32, want, rtol=1e-4, atol=kci_atol if index == "kci" else 0.0)


def _four_joint_arm():
    x, y, z = np.eye(3)
    return kin.make_chain(
        twists=np.stack([kin.revolute_twist(z, (0, 0, 0)), kin.revolute_twist(y, (0, 0, 0.2)),
                         kin.revolute_twist(y, (0.3, 0, 0.2)), kin.revolute_twist(x, (0.5, 0, 0.2))]),
        T_base_tool0=np.array([[1, 0, 0, 0.6], [0, 1, 0, 0], [0, 0, 1, 0.2], [0, 0, 0, 1.0]]),
        lower=[-np.pi] * 4, upper=[np.pi] * 4, kinds=["revolute"] * 4)


def test_kernel_task_rows_short_arm_and_batch_shape():
    """A 4-joint arm in the position task (3 rows ≤ 4 joints) and the full task (6 rows > 4
    joints), on a (2, 5, 4) batch."""
    arm = _four_joint_arm()
    q = _q(arm, 10, dtype=jnp.float64).reshape(2, 5, 4)  # float64: equal to round-off (see above)
    for task in ("position", "full"):
        rows = indices.task_rows(task)
        got = _gpu.index_on_gpu(manipulability_from_rows, _manipulability_of, arm, q, rows)
        want = _manipulability_of(arm, q, rows)
        assert got.shape == (2, 5)
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-13)
        assert np.all(np.asarray(got) > 0)


def test_kernel_derivative_is_the_xla_paths():
    chain = _four_joint_arm()
    q = _q(chain, 3, seed=1)
    rows = indices.task_rows("full")

    def total(fn):  # one compiled program per derivative, not one per primitive
        return jax.jit(jax.grad(lambda q: jnp.sum(fn(q))))(q)

    got = total(lambda q: _gpu.index_on_gpu(manipulability_from_rows, _manipulability_of, chain, q, rows))
    want = total(lambda q: _manipulability_of(chain, q, rows))
    np.testing.assert_allclose(got, want, rtol=1e-6)


def test_gpu_path_only_where_it_applies(monkeypatch):
    chain = _four_joint_arm()
    q = _q(chain, 4)
    assert _gpu.applies(chain, q) == (jax.default_backend() == "gpu")
    monkeypatch.setattr(jax, "default_backend", lambda: "gpu")
    assert _gpu.applies(chain, q)
    assert not _gpu.applies(chain, q.astype(jnp.int32))
    seen = []

    def scaled_chain(s):  # a traced geometry (as under a design derivative) takes the XLA path
        scaled = chain.replace(twists=chain.twists * s, T_base_tool0=chain.T_base_tool0 * s)
        seen.append(_gpu.applies(scaled, q))
        return scaled.twists

    jax.make_jaxpr(scaled_chain)(1.0)
    assert seen == [False]
