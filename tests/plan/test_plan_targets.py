"""IK targets of every object and base, edge planning with all planners, and plan.json."""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml

from uvms_jax import hw, kin
from uvms_jax.plan import (
    PLANNERS,
    CollisionChecker,
    build_scene,
    node_contexts,
    pick_place_targets,
    plan_edge,
    plan_json,
    seed_ompl,
)

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
POSE_ATOL = 1e-6  # [m, rad-ish] float64 IK converges to 1e-8; FK round trip well within this

pytestmark = pytest.mark.slow  # one numerical-IK compile (~30 s on 2 cores)


@pytest.fixture(scope="module")
def setup():
    seed_ompl(3)
    scene = build_scene(yaml.safe_load(SCENARIO.read_text()))
    checker = CollisionChecker(scene)
    targets = pick_place_targets(scene, checker, jax.random.PRNGKey(0), n_seeds=48)
    return scene, checker, targets


def test_all_targets_reachable_and_valid(setup):
    scene, checker, targets = setup
    chain = kin.bravo7()
    assert sorted(targets) == sorted(scene.objects) + sorted(scene.bases)
    for node, tg in targets.items():
        for q, T in ((tg.q_pre, tg.T_world_pre), (tg.q_at, tg.T_world_at)):
            assert checker.in_limits(q)
            T_reached = scene.T_world_base @ np.asarray(kin.fk(chain, jnp.asarray(q)))
            np.testing.assert_allclose(T_reached, T, atol=POSE_ATOL)
        # The grasp/final pose puts the object where it belongs: tool = object · T_obj_tool.
        obj = node if node in scene.objects else scene.bases[node].fits[0]
        T_obj = tg.T_world_at @ scene.T_tool_obj_for(obj)
        ref = scene.T_world_object(node) if node in scene.objects else scene.T_world_placed(node, obj)
        np.testing.assert_allclose(T_obj[:3, 3], ref[:3, 3], atol=POSE_ATOL)
        np.testing.assert_allclose(T_obj[:3, 2], ref[:3, 2], atol=POSE_ATOL)
        ctx = node_contexts(scene, node)
        for key, q in (("arrive", tg.q_pre), ("leave", tg.q_pre), ("down", tg.q_at), ("up", tg.q_at)):
            checker.set_context(ctx[key])
            assert checker.is_valid(q), (node, key, checker.contacts(q))
        checker.set_context(ctx["down"])
        assert checker.path_is_valid(np.stack([tg.q_pre, tg.q_at]), 0.01)
        assert tg.manipulability > 0


@pytest.mark.parametrize("planner", PLANNERS)
def test_edges_planned_and_revalidated(setup, planner):
    scene, checker, targets = setup
    for src, dst in [(0, 1), (1, 5), (5, 4), (4, 8), (8, 9)]:
        e = plan_edge(scene, checker, targets, src, dst, planner, budget_s=5.0)
        assert e.success and e.revalidated, (planner, src, dst, e.check)
        m = e.metrics
        assert m.planning_time_s <= 5.0 and m.joint_movement > 0 and m.ee_distance > 0
        assert m.min_clearance >= 0.0
        assert (m.max_torque > 0) == (src in scene.objects)


def test_plan_json_passes_hw_dry_run(setup):
    scene, checker, targets = setup
    seq = [0, 3, 7, 9]
    edges = {(s, d): plan_edge(scene, checker, targets, s, d, "RRTConnect") for s, d in zip(seq[:-1], seq[1:])}
    obj = plan_json(scene, targets, edges, seq, checker=checker)
    plan = hw.parse_plan(obj)
    summary = hw.check_plan(plan)
    assert summary.n_gripper_steps == 3  # open, close at the cylinder; release on its base
    names = [s.name for s in plan.segments]
    assert names[0].startswith("0->3") and any(n.startswith("grasp") for n in names)
    with pytest.raises(ValueError, match="no successful plan"):
        plan_json(scene, targets, edges, [0, 1, 5, 9])
