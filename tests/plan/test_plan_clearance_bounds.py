"""The smallest clearance of a path from sphere lower bounds plus a few MuJoCo calls equals
MuJoCo's clearance at every sample; the task graph's edge set is cached per scene."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from uvms_jax.plan import CollisionChecker, Context, SphereChecker, build_scene, densify, task_edges
from uvms_jax.plan._collision import BOUND_SLACK
from uvms_jax.plan._tasks import _edge_set

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
CONTEXTS = [Context(), Context(held=1), Context(held=3), Context(held=4), Context(ignore=(5, "dest_inclined"))]


@pytest.fixture(scope="module")
def raw():
    return yaml.safe_load(SCENARIO.read_text())


@pytest.fixture(scope="module")
def checkers(raw):
    reference = CollisionChecker(build_scene(raw))
    return reference, SphereChecker(reference)


@pytest.mark.parametrize("context", CONTEXTS, ids=str)
def test_bounds_are_below_mujoco(checkers, context):
    """Where a bound is non-negative (no sphere inside the scene) MuJoCo's clearance is not
    below it by more than its tolerance; and the bounds are close enough to prune."""
    reference, fast = checkers
    fast.set_context(context)
    Q = np.random.default_rng(5).uniform(reference.lower, reference.upper, (1500, 6))
    lb = fast.clearance_lower_bounds(Q)
    mj = reference.clearance_batch(Q)
    assert lb.shape == (len(Q),) and np.all(lb <= reference.clearance_max)
    free = lb >= 0
    assert free.sum() > 100
    assert np.all(lb[free] <= mj[free] + BOUND_SLACK / 10)
    assert np.median(mj[free] - lb[free]) < 0.03  # the spheres hug the geoms within a few cm


@pytest.mark.parametrize("context", CONTEXTS, ids=str)
def test_min_clearance_equals_mujoco_at_every_sample(checkers, context):
    """Valid start, random straight motions (some through obstacles): the same minimum as
    MuJoCo's clearance at every sample, to the bit."""
    reference, fast = checkers
    fast.set_context(context)
    rng = np.random.default_rng(6)
    Q = rng.uniform(reference.lower, reference.upper, (600, 6))
    Q = Q[reference.is_valid_batch(Q)]
    penetrating = 0
    for q0, q1 in zip(Q[:-1:2][:40], Q[1::2][:40]):
        dense = densify(np.stack([q0, q0 + 0.5 * (q1 - q0)]), 0.05)
        brute = float(np.min(reference.clearance_batch(dense)))
        penetrating += brute < 0
        assert fast.min_clearance(dense) == brute
        assert reference.min_clearance(dense) == brute
    assert penetrating > 0  # negative bounds (never trusted to skip) were exercised


def test_min_clearance_checks_its_input(checkers, raw):
    reference, _ = checkers
    q = np.asarray(raw["start_q"], dtype=float)[None]
    with pytest.raises(ValueError, match="lower_bounds must have shape"):
        reference.min_clearance(q, np.zeros(2))
    with pytest.raises(ValueError, match="at least one row"):
        reference.min_clearance(np.zeros((0, 6)))
    # A bound above the truth would be wrong; one at -inf only costs MuJoCo calls.
    assert reference.min_clearance(q, np.array([-np.inf])) == reference.clearance(q[0])


def test_edge_set_is_the_task_graph_per_scene(raw):
    a, b = build_scene(raw), build_scene(raw)
    assert _edge_set(a) == frozenset(task_edges(a)) and _edge_set(a) is _edge_set(a)
    assert _edge_set(b) == _edge_set(a) and _edge_set(b) is not _edge_set(a)
