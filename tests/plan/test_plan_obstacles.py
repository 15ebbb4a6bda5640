"""Obstacles from the scenario config: every shape in the MuJoCo scene, checked by both checkers."""

import copy
from pathlib import Path

import mujoco
import numpy as np
import pytest
import yaml
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf
from scipy.spatial import ConvexHull

from uvms_jax.plan import CollisionChecker, Context, SphereChecker, build_scene
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

CONFIGS = Path(__file__).parents[2] / "configs"
SCENARIO = CONFIGS / "scenario" / "thesis_cage.yaml"


@pytest.fixture(scope="module")
def raw():
    return yaml.safe_load(SCENARIO.read_text())


def _scene_with(raw, obstacles):
    spec = copy.deepcopy(raw)
    spec["obstacles"] = obstacles
    return build_scene(BRAVO7, spec)


def _write_box_obj(path: Path, edge: float) -> None:
    """A Wavefront OBJ of a cube: its vertices and its hull's triangles."""
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * edge / 2
    lines = [f"v {a} {b} {c}" for a, b, c in v] + [f"f {i + 1} {j + 1} {k + 1}" for i, j, k in ConvexHull(v).simplices]
    path.write_text("\n".join(lines) + "\n")


def _tool(scene, q):
    d = mujoco.MjData(scene.model)
    d.qpos[:] = q
    mujoco.mj_kinematics(scene.model, d)
    return d.site_xpos[0].copy()


@pytest.mark.parametrize("shape, dims", [
    ("box", {"size": [0.1, 0.1, 0.1]}), ("cylinder", {"radius": 0.05, "height": 0.1}),
    ("sphere", {"radius": 0.05}), ("capsule", {"radius": 0.04, "length": 0.1}), ("mesh", None),
])
def test_each_shape_blocks_the_arm(raw, tmp_path, shape, dims):
    """An obstacle of every shape centred on the tool point at the start makes the start
    invalid for MuJoCo and for the sphere checker; moved away, the start is free again."""
    q = np.asarray(raw["start_q"])
    p = _tool(build_scene(BRAVO7, raw), q)
    if dims is None:
        file = tmp_path / "block.obj"
        _write_box_obj(file, 0.1)
        dims = {"file": str(file), "scale": 1.0}
    for where, blocked in ((p, True), (p + np.array([0.0, 0.0, -0.25]), False)):
        scene = _scene_with(raw, [{"name": "thing", "shape": shape, "pos": where.tolist(), **dims}])
        assert "thing" in scene.obstacle_geoms
        reference = CollisionChecker(scene)
        fast = SphereChecker(reference)
        assert reference.is_valid(q, Context()) is not blocked
        if blocked:
            assert not fast.spheres_free(q[None], Context())[0]  # conservative
        assert reference.is_valid(q, Context(ignore=("thing",)))


def test_cylinder_obstacle_contains_the_cylinder(raw):
    """The prism standing for a cylinder circumscribes it: its faces are at least r away."""
    scene = _scene_with(raw, [{"name": "pillar", "shape": "cylinder", "radius": 0.05, "height": 0.2, "pos": [0.7, 0, 0.5]}])
    o = scene.spec.obstacles[0]
    v = o.hull_vertices()
    assert np.min(np.linalg.norm(v[:, :2], axis=1)) >= 0.05
    # The inscribed radius of the polygon (mid-edge distance) is exactly r.
    mid = (v[0, :2] + v[1, :2]) / 2
    assert np.linalg.norm(mid) == pytest.approx(0.05, abs=1e-12)


@pytest.mark.parametrize("obstacle, match", [
    ({"name": "x", "shape": "cone", "pos": [0, 0, 0]}, r"obstacles\[0\].shape: expected one of \['box', .*got 'cone'"),
    ({"name": "x", "shape": "sphere", "pos": [0, 0, 0]}, r"obstacles\[0\]: obstacle shape 'sphere' takes radius; missing radius"),
    ({"name": "x", "shape": "sphere", "radius": -1.0, "pos": [0, 0, 0]}, r"obstacles\[0\].radius: expected a value > 0"),
    ({"name": "x", "shape": "box", "size": [1, 1], "pos": [0, 0, 0]}, r"obstacles\[0\].size: expected 3 values, got 2"),
    ({"name": "x", "shape": "sphere", "radius": 0.1, "height": 1.0, "pos": [0, 0, 0]}, "takes radius; not height"),
    ({"name": "x", "shape": "mesh", "file": "/nonexistent.stl", "pos": [0, 0, 0]}, "file: no such file"),
    ({"name": "x", "shape": "sphere", "radius": 0.1, "pos": [0, float("nan"), 0]}, "expected a finite number, got nan"),
    ({"name": "mount", "shape": "sphere", "radius": 0.1, "pos": [0, 0, 0]}, "names must be unique"),
    ({"name": "start_left", "shape": "sphere", "radius": 0.1, "pos": [0, 0, 0]}, "names must be unique"),
])
def test_bad_obstacle_is_named(raw, obstacle, match):
    with pytest.raises(ValueError, match=match):
        _scene_with(raw, [obstacle])


def test_preset_with_obstacles_composes(raw):
    """configs/scenario/cage_obstacles.yaml = the thesis cage + one obstacle of each primitive;
    the start configuration stays free."""
    with initialize_config_dir(config_dir=str(CONFIGS), version_base="1.3"):
        cfg = compose(config_name="plan", overrides=["scenario=cage_obstacles"])
    spec = OmegaConf.to_container(cfg.scenario, resolve=True)
    scene = build_scene(BRAVO7, spec)
    assert {o.shape for o in scene.spec.obstacles} == {"box", "cylinder", "sphere", "capsule"}
    assert scene.spec.tables == build_scene(BRAVO7, raw).spec.tables
    assert CollisionChecker(scene).is_valid(np.asarray(spec["start_q"]), Context())
