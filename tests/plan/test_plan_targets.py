"""IK targets of every object and base, edge planning with all planners, the planning stage,
and plan.json."""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml

from uvms_jax import hw, kin, planfile, sched
from uvms_jax.plan import (
    PLANNERS,
    CollisionChecker,
    IkSettings,
    PlanJsonSettings,
    PlanSettings,
    build_scene,
    node_contexts,
    pick_place_targets,
    plan_edge,
    plan_for_schedule,
    plan_from_edges,
    plan_task_graph,
    seed_ompl,
    task_edges,
    write_plan,
    write_task_graph,
)
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
POSE_ATOL = 1e-6  # [m, rad-ish] float64 IK converges to 1e-8; FK round trip well within this

N_SEEDS = 48  # IK seeds of every test here: one numerical-IK compile serves them all
pytestmark = pytest.mark.slow  # one numerical-IK compile (~30 s on 2 cores)


@pytest.fixture(scope="module")
def setup():
    seed_ompl(3)
    scene = build_scene(BRAVO7, yaml.safe_load(SCENARIO.read_text()))
    checker = CollisionChecker(scene)
    targets = pick_place_targets(jax.random.PRNGKey(0), scene, checker, IkSettings(n_seeds=N_SEEDS))
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
            assert checker.is_valid(q, ctx[key]), (node, key, checker.contacts(q, ctx[key]))
        assert checker.path_is_valid(np.stack([tg.q_pre, tg.q_at]), ctx["down"], 0.01)
        assert tg.manipulability > 0


@pytest.mark.parametrize("planner", PLANNERS)
def test_edges_planned_and_revalidated(setup, planner):
    scene, checker, targets = setup
    for src, dst in [(0, 1), (1, 5), (5, 4), (4, 8), (8, 9)]:
        e = plan_edge(scene, checker, targets, src, dst, planner, PlanSettings(budget_s=5.0))
        assert e.success and e.revalidated, (planner, src, dst, e.check)
        m = e.metrics
        assert m.planning_time <= 5.0 and m.joint_movement > 0 and m.ee_distance > 0
        assert m.security >= 0.0
        assert m.max_torque > 0  # the arm's own weight and buoyancy load every move


def test_plan_passes_hw_dry_run(setup):
    scene, checker, targets = setup
    seq = [0, 3, 7, 9]
    edges = {(s, d): plan_edge(scene, checker, targets, s, d, "RRTConnect") for s, d in zip(seq[:-1], seq[1:])}
    plan = plan_from_edges(scene, targets, edges, seq, checker=checker)
    assert planfile.parse_plan(planfile.plan_to_dict(plan)) == plan
    summary = hw.check_plan(plan, BRAVO7)
    assert summary.n_gripper_steps == 3  # open, close at the cylinder; release on its base
    names = [s.name for s in plan.segments]
    assert names[0].startswith("0->3") and any(n.startswith("grasp") for n in names)
    with pytest.raises(ValueError, match="no successful plan"):
        plan_from_edges(scene, targets, edges, [0, 1, 5, 9])


def test_stage_run_and_files(setup, tmp_path):
    """plan_task_graph → write_task_graph, plan_for_schedule → write_plan: every edge planned,
    the cost matrix is sched's formula over the metric tensor, the files are complete."""
    scene = setup[0]
    settings = PlanSettings(planners=("RRTConnect",), budget_s=2.0, ik=IkSettings(n_seeds=N_SEEDS),
                            plan_json=PlanJsonSettings(sequence=(0, 3, 7, 9)))
    tp = plan_task_graph(jax.random.PRNGKey(0), scene, settings, progress=False)
    edges = task_edges(scene)
    assert [(r.src, r.dst) for r in tp.by_planner["RRTConnect"]] == edges
    s = tp.summary["RRTConnect"]
    assert s.edges == len(edges) and s.success == len(edges)
    m = tp.metrics["RRTConnect"]
    np.testing.assert_array_equal(tp.costs["RRTConnect"],
                                  sched.cost_matrix(sched.normalise_metrics(m), settings.weight_vector()))
    write_task_graph(tp, tmp_path)
    for name in ("targets.json", "edges.csv", "metrics_RRTConnect.json", "cost_RRTConnect.csv",
                 "ee_paths_RRTConnect.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    with open(tmp_path / "edges.csv") as f:
        assert sum(1 for _ in f) == len(edges) + 1
    plan = plan_for_schedule(tp, "RRTConnect", settings.plan_json.sequence, settings)
    write_plan(plan, tmp_path)
    assert planfile.load_plan(tmp_path / "plan.json") == plan
    assert plan.base_rpy == tuple(scene.spec.mount_rpy)  # the simulated run gets the planned gravity
    assert (tmp_path / "joints.png").stat().st_size > 0
    with pytest.raises(ValueError, match="was not run"):
        plan_for_schedule(tp, "PRM", settings.plan_json.sequence, settings)
