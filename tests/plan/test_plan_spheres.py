"""The compiled sphere checker: exact primitive distances, conservative against MuJoCo in
every context, motions accepted only where the MuJoCo re-check passes, and planning with it;
the smallest clearance of a path from sphere lower bounds plus a few MuJoCo calls equals
MuJoCo's clearance at every sample; the task graph's edge set is cached per scene."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from uvms_jax.plan import (CollisionChecker, Context, SphereChecker, build_scene, densify, plan_motion, seed_ompl,
                           task_edges)
from uvms_jax.plan._collision import BOUND_SLACK
from uvms_jax.plan._sphere_kernels import _box_distance, _hull_faces, _mesh_spheres, _segment_distance, coarse_to_fine
from uvms_jax.plan._tasks import _edge_set
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
GRID = 400  # dense parameter grid of the brute-force distance oracles
CONTEXTS = [Context(), Context(held=1), Context(held=3), Context(held=4), Context(ignore=(5, "dest_inclined"))]


@pytest.fixture(scope="module")
def raw():
    return yaml.safe_load(SCENARIO.read_text())


@pytest.fixture(scope="module")
def checkers(raw):
    reference = CollisionChecker(build_scene(BRAVO7, raw))
    return reference, SphereChecker(reference)


def test_segment_distance_matches_dense_sampling():
    rng = np.random.default_rng(0)
    s = np.linspace(0.0, 1.0, GRID)
    for _ in range(20):
        p1, q1, p2, q2 = rng.normal(size=(4, 3))
        if rng.random() < 0.3:
            q2 = p2 + 0.5 * (q1 - p1)  # parallel segments: the degenerate branch
        a = p1 + s[:, None] * (q1 - p1)
        b = p2 + s[:, None] * (q2 - p2)
        brute = np.min(np.linalg.norm(a[:, None] - b[None], axis=2))
        d = _segment_distance(p1, q1, p2, q2)
        # The grid's closest pair is at most one grid step (on each segment) from the true one.
        step = (np.linalg.norm(q1 - p1) + np.linalg.norm(q2 - p2)) / (GRID - 1)
        assert d <= brute + 1e-12 and d >= brute - step


def test_box_distance_matches_dense_sampling():
    """Outside: distance to a densely sampled box surface; inside: minus the depth to the nearest face."""
    rng = np.random.default_rng(1)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    centre, half = np.array([0.1, -0.2, 0.3]), np.array([0.05, 0.2, 0.1])
    box = np.vstack([[1.0, 0.0, 0.0], centre, (R * half).T])
    u = np.linspace(-1, 1, 61)
    faces = []
    for a in range(3):
        g = np.stack(np.meshgrid(u, u, indexing="ij"), -1).reshape(-1, 2)
        for sign in (-1.0, 1.0):
            local = np.insert(g, a, sign, axis=1)
            faces.append(centre + (local * half) @ R.T)
    surface = np.concatenate(faces)
    for _ in range(30):
        x = centre + R @ (rng.uniform(-2, 2, 3) * half)
        local = R.T @ (x - centre)
        d = _box_distance(x, box)
        if np.all(np.abs(local) <= half):
            assert d == pytest.approx(-np.min(half - np.abs(local)), abs=1e-12)
        else:
            brute = np.min(np.linalg.norm(surface - x, axis=1))
            assert d <= brute + 1e-12 and d >= brute - np.linalg.norm(half) * 2 / 60


def _hull_samples(vertices: np.ndarray, rng, n: int) -> np.ndarray:
    """Points of the convex hull of ``vertices``: uniform in its bounding box, kept inside, and
    on its surface (rays from an inner point to each face, so every face is sampled)."""
    faces = _hull_faces(vertices)
    lo, hi = vertices.min(0), vertices.max(0)
    x = rng.uniform(lo, hi, (n, 3))
    inside = x[np.max(x @ faces[:, :3].T + faces[:, 3], axis=1) <= 0]
    o = vertices.mean(0)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    with np.errstate(divide="ignore"):
        t = -(o @ faces[:, :3].T + faces[:, 3]) / (d @ faces[:, :3].T)  # (n, f) ray parameter to each plane
    surface = o + np.min(np.where(t > 0, t, np.inf), axis=1)[:, None] * d
    return np.concatenate([vertices, inside, surface])


def _circumscribed_cells(vertices: np.ndarray, cell: float) -> tuple[np.ndarray, float]:
    """The plain cover to beat: centres ``(n, 3)`` and the radius of the circumscribed spheres
    of the grid cells whose sphere reaches the hull."""
    faces = _hull_faces(vertices)
    lo, hi = vertices.min(0), vertices.max(0)
    n = np.maximum(1, np.ceil((hi - lo) / cell - 1e-9).astype(int))
    h = (hi - lo) / n
    c = np.stack(np.meshgrid(*[lo[i] + (np.arange(n[i]) + 0.5) * h[i] for i in range(3)], indexing="ij"), -1)
    c, r = c.reshape(-1, 3), np.linalg.norm(h) / 2
    return c[np.max(c @ faces[:, :3].T + faces[:, 3], axis=1) <= r], r


def test_mesh_spheres_hold_the_hull_and_bulge_less_than_cells():
    """Random convex meshes (a blob, a thin slab, a long rod): every sampled point of the hull
    (inside, on the surface, its vertices) lies in some sphere; no more spheres than the plain
    cover of circumscribed cell spheres, and less bulge out of the hull (radius plus the
    centre's largest face distance): at most its largest, below its mean, and a small fraction
    of it on the blob, whose spheres can centre deep inside."""
    rng = np.random.default_rng(4)
    cell = 0.03
    shapes = [rng.normal(size=(60, 3)) * [0.06, 0.04, 0.1], rng.uniform(-1, 1, (40, 3)) * [0.1, 0.08, 0.004],
              rng.uniform(-1, 1, (40, 3)) * [0.01, 0.012, 0.2]]
    for i, v in enumerate(shapes):
        c, r = _mesh_spheres(v, cell)
        x = _hull_samples(v, rng, 20_000)
        d = np.linalg.norm(x[:, None] - c[None], axis=2) - r
        assert np.all(np.min(d, axis=1) <= 1e-12), "a point of the hull outside every sphere"
        faces = _hull_faces(v)
        bulge = r + np.max(c @ faces[:, :3].T + faces[:, 3], axis=1)
        c0, r0 = _circumscribed_cells(v, cell)
        bulge0 = r0 + np.max(c0 @ faces[:, :3].T + faces[:, 3], axis=1)
        assert len(r) <= len(c0)
        assert np.max(bulge) <= np.max(bulge0) and np.mean(bulge) < np.mean(bulge0)
        if i == 0:
            assert np.mean(bulge) < 0.2 * np.mean(bulge0)


def test_coarse_to_fine_is_a_permutation_ending_first():
    for n in (1, 2, 7, 64, 100):
        order = coarse_to_fine(n)
        assert order[0] == n and sorted(order) == list(range(1, n + 1))


@pytest.mark.parametrize("context", CONTEXTS, ids=str)
def test_spheres_are_conservative(checkers, context):
    """A configuration the spheres accept has no MuJoCo pair nearer than the margin; and the
    spheres accept most of what MuJoCo accepts (else the checker would be useless)."""
    reference, fast = checkers
    rng = np.random.default_rng(2)
    Q = rng.uniform(reference.lower, reference.upper, (3000, 6))
    ok = fast.spheres_free(Q, context)
    mj = reference.is_valid_batch(Q, context)
    assert not np.any(ok & ~mj), "the spheres accepted a configuration MuJoCo rejects"
    assert ok.sum() >= 0.8 * mj.sum()


@pytest.mark.parametrize("context", CONTEXTS[:3], ids=str)
def test_accepted_motions_pass_the_mujoco_recheck(checkers, context):
    reference, fast = checkers
    rng = np.random.default_rng(3)
    Q = rng.uniform(reference.lower, reference.upper, (2000, 6))
    starts = Q[reference.is_valid_batch(Q, context)][:60]
    accepted = 0
    for q0, q1 in zip(starts[:-1], starts[1:]):
        q1 = q0 + 0.4 * (q1 - q0)
        ok = fast.motion_is_valid(q0, q1, context, 0.01)
        ref = reference.path_is_valid(np.stack([q0, q1]), context, 0.01)
        assert ok == ref  # spheres first, MuJoCo on each rejected sample: MuJoCo's answer
        accepted += ok
    assert 0 < accepted < len(starts) - 1  # both outcomes were exercised


def test_planning_with_spheres(checkers, raw):
    """Goals the straight joint path cannot reach (it collides): every planner finds a path
    with the sphere checker, and the path passes MuJoCo's re-check at a finer step."""
    seed_ompl(0)
    reference, fast = checkers
    ctx = Context()
    q0 = np.asarray(raw["start_q"])
    rng = np.random.default_rng(4)
    Q = rng.uniform(reference.lower, reference.upper, (400, 6))
    goals = [q for q in Q if reference.is_valid(q, ctx) and not reference.path_is_valid(np.stack([q0, q]), ctx, 0.01)][:2]
    assert len(goals) == 2
    n0 = fast.n_motions
    for planner in ("RRTConnect", "BKPIECE1", "PRM"):
        for q1 in goals:
            r = plan_motion(reference, q0, q1, ctx, planner, budget_s=5.0, fast=fast)
            assert r.success and reference.path_is_valid(r.path, ctx, 0.005, margin=0.0)
    assert fast.n_motions > n0


def test_fast_must_wrap_the_given_checker(checkers, raw):
    reference, fast = checkers
    other = CollisionChecker(build_scene(BRAVO7, raw))
    q = np.asarray(raw["start_q"])
    with pytest.raises(ValueError, match="SphereChecker built on the given checker"):
        plan_motion(other, q, q + 0.1, Context(), fast=fast)


@pytest.mark.parametrize("context", CONTEXTS, ids=str)
def test_bounds_are_below_mujoco(checkers, context):
    """Where a bound is non-negative (no sphere inside the scene) MuJoCo's clearance is not
    below it by more than its tolerance; and the bounds are close enough to prune."""
    reference, fast = checkers
    Q = np.random.default_rng(5).uniform(reference.lower, reference.upper, (1500, 6))
    lb = fast.clearance_lower_bounds(Q, context)
    mj = reference.clearance_batch(Q, context)
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
    rng = np.random.default_rng(6)
    Q = rng.uniform(reference.lower, reference.upper, (600, 6))
    Q = Q[reference.is_valid_batch(Q, context)]
    penetrating = 0
    for q0, q1 in zip(Q[:-1:2][:40], Q[1::2][:40]):
        dense = densify(np.stack([q0, q0 + 0.5 * (q1 - q0)]), 0.05)
        brute = float(np.min(reference.clearance_batch(dense, context)))
        penetrating += brute < 0
        assert fast.min_clearance(dense, context) == brute
        assert reference.min_clearance(dense, context) == brute
    assert penetrating > 0  # negative bounds (never trusted to skip) were exercised


def test_min_clearance_checks_its_input(checkers, raw):
    reference, _ = checkers
    q = np.asarray(raw["start_q"], dtype=float)[None]
    with pytest.raises(ValueError, match="lower_bounds must have shape"):
        reference.min_clearance(q, Context(), np.zeros(2))
    with pytest.raises(ValueError, match="at least one row"):
        reference.min_clearance(np.zeros((0, 6)), Context())
    # A bound above the truth would be wrong; one at -inf only costs MuJoCo calls.
    assert reference.min_clearance(q, Context(), np.array([-np.inf])) == reference.clearance(q[0], Context())


def test_answers_do_not_depend_on_earlier_contexts(checkers):
    """Every query takes its context: interleaving queries in other contexts (equal copies
    included) and an OMPL validator bound to one context give the answers of queries made in
    one context alone; a non-Context is refused."""
    reference, fast = checkers
    rng = np.random.default_rng(7)
    Q = rng.uniform(reference.lower, reference.upper, (300, 6))
    alone = {c: (reference.is_valid_batch(Q, c), fast.spheres_free(Q, c), reference.clearance_batch(Q[:50], c))
             for c in CONTEXTS}
    validators = {c: reference.state_validator(6, c) for c in CONTEXTS}
    for i, q in enumerate(Q):
        for c in CONTEXTS[::-1] if i % 2 else CONTEXTS:
            copy = Context(c.held, tuple(c.ignore))  # equal, not the same object
            assert reference.is_valid(q, c) == alone[c][0][i]
            assert validators[c](q) == alone[c][0][i]  # Q is inside the bounds, as OMPL's states
            assert fast.spheres_free(q[None], copy)[0] == alone[c][1][i]
            if i < 50:
                assert reference.clearance(q, copy) == alone[c][2][i]
    q0 = Q[np.all([alone[c][0] for c in CONTEXTS], axis=0)][0]  # valid in every context
    ends = [q0 + 0.4 * (q - q0) for q in Q[:20]]
    ref = {c: [reference.path_is_valid(np.stack([q0, q]), c, 0.01) for q in ends] for c in CONTEXTS}
    for j, q in enumerate(ends):
        for c in CONTEXTS[::-1] if j % 2 else CONTEXTS:
            assert fast.motion_is_valid(q0, q, c, 0.01) == ref[c][j]
    assert 0 < sum(map(sum, ref.values())) < len(CONTEXTS) * len(ends)  # both outcomes exercised
    with pytest.raises(TypeError, match="plan.Context"):
        reference.is_valid(q0, 0.0)
    assert not hasattr(reference, "set_context") and not hasattr(fast, "set_context")


def test_edge_set_is_the_task_graph_per_scene(raw):
    a, b = build_scene(BRAVO7, raw), build_scene(BRAVO7, raw)
    assert _edge_set(a) == frozenset(task_edges(a)) and _edge_set(a) is _edge_set(a)
    assert _edge_set(b) == _edge_set(a) and _edge_set(b) is not _edge_set(a)
