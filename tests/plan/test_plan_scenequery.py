"""The pick-and-place task graph on the query path (PlanSettings.checker = "query"): the thesis
cage as a world in the arm's base frame, the held object and the card's jaws in the sphere model
and in MuJoCo's, every edge planned and re-checked. The oracle throughout is the scene's own
MuJoCo CollisionChecker (a model built from the scenario, independent of the world's obstacles)."""

from pathlib import Path

import jax
import numpy as np
import pytest
import yaml

from uvms_jax.plan import (CollisionChecker, Context, IkSettings, PlanSettings, build_scene, densify,
                           edge_endpoints, plan_query, plan_scene_query, plan_task_graph, scene_checker, scene_world,
                           task_edges)
from uvms_jax.plan import _vector_kernels as K
from uvms_jax.plan._worlds import obstacle_rows
from uvms_jax.robot import load_arm

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
RESOLUTION = 0.01  # [rad] the re-check's joint step (PlanSettings.recheck_resolution)
N_STATES = 3000  # random states per context: enough for jaw-only and held-object-only contacts
BOX_ATOL = 1e-6  # [m] the scene's meshes hold float32 vertices
N_SEEDS = 48  # IK seeds, as the other task-graph tests (one numerical-IK compile serves them all)


@pytest.fixture(scope="module")
def scene():
    return build_scene(load_arm("bravo7"), yaml.safe_load(SCENARIO.read_text()))


@pytest.fixture(scope="module")
def oracle(scene):
    return CollisionChecker(scene, margin=0.005)


def _states(scene, n=N_STATES, seed=0):
    return np.random.default_rng(seed).uniform(scene.robot.lower, scene.robot.upper, (n, scene.robot.n_joints))


def _corners(T, size) -> np.ndarray:
    """``(8, 3)`` the corners of a box of full edges ``size`` at pose ``T``, in a fixed order."""
    local = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) * np.asarray(size) / 2
    world = local @ T[:3, :3].T + T[:3, 3]
    return world[np.lexsort(np.round(world, 4).T)]


def test_world_is_the_scenes_geometry_in_the_base_frame(scene):
    """A table is the scenario's box, in the base frame; the ceiling's half-space is a box whose
    face is the ceiling's plane wherever the arm reaches."""
    spec = scene.spec
    world = scene_world(scene, Context())
    by_name = {o.name: o for o in world.obstacles}
    table = next(t for t in spec.tables if t.name == "start_left")
    box = by_name["start_left"]
    T = scene.T_base_world @ table.T_world_box
    np.testing.assert_allclose(box.T_world[:3, 3], T[:3, 3], atol=BOX_ATOL)
    # The same box whatever the order of its axes: its corners.
    np.testing.assert_allclose(_corners(box.T_world, box.dims), _corners(T, table.size), atol=BOX_ATOL)
    rows, planes = obstacle_rows([by_name["ceiling"]])
    height = spec.cage_size[2]
    for p_world in np.random.default_rng(1).uniform([-0.9, -0.9, 0.3], [0.9, 0.9, 1.2], (200, 3)):
        p = scene.T_base_world[:3, :3] @ p_world + scene.T_base_world[:3, 3]
        assert K.sphere_obstacle_distance(*p, rows[0], planes) == pytest.approx(height - p_world[2], abs=BOX_ATOL)
    held = scene_world(scene, Context(held=1, ignore=(5,)))
    assert {"n1:cube1", "n5:base_cube1"}.isdisjoint(o.name for o in held.obstacles)
    with pytest.raises(ValueError, match="unknown held object"):
        scene_world(scene, Context(held=42))


@pytest.mark.parametrize("ctx", [Context(), Context(held=1), Context(held=3)])
def test_query_checker_agrees_with_the_scene_state_by_state(scene, oracle, ctx):
    Q = _states(scene)
    np.testing.assert_array_equal(scene_checker(scene, ctx, oracle.margin).states_free(Q),
                                  oracle.is_valid_batch(Q, ctx))


def test_card_jaws_are_covered(scene):
    """The Bravo 7's card gives it a gripper and its description no fingers: no state where
    MuJoCo finds a jaw in contact is FREE for the spheres alone, jaw-only contacts included."""
    zero = CollisionChecker(scene, margin=0.0)
    ctx = Context()
    Q = _states(scene, seed=2)
    status = scene_checker(scene, ctx, 0.0).states_status(Q)
    jaw_contact, jaw_only = [], []
    for i, q in enumerate(Q):
        pairs = {(a, b) for a, b, d in zero.contacts(q, ctx) if d < 0}
        jaws = {p for p in pairs if any(name.startswith("geom_jaw_") for name in p)}
        if jaws:
            jaw_contact.append(i)
            if jaws == pairs:
                jaw_only.append(i)
    assert len(jaw_only) > 10  # the jaws alone decide some states
    assert not np.any(status[jaw_contact] == K.FREE)


def test_held_object_refuses_a_motion_that_passes_without_it(scene, oracle):
    """A straight motion the scene passes with empty jaws but not with the cube in them: the
    query path passes it without the cube and refuses it with it."""
    empty, held = Context(), Context(held=1)
    Q = _states(scene, seed=3)
    bad = Q[oracle.is_valid_batch(Q, empty, margin=0.0) & ~oracle.is_valid_batch(Q, held, margin=0.0)]
    rng = np.random.default_rng(4)
    found = None
    for q1 in bad:
        for q0 in np.clip(q1 + rng.uniform(-0.4, 0.4, (20, len(q1))), scene.robot.lower, scene.robot.upper):
            path = np.stack([q0, q1])
            if oracle.is_valid(q0, held, margin=0.0) and oracle.path_is_valid(path, empty, RESOLUTION, margin=0.0):
                found = path
                break
        if found is not None:
            break
    assert found is not None
    q0, q1 = found
    assert not oracle.path_is_valid(found, held, RESOLUTION, margin=0.0)
    assert scene_checker(scene, empty, 0.0).motion_free(q0, q1, RESOLUTION)
    with_cube = scene_checker(scene, held, 0.0)
    assert not with_cube.motion_free(q0, q1, RESOLUTION)
    assert plan_query(scene.robot, with_cube.world, q0, q1, opening=scene.spec.jaws_open, checker=with_cube).reason \
        == "goal in collision"
    with pytest.raises(ValueError, match="goal .* is invalid"):
        plan_scene_query(scene, oracle, q0, q1, held, "RRTConnect", PlanSettings(checker="query"))


@pytest.mark.slow  # one numerical-IK compile (~30 s on 2 cores)
def test_thesis_cage_plans_every_edge_on_the_query_path(scene):
    settings = PlanSettings(checker="query", planners=("RRTConnect",), ik=IkSettings(n_seeds=N_SEEDS))
    tp = plan_task_graph(jax.random.PRNGKey(0), scene, settings, progress=False)
    results = tp.by_planner["RRTConnect"]
    assert [(r.src, r.dst) for r in results] == task_edges(scene) and len(results) == 34
    reference = CollisionChecker(scene, margin=0.0)  # a fresh copy of the scene's MuJoCo model
    for r in results:
        assert r.success and r.revalidated, (r.src, r.dst)
        q0, q1, ctx = edge_endpoints(scene, tp.targets, r.src, r.dst)
        np.testing.assert_array_equal(r.plan.path[[0, -1]], np.stack([q0, q1]))
        assert reference.is_valid_batch(densify(r.plan.path, RESOLUTION), ctx).all(), (r.src, r.dst)
