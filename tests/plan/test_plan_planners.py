"""Any OMPL geometric planner by name, its parameters from config, clear errors otherwise."""

from pathlib import Path

import numpy as np
import pytest
import yaml
from ompl import base as ob

from uvms_jax.plan import (
    CollisionChecker,
    Context,
    PlanSettings,
    SphereChecker,
    build_scene,
    ompl_planners,
    plan_motion,
    planner_parameters,
    seed_ompl,
)
from uvms_jax.plan._planners import make_planner
from uvms_jax.settings import from_mapping
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"


def _si():
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0.0)
    bounds.setHigh(1.0)
    space.setBounds(bounds)
    return ob.SpaceInformation(space)


def test_every_ompl_planner_by_name():
    names = ompl_planners()
    assert {"RRTConnect", "BKPIECE1", "PRM", "RRTstar", "BITstar"} <= set(names)
    for name in names:
        planner = make_planner(name, _si())
        assert planner.getName() in (name, "k" + name)  # BITstar names itself kBITstar


def test_parameters_reach_the_planner():
    """The value set from config is what OMPL's getter reports."""
    si = _si()
    assert "range" in planner_parameters("RRTConnect")
    assert make_planner("RRTConnect", si, {"range": 0.37}).getRange() == pytest.approx(0.37)
    assert make_planner("RRT", si, {"goal_bias": 0.2}).getGoalBias() == pytest.approx(0.2)
    assert make_planner("PRM", si, {"max_nearest_neighbors": 7}) is not None
    assert planner_parameters("FMT")["extended_fmt"] is bool


@pytest.mark.parametrize("name, params, match", [
    ("RRT*", {}, r"unknown planner 'RRT\*'.*RRTConnect.*RRTstar"),
    ("RRTConnect", {"goal_bias": 0.1}, r"RRTConnect has no parameter 'goal_bias'.*range: float"),
    ("RRTConnect", {"range": "far"}, r"'range' must be float"),
    ("PRM", {"max_nearest_neighbors": 2.5}, r"'max_nearest_neighbors' must be int"),
    ("RRT", {"intermediate_states": 1}, r"'intermediate_states' must be bool"),
])
def test_bad_planner_or_parameter_is_named(name, params, match):
    with pytest.raises(ValueError, match=match):
        make_planner(name, _si(), params)


def test_settings_take_planners_and_parameters_from_config():
    s = from_mapping(PlanSettings, {"planners": ["RRTstar", "PRM"], "planner_params": {"RRTstar": {"range": 0.5}}})
    assert s.planners == ("RRTstar", "PRM") and s.planner_params == {"RRTstar": {"range": 0.5}}
    with pytest.raises(ValueError, match="no parameter 'rang'"):
        PlanSettings(planner_params={"RRTConnect": {"rang": 1.0}})
    with pytest.raises(ValueError, match="not in planners"):
        PlanSettings(planners=("PRM",), planner_params={"RRTConnect": {"range": 1.0}})
    with pytest.raises(ValueError, match="unknown planners"):
        PlanSettings(planners=("RRTConnect", "AStar"))


@pytest.mark.parametrize("name, params", [("RRTstar", {"range": 1.0}), ("RRT", {"goal_bias": 0.1}),
                                          ("KPIECE1", {}), ("BKPIECE1", {}), ("LBKPIECE1", {"range": 1.0})])
def test_other_planners_plan_with_the_sphere_checker(name, params):
    """Motions accepted by the sphere checker are sampled like the re-check, so the first
    attempt's path passes it (OMPL's own state-by-state checks at the planner's coarser step
    and with a margin usually do, but not by construction). The KPIECE family too, although
    the bindings give it no partial motions."""
    seed_ompl(0)
    raw = yaml.safe_load(SCENARIO.read_text())
    reference = CollisionChecker(build_scene(BRAVO7, raw))
    fast = SphereChecker(reference)
    q0 = np.asarray(raw["start_q"])
    q1 = q0 + np.array([0.8, -0.3, 0.2, 0.0, 0.3, 0.0])
    ctx = Context()
    assert reference.is_valid(q1, ctx)
    r = plan_motion(reference, q0, q1, ctx, name, budget_s=0.5, fast=fast, params=params)
    assert r.success and r.attempts == 1 and reference.path_is_valid(r.path, ctx, 0.005, margin=0.0)
