"""A video of an executed run: the arm in the planning scene, rendered offscreen by MuJoCo.

The frames replay joint angles logged over time (e.g. the measured states of a hardware run),
sampled at a fixed frame rate, and go to an H.264 MP4 (yuv420p, playable everywhere) through
the ffmpeg that ``imageio-ffmpeg`` ships.
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import time
import warnings
from pathlib import Path

import numpy as np

from uvms_jax.plan._scene import Scene

__all__ = ["VideoInfo", "render_run_video", "scene_camera"]

log = logging.getLogger(__name__)

# Camera of every rendered view of the cage (frames and videos): from the +x+y corner, above
# the tables, the whole arm and all four tables in view.
CAMERA_LOOKAT = (0.0, 0.0, 0.45)  # [m], world frame
CAMERA_DISTANCE = 2.2  # [m]
CAMERA_AZIMUTH = 135.0  # [deg]
CAMERA_ELEVATION = -30.0  # [deg]
CAGE_BASE_Z = 0.94  # [m] height of the arm's base in the cage (configs/scenario/thesis_cage.yaml)
HEADLIGHT_AMBIENT = 0.35  # RGB intensity of the video's headlight, each channel
HEADLIGHT_DIFFUSE = 0.6


def scene_camera(scene: Scene | None = None):
    """The free ``mujoco.MjvCamera`` that frames the cage (see ``CAMERA_*``); for an arm base
    higher than the cage's (e.g. under a vehicle), it looks higher and steps back so that the
    base and what carries it stay in view."""
    import mujoco

    cam = mujoco.MjvCamera()
    cam.lookat[:] = CAMERA_LOOKAT
    cam.distance, cam.azimuth, cam.elevation = CAMERA_DISTANCE, CAMERA_AZIMUTH, CAMERA_ELEVATION
    above = 0.0 if scene is None else max(0.0, float(scene.T_world_base[2, 3]) - CAGE_BASE_Z)
    cam.lookat[2] += above / 2
    cam.distance += 2 * above
    return cam


@dataclasses.dataclass(frozen=True)
class VideoInfo:
    """What :func:`render_run_video` wrote.

    Attributes:
      path: the MP4 file.
      frames: number of frames.
      fps: frames per second.
      seconds: wall time of rendering and encoding [s].
    """

    path: Path
    frames: int
    fps: float
    seconds: float

    @property
    def duration_s(self) -> float:
        """Length of the video [s]."""
        return self.frames / self.fps


def _frame_indices(t: np.ndarray, fps: float) -> np.ndarray:
    """Row of ``t`` shown in each frame: frame k shows the last row at or before ``t[0] + k / fps``
    (a zero-order hold, as the log holds each state until the next one arrived).

    Args:
      t: ``(n,)`` non-decreasing times [s].
      fps: frames per second.

    Returns:
      ``(floor((t[-1] - t[0]) * fps) + 1,)`` row indices.
    """
    n_frames = int(np.floor((t[-1] - t[0]) * fps + 1e-9)) + 1  # 1e-9: a duration of exactly k / fps
    t_frame = t[0] + np.arange(n_frames) / fps
    return np.searchsorted(t, t_frame + 1e-9, side="right") - 1


def render_run_video(scene: Scene, t, q, path: Path | str, *, fps: float = 8.0,
                     size: tuple[int, int] = (480, 360), progress: bool = True) -> VideoInfo:
    """Render the arm moving through ``q`` over ``t`` in ``scene`` to an MP4 at ``path``.

    The arm only: the scene model's jaws are two fixed fingers (no jaw joint), so the jaws'
    opening is not shown, and the objects stay where the scenario puts them (the in-hand
    copies of the collision model are hidden). Shadows and reflections are off, which halves
    the cost of software (Mesa) rendering on a CPU-only machine.

    Args:
      scene: from :func:`build_scene`; its model is copied, not changed.
      t: ``(n,)`` non-decreasing times [s] (e.g. the run log's ``t_s``).
      q: ``(n, 6)`` joint angles G…B [rad] at ``t`` (e.g. the measured ones; no NaN).
      path: the MP4 file (parent folders created).
      fps: frames per second; the video lasts ``t[-1] - t[0]`` (one frame every ``1 / fps``
        seconds of the run, each the last state logged before it).
      size: ``(width, height)`` [pixels], both even (yuv420p) and at most the scene's offscreen
        buffer (960 × 720).
      progress: show progress (:func:`uvms_jax.progress.bar`: a bar on a terminal, lines in a log).

    Returns:
      :class:`VideoInfo`.

    Raises:
      ValueError: on bad shapes, NaN, decreasing times, or a bad ``fps``/``size``.
      RuntimeError: no offscreen GL context (set ``MUJOCO_GL=egl`` or ``osmesa`` before MuJoCo
        is first imported).
    """
    import imageio
    import mujoco

    from uvms_jax import progress as progress_lines

    t, q = np.asarray(t, dtype=float), np.asarray(q, dtype=float)
    m0 = scene.model
    if t.ndim != 1 or len(t) == 0 or q.shape != (len(t), m0.nq):
        raise ValueError(f"t must be (n,) and q (n, {m0.nq}) with n > 0, got t {t.shape}, q {q.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
        raise ValueError("t and q must be finite (drop the log rows without a measured state)")
    if np.any(np.diff(t) < 0):
        raise ValueError("t must be non-decreasing")
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number, got {fps}")
    width, height = (int(v) for v in size)
    max_w, max_h = int(m0.vis.global_.offwidth), int(m0.vis.global_.offheight)
    if width % 2 or height % 2 or not (0 < width <= max_w and 0 < height <= max_h):
        raise ValueError(f"size must be even (width, height) within ({max_w}, {max_h}), got {size}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = _frame_indices(t, fps)

    model = copy.deepcopy(m0)
    model.geom_rgba[list(scene.held_geoms.values()), 3] = 0.0
    # A brighter headlight than MuJoCo's default (ambient 0.1, diffuse 0.4): the grey arm
    # stays visible on the dark background once shadows are off.
    model.vis.headlight.ambient[:] = HEADLIGHT_AMBIENT
    model.vis.headlight.diffuse[:] = HEADLIGHT_DIFFUSE
    data = mujoco.MjData(model)
    try:
        renderer = mujoco.Renderer(model, height, width)
    except Exception as e:  # no EGL/OSMesa/GLFW context on this machine
        raise RuntimeError(f"offscreen rendering unavailable ({e}); set MUJOCO_GL=egl or osmesa") from e
    for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION):
        renderer.scene.flags[flag] = False
    cam = scene_camera(scene)
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            # imageio-ffmpeg starts ffmpeg with a pre-exec hook, so JAX's at-fork handler warns of
            # a deadlock; the child only calls exec, which touches none of JAX's threads.
            warnings.filterwarnings("ignore", message=r"os\.fork\(\) was called", category=RuntimeWarning)
            # macro_block_size=2: yuv420p needs even sizes only; imageio would otherwise resize
            # to multiples of 16.
            with imageio.get_writer(path, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                                    pixelformat="yuv420p", macro_block_size=2, ffmpeg_log_level="error") as writer:
                for i in (progress_lines.bar(rows, desc="video", unit="frame") if progress else rows):
                    data.qpos[:] = q[i]
                    mujoco.mj_kinematics(model, data)
                    renderer.update_scene(data, cam)
                    writer.append_data(renderer.render())
    finally:
        renderer.close()
    info = VideoInfo(path, len(rows), float(fps), time.perf_counter() - start)
    log.info("video %s: %d frames (%.0f s at %g fps, %dx%d) in %.1f s", path.name, info.frames,
             info.duration_s, fps, width, height, info.seconds)
    return info
