"""Helpers of experiments/papers.py: the transcribed tables and the docking geometry."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from uvms_jax import kin

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def papers():
    spec = importlib.util.spec_from_file_location("papers", ROOT / "experiments" / "papers.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["papers"] = module  # dataclasses look their module up while the class is built
    spec.loader.exec_module(module)
    return module


def test_thesis_tables_are_transcribed_consistently(papers):
    """Σ K·N = C in every thesis table but 5.8 (the thesis's own inconsistency, theory §7);
    a mistyped K, N or C shows up here."""
    bad = {t for t, rows in papers.PAPER_T22.items() for alg, path, K, N, C, ms in rows
           if abs(float(np.dot(K, N)) - C) > 0.01}
    assert bad == {"5.8"}
    for rows in papers.PAPER_T22.values():
        for alg, path, K, N, C, ms in rows:
            nodes = [int(v) for v in path.split("-")]
            assert nodes[0] == 0 and nodes[-1] == 9 and sorted(set(nodes) - {0, 9}) == list(range(1, 9))
            assert math.isclose(sum(K), 1.0, abs_tol=1e-9)


def test_heading_and_distance(papers):
    # A pose at (−1, 0) facing +x looks straight at the centre; one at (0, −1) facing +x is 90° off.
    poses = np.array([[-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.0], [-1.0, -1.0, 0.2, math.pi / 4]])
    np.testing.assert_allclose(papers.heading_offset(poses), [0.0, 90.0, 0.0], atol=1e-9)
    # Docking point of the pose p_init itself with ψ = π/4: p_bp rotated and added (eq. 5).
    p = np.array([[-2.0, -2.0, 2.0, math.pi / 4]])
    d = np.array([-0.3 / math.sqrt(2), -0.3 / math.sqrt(2), -0.2])
    np.testing.assert_allclose(papers.distance_d(p), [np.linalg.norm(d)], rtol=1e-12)


def test_offset_chain_moves_the_tool_along_the_approach_axis(papers):
    arm = kin.docking_arm()
    q = np.array([[0.3, -0.4, 1.1, 0.2, 0.7, -0.5]], np.float32)
    T, T_off = np.asarray(kin.fk(arm, q))[0], np.asarray(kin.fk(papers.offset_chain(arm, 0.25), q))[0]
    np.testing.assert_allclose(T_off[:3, 3], T[:3, 3] + 0.25 * T[:3, 0], atol=1e-6)
    np.testing.assert_allclose(T_off[:3, :3], T[:3, :3], atol=1e-6)
