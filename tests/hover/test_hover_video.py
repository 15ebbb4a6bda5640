"""The hovering run's video (uvms_jax.hover.write_hover_video, HoverFilm): the hw video's scene
and camera, the hull's outline, the paths, the current's arrow and the overlay.

Oracles: the box's edge lengths and the current's velocity set here by hand; the gates counted
by hand from the plan (test_hover_executor); the hw video's own renderer
(uvms_jax.video.render_frame on the planning scene from uvms_jax.plan.scene_camera) for the
scene's pixels; and the frame count of a run's length at a frame rate.

Rendering needs an offscreen GL context picked when MuJoCo is first imported, so it runs in a
child process with ``MUJOCO_GL=egl`` (skipped, saying why, where none can be made); the scene
geoms and the overlay need no GL and are checked here.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import mujoco
import numpy as np
import pytest
import yaml

from uvms_jax.hover import HULL_GEOM, CurrentSettings, HoverFilm, VehicleSettings, execute_plan_hovering
from uvms_jax.hover._video import ARROW_S, CURRENT_RGBA, OUTLINE_RGBA
from uvms_jax.plan import build_scene

from test_hover_executor import PLAN_GATES
from test_hover_plan import ARM, POSE, _plan

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
CURRENT = (0.4, 0.0, 0.0)  # [m/s]
GEOM_TOL = 1e-6  # [m] mjvGeom holds sizes and positions in float32 (~1e-7 relative at 1 m)
NO_GL_EXIT = 3
SIZE = (160, 120)  # tiny frames: the checks need the scene's layout, not its detail
FPS = 2.0
SAME_LEVEL = 12  # a pixel is the hw frame's if every channel is within this [0-255]
SCENE_SHARE = 0.5  # at least this share of the frames' lower halves (floor, tables) is the hw frame's
TEXT_PX = 20  # pixels the overlay's text changes at least between two times (a digit is ~30)

pytestmark = pytest.mark.filterwarnings(r"ignore:os\.fork\(\) was called:RuntimeWarning")


@pytest.fixture(scope="module")
def film():
    run = execute_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity=CURRENT))
    return HoverFilm(run, build_scene(ARM, yaml.safe_load(SCENARIO.read_text())))


def _geoms(film: HoverFilm, row: int) -> list:
    scn = mujoco.MjvScene(film.model, maxgeom=10000)
    film.add_geoms(row, scn)
    return [scn.geoms[i] for i in range(scn.ngeom)]


def _of_colour(geoms, kind, rgba) -> list:
    return [g for g in geoms if g.type == kind and np.allclose(g.rgba, rgba)]


def test_the_current_is_one_arrow_along_it_as_long_as_the_water_flows_in_ARROW_S(film):
    arrows = _of_colour(_geoms(film, 10), mujoco.mjtGeom.mjGEOM_ARROW, CURRENT_RGBA)
    assert len(arrows) == 1
    a = arrows[0]
    assert a.size[2] == pytest.approx(np.linalg.norm(CURRENT) * ARROW_S, abs=GEOM_TOL)
    np.testing.assert_allclose(a.mat[:, 2], np.asarray(CURRENT) / np.linalg.norm(CURRENT), atol=GEOM_TOL)


def test_still_water_has_no_arrow(film):
    still = execute_plan_hovering(ARM, _plan(), POSE, VehicleSettings())
    assert not _of_colour(_geoms(HoverFilm(still, film.scene), 10), mujoco.mjtGeom.mjGEOM_ARROW, CURRENT_RGBA)
    assert "still water" in HoverFilm(still, film.scene).lines(10)[0]


def test_the_outline_is_the_hulls_twelve_edges(film):
    lines = _of_colour(_geoms(film, 0), mujoco.mjtGeom.mjGEOM_LINE, OUTLINE_RGBA)
    size = VehicleSettings().size
    np.testing.assert_allclose(sorted(g.size[2] for g in lines), sorted(np.repeat(size, 4)), atol=GEOM_TOL)


def test_the_vehicle_and_arm_are_added_where_the_log_has_them(film):
    """The hovering model's geoms come in at the logged state: the vehicle's hull at the logged
    position of row k (the oracle: the log itself, not the model's replay)."""
    row = len(film.run.log.time) - 1
    hull = [g for g in _geoms(film, row) if g.objtype == mujoco.mjtObj.mjOBJ_GEOM
            and g.objid == film.model.geom(HULL_GEOM).id]
    assert len(hull) == 1
    np.testing.assert_allclose(hull[0].pos, film.run.log.position[row], atol=GEOM_TOL)


def test_the_overlay_counts_the_gates_and_changes_the_image(film):
    last = len(film.run.log.time) - 1
    first, end = film.lines(0), film.lines(last)
    assert first[0].startswith("t = 0.0 s") and "current 0.40 m/s" in first[0]
    assert first[1].startswith(f"gate 0/{PLAN_GATES}")
    assert end[1].startswith(f"gate {PLAN_GATES}/{PLAN_GATES}: tool error")
    black = np.zeros((SIZE[1], SIZE[0], 3), np.uint8)
    a, b = film.overlay(0, black), film.overlay(last, black)
    assert np.count_nonzero(np.any(a != b, axis=-1)) >= TEXT_PX  # the time and the gate differ
    assert np.count_nonzero(a[SIZE[1] // 2:]) == 0  # the panel stays in the top-left corner


CHILD = textwrap.dedent("""
    import json, sys, numpy as np, yaml
    sys.path.insert(0, sys.argv[3])
    from test_hover_plan import ARM, POSE, _plan
    from uvms_jax.hover import CurrentSettings, VehicleSettings, execute_plan_hovering, hover_frame, write_hover_video
    from uvms_jax.plan import build_scene, scene_camera
    from uvms_jax.video import render_frame
    scene = build_scene(ARM, yaml.safe_load(open(sys.argv[1])))
    run = execute_plan_hovering(ARM, _plan(), POSE, VehicleSettings(), current=CurrentSettings(velocity={current}))
    try:
        hw = render_frame(scene.model, scene.model.qpos0, scene_camera(scene), size={size})
        frames = [hover_frame(run, scene, t, size={size}) for t in (0.0, run.log.time[-1])]
    except RuntimeError as e:
        print(e)
        sys.exit({no_gl})
    info = write_hover_video(run, scene, sys.argv[2] + "/hover.mp4", fps={fps}, size={size}, progress=False)
    np.savez(sys.argv[2] + "/frames.npz", hw=hw, hover=np.stack(frames))
    print(json.dumps({{"frames": info.frames, "duration_s": float(run.log.time[-1] - run.log.time[0])}}))
""").format(current=CURRENT, size=SIZE, fps=FPS, no_gl=NO_GL_EXIT)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    out = tmp_path_factory.mktemp("hover_video")
    env = {**os.environ, "MUJOCO_GL": "egl", "JAX_PLATFORMS": "cpu"}
    r = subprocess.run([sys.executable, "-c", CHILD, str(SCENARIO), str(out), str(Path(__file__).parent)], env=env,
                       capture_output=True, text=True, timeout=300)
    if r.returncode == NO_GL_EXIT:
        pytest.skip(f"no offscreen GL context with MUJOCO_GL=egl: {r.stdout.strip()}")
    assert r.returncode == 0, r.stderr[-2000:]
    return out, json.loads(r.stdout.splitlines()[-1]), np.load(out / "frames.npz")


def test_the_frames_show_the_hw_videos_scene_from_its_camera(rendered):
    _, _, f = rendered
    lower = slice(SIZE[1] // 2, None)  # the floor and the tables, below the overlay and the hull
    for frame in f["hover"]:
        same = np.all(np.abs(frame[lower].astype(int) - f["hw"][lower].astype(int)) <= SAME_LEVEL, axis=-1)
        assert same.mean() >= SCENE_SHARE, same.mean()
    assert np.any(f["hover"][0] != f["hover"][1])  # the overlay, the arm and the path move


def test_the_video_has_the_hw_videos_frames_of_the_run(rendered):
    _, info, _ = rendered
    assert info["frames"] == int(np.floor(info["duration_s"] * FPS + 1e-9)) + 1


def _distance_to_polyline(p: np.ndarray, line: np.ndarray) -> float:
    """The distance [m] of point ``p`` from the polyline ``line`` (k, 3), segment by segment."""
    best = np.inf
    for a, b in zip(line[:-1], line[1:]):
        s = np.clip(np.dot(p - a, b - a) / max(np.dot(b - a, b - a), 1e-300), 0.0, 1.0)
        best = min(best, float(np.linalg.norm(p - a - s * (b - a))))
    return best


def test_a_drawn_path_keeps_its_corners_and_stays_within_its_tolerance():
    from uvms_jax.hover._video import simplified

    t = np.linspace(0.0, 1.0, 101)[:, None]
    straight = t * np.array([1.0, 2.0, 0.5])
    np.testing.assert_array_equal(simplified(straight, 1e-3), [0, 100])
    corner = np.concatenate([straight[:51], straight[50] + t[1:51] * np.array([0.0, 0.0, 1.0])])
    np.testing.assert_array_equal(simplified(corner, 1e-3), [0, 50, 100])
    rng = np.random.default_rng(0)
    wiggly = np.cumsum(rng.normal(0.0, 0.01, (300, 3)), axis=0)
    tolerance = 0.005
    kept = simplified(wiggly, tolerance)
    assert kept[0] == 0 and kept[-1] == 299 and len(kept) < 300
    assert max(_distance_to_polyline(p, wiggly[kept]) for p in wiggly) <= tolerance
