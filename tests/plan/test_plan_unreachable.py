"""An arm that cannot do the task says which target, why and by how much, at which base pose:
out of reach, or in collision."""

import re
from pathlib import Path

import jax
import numpy as np
import pytest
import yaml

from uvms_jax import robot
from uvms_jax.plan import CollisionChecker, IkSettings, build_scene, pick_place_targets

SCENARIO = yaml.safe_load((Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml").read_text())
IK = IkSettings(n_seeds=16, iterations=60)


def _targets(arm: robot.Robot, start_q=None):
    scene = build_scene(arm, {**SCENARIO, "start_q": start_q})
    return scene, lambda: pick_place_targets(jax.random.key(0), scene, CollisionChecker(scene), IK)


def test_out_of_reach_says_by_how_much():
    scene, solve = _targets(robot.load_arm("alpha5"))  # 0.4 m of arm under the cage's 1 m ceiling
    with pytest.raises(ValueError, match=r"node 1 \(cube1\): out of reach") as err:
        solve()
    found = [float(x) for x in re.findall(r"is ([0-9.]+) m from the arm's base, ([0-9.]+) m beyond", str(err.value))[0]]
    cube = scene.T_world_object(1)
    top = cube[:3, 3] + cube[:3, 2] * (scene.objects[1].height / 2 + scene.spec.grasp_standoff)
    assert found[0] == pytest.approx(np.linalg.norm(top - scene.T_world_base[:3, 3]), abs=1e-3)
    assert found[1] == pytest.approx(found[0] - scene.robot.max_reach, abs=2e-3)
    assert f"base at {np.round(scene.T_world_base[:3, 3], 3).tolist()} m" in str(err.value)


def test_collision_names_the_contact():
    fat = robot.robot_from_config({"card": "bravo7", "link_radius": 0.12})  # links that cannot pass the tables
    _, solve = _targets(fat, SCENARIO["start_q"])
    with pytest.raises(ValueError, match=r"node \d \(\w+\): in collision: every IK solution collides, e\.g\. geom_\w+ "
                                         r"against \S+ \(\d+ mm deep\)"):
        solve()
