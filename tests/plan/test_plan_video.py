"""Video of an executed run: frame count from the run's length, frames that follow the arm.

MuJoCo picks its GL backend when it is first imported, and other test modules import it
first, so the rendering runs in a child process with ``MUJOCO_GL=egl`` (software rendering
through Mesa on a CPU-only machine); the test is skipped, saying why, where no GL context
can be made. Reading the MP4 back needs no GL.
"""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import imageio
import numpy as np
import pytest
import yaml

from uvms_jax.plan import build_scene, render_run_video
from uvms_jax.robot import load_arm  # noqa: E402

BRAVO7 = load_arm("bravo7")

SCENARIO = Path(__file__).parents[2] / "configs" / "scenario" / "thesis_cage.yaml"
NO_GL_EXIT = 3  # exit status of the child when no offscreen context exists
FPS = 10.0
RUN_S = 2.0  # the synthetic run: still for 1 s, then joints G, F, E move for 1 s
SIZE = (320, 240)
CHANGED_LEVEL = 20  # a pixel changed if a channel moved by more [0-255]: above H.264 noise
STILL_PX = 10  # changed pixels allowed between frames of a still arm (codec noise)
MOVING_PX = 100  # changed pixels at least, frames 0.1 s apart, joints at 0.4-0.8 rad/s (≈ 230 seen)

# The child and ffmpeg (which reads the MP4 back) are started by fork + exec; JAX's at-fork
# handler warns of deadlocks that exec rules out.
pytestmark = pytest.mark.filterwarnings(r"ignore:os\.fork\(\) was called:RuntimeWarning")

CHILD = textwrap.dedent("""
    import sys, numpy as np, yaml
    from uvms_jax.plan import build_scene, render_run_video
    from uvms_jax.robot import load_arm
    scene = build_scene(load_arm("bravo7"), yaml.safe_load(open(sys.argv[1])))
    t = np.linspace(0.0, {run_s}, 101)                      # a 50 Hz log
    q = np.tile(np.asarray(scene.start_q), (len(t), 1))
    moving = t > {run_s} / 2
    q[moving, :3] += np.outer(t[moving] - {run_s} / 2, [0.4, -0.8, -0.8])  # [rad/s]
    try:
        info = render_run_video(scene, t, q, sys.argv[2], fps={fps}, size={size}, progress=False)
    except RuntimeError as e:
        print(e)
        sys.exit({no_gl})
    print(info.frames)
""").format(run_s=RUN_S, fps=FPS, size=SIZE, no_gl=NO_GL_EXIT)


@pytest.fixture(scope="module")
def video(tmp_path_factory):
    path = tmp_path_factory.mktemp("video") / "run.mp4"
    env = {**os.environ, "MUJOCO_GL": "egl", "JAX_PLATFORMS": "cpu"}
    r = subprocess.run([sys.executable, "-c", CHILD, str(SCENARIO), str(path)], env=env,
                       capture_output=True, text=True, timeout=300)
    if r.returncode == NO_GL_EXIT:
        pytest.skip(f"no offscreen GL context with MUJOCO_GL=egl: {r.stdout.strip()}")
    assert r.returncode == 0, r.stderr[-2000:]
    return path, int(r.stdout.split()[-1])


def test_video_has_one_frame_per_tick_of_the_run(video):
    path, reported = video
    assert path.stat().st_size > 0
    with imageio.get_reader(path, format="FFMPEG") as reader:
        frames = [np.asarray(f, dtype=float) for f in reader]
    n = int(RUN_S * FPS) + 1  # frames at 0, 0.1, …, 2.0 s
    assert reported == n
    assert len(frames) == n
    assert frames[0].shape == (SIZE[1], SIZE[0], 3)


def test_frames_follow_the_arm(video):
    path, _ = video
    with imageio.get_reader(path, format="FFMPEG") as reader:
        frames = np.stack([np.asarray(f, dtype=float) for f in reader])
    changed = np.abs(np.diff(frames, axis=0)).max(axis=-1) > CHANGED_LEVEL  # frame k → k + 1
    step = changed.sum(axis=(1, 2))
    half = int(RUN_S * FPS / 2)  # frame `half` is the last one before the arm moves
    assert step[:half].max() <= STILL_PX, step
    assert step[half:].min() >= MOVING_PX, step


@pytest.fixture(scope="module")
def scene():
    return build_scene(BRAVO7, yaml.safe_load(SCENARIO.read_text()))


@pytest.mark.parametrize("t, q, kw, match", [
    (np.array([0.0, 1.0]), np.zeros((2, 5)), {}, "q"),
    (np.array([0.0, 1.0]), np.full((2, 6), np.nan), {}, "finite"),
    (np.array([1.0, 0.0]), np.zeros((2, 6)), {}, "non-decreasing"),
    (np.array([0.0, 1.0]), np.zeros((2, 6)), {"fps": 0.0}, "fps"),
    (np.array([0.0, 1.0]), np.zeros((2, 6)), {"size": (481, 360)}, "even"),
    (np.array([0.0, 1.0]), np.zeros((2, 6)), {"size": (2000, 360)}, "within"),
])
def test_bad_input_is_refused_before_rendering(scene, tmp_path, t, q, kw, match):
    with pytest.raises(ValueError, match=match):
        render_run_video(scene, t, q, tmp_path / "x.mp4", **kw)
    assert not (tmp_path / "x.mp4").exists()
