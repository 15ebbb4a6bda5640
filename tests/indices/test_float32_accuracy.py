"""w and KCI in float32 near singular poses, against float64 singular values (numpy's SVD).

The configurations are found, not assumed: ``indices.near_singular_poses`` walks random poses
onto the singular set by Newton steps on the smallest singular value of J (float64, through
JAX's SVD); a third of the set sits on it, a third within 1e-3 rad of it, a third is uniform.
The same set defeats the Gram form (``sqrt(det J Jᵀ)`` and the eigenvalues of ``J Jᵀ`` in
float32), so the bounds below test the factorisation, not an easy sample.
"""

import importlib.metadata

import jax.numpy as jnp
import numpy as np
import pytest

from uvms_jax import indices, kin, robot
from uvms_jax.robot import load_arm

W_TOL = 1e-5  # |w32 − w64| over the set's largest w
KCI_TOL = 1e-4  # |KCI32 − KCI64|

ROBOTS = importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots"
)

# name: (the chain, its task space). The 4-joint arms are scored on position and heading, a
# square J whose singular set the search below can reach (a tall 6 × 4 J is rank-deficient
# only on a set of codimension 3).
ARMS = {
    "bravo7": (kin.bravo7, "full"),
    "uvms12": (kin.uvms12, "full"),
    "docking_arm": (kin.docking_arm, "full"),
    "bravo7_to_link_D": (lambda: robot.chain_from_urdf(kin.bravo7_urdf(), tip_link="link_D"), ("vx", "vy", "vz", "wz")),
    "alpha5": (lambda: load_arm("alpha5").chain, ("vx", "vy", "vz", "wz")),
    "panda": (lambda: robot.chain_from_urdf(str(ROBOTS / "panda_description/urdf/panda.urdf"), tip_link="panda_hand_tcp"),
              "full"),
}


@pytest.mark.parametrize("arm", list(ARMS))
def test_float32_indices_match_float64_singular_values_near_singularities(arm):
    factory, task = ARMS[arm]
    chain, rows = factory(), list(indices.task_rows(task))
    lo, hi = np.maximum(np.asarray(chain.lower), -3.0), np.minimum(np.asarray(chain.upper), 3.0)
    uniform = lo + np.random.default_rng(len(arm)).random((300, chain.n_joints)) * (hi - lo)
    q = np.concatenate([*indices.near_singular_poses(chain, 300, task, seed=len(arm)), uniform])
    sigma = np.linalg.svd(np.asarray(kin.jacobian(chain, q))[:, rows], compute_uv=False)
    w64, kci64 = sigma.prod(-1), sigma[:, -1] / sigma[:, 0]
    w_max = w64.max()
    if arm != "uvms12":  # the vehicle's six DOF alone keep its J at full rank
        # the set reaches them: a sixth or more of its poses 1000× nearer than the uniform ones
        assert np.mean(sigma[:300, -1] < 1e-3 * np.median(sigma[600:, -1])) > 1 / 6

    q32 = jnp.asarray(q, jnp.float32)
    J32 = kin.jacobian(chain, q32)
    for w32 in (indices.manipulability_of(chain, q32, task), indices.manipulability(J32, task)):
        assert np.abs(np.asarray(w32, np.float64) - w64).max() <= W_TOL * w_max
    for kci32 in (indices.kci_of(chain, q32, task), indices.kci(J32, task)):
        assert np.abs(np.asarray(kci32, np.float64) - kci64).max() <= KCI_TOL

    # The Gram form on the same float32 Jacobians misses both bounds on the arms with the
    # largest σ1 (a sample that tells the two forms apart, not an easy one).
    J32 = np.asarray(J32)[:, rows]
    G = J32 @ np.swapaxes(J32, -1, -2) if J32.shape[-2] <= J32.shape[-1] else np.swapaxes(J32, -1, -2) @ J32
    lam = np.linalg.eigvalsh(G.astype(np.float32)).astype(np.float64)
    gram_w, gram_kci = np.sqrt(np.clip(lam, 0, None)).prod(-1), np.sqrt(np.clip(lam[:, 0], 0, None) / lam[:, -1])
    if arm in ("bravo7", "panda"):
        assert np.abs(gram_w - w64).max() > W_TOL * w_max
        assert np.abs(gram_kci - kci64).max() > KCI_TOL
