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


def _q(chain, batch, seed=0):
    lo, hi = np.maximum(chain.lower, -1.0), np.minimum(chain.upper, 1.0)
    return jnp.asarray(np.random.default_rng(seed).uniform(lo, hi, (batch, chain.n_joints)), jnp.float32)


@pytest.mark.parametrize(("index", "make_chain"), [("w", kin.uvms12), ("kci", kin.docking_arm)])
def test_kernel_equals_xla_path(index, make_chain):
    chain = make_chain()
    q = _q(chain, _gpu.BLOCK + 37)  # not a whole number of blocks: padding is cut off
    from_rows, xla = KERNELS[index]
    rows = indices.task_rows("full")
    got = np.asarray(_gpu.index_on_gpu(from_rows, xla, chain, q, rows))
    want = np.asarray(xla(chain, q, rows))
    assert got.shape == (q.shape[0],)
    np.testing.assert_allclose(got, want, rtol=2e-5, atol=1e-6)


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
    q = _q(arm, 10).reshape(2, 5, 4)
    for task in ("position", "full"):
        rows = indices.task_rows(task)
        got = _gpu.index_on_gpu(manipulability_from_rows, _manipulability_of, arm, q, rows)
        want = _manipulability_of(arm, q, rows)
        assert got.shape == (2, 5)
        np.testing.assert_allclose(got, want, rtol=2e-5, atol=1e-7)
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
