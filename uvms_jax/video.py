"""MP4 videos of logged MuJoCo states, rendered offscreen: one writer for every video of the
package (an executed run in its planning scene, the hovering vehicle).

Frames replay ``qpos`` rows logged over time, sampled at a fixed frame rate, and go to an H.264
MP4 (yuv420p, playable everywhere) through the ffmpeg that ``imageio-ffmpeg`` ships.
"""

from __future__ import annotations

import dataclasses
import logging
import time
import warnings
from pathlib import Path

import numpy as np

__all__ = ["HEADLIGHT_AMBIENT", "HEADLIGHT_DIFFUSE", "VideoInfo", "frame_rows", "render_frame", "write_video"]

log = logging.getLogger(__name__)

# A brighter headlight than MuJoCo's default (ambient 0.1, diffuse 0.4): grey links stay
# visible on the dark background once shadows are off.
HEADLIGHT_AMBIENT = 0.35  # RGB intensity, each channel
HEADLIGHT_DIFFUSE = 0.6


@dataclasses.dataclass(frozen=True)
class VideoInfo:
    """What :func:`write_video` wrote.

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


def frame_rows(t: np.ndarray, fps: float) -> np.ndarray:
    """Row of ``t`` shown in each frame: frame k shows the last row at or before ``t[0] + k / fps``
    (a zero-order hold, as a log holds each state until the next one arrived).

    Args:
      t: ``(n,)`` non-decreasing times [s].
      fps: frames per second.

    Returns:
      ``(floor((t[-1] - t[0]) * fps) + 1,)`` row indices.
    """
    n_frames = int(np.floor((t[-1] - t[0]) * fps + 1e-9)) + 1  # 1e-9: a duration of exactly k / fps
    t_frame = t[0] + np.arange(n_frames) / fps
    return np.searchsorted(t, t_frame + 1e-9, side="right") - 1


def _renderer(model, size: tuple[int, int]):
    """``(model copy, its data, mujoco.Renderer)`` for offscreen frames of ``size = (width,
    height)`` [pixels]: the headlight brightened (``HEADLIGHT_*``), shadows and reflections off
    (half the cost of software rendering). ``model`` is not changed.

    Raises:
      ValueError: ``size`` odd or beyond the model's offscreen buffer.
      RuntimeError: no offscreen GL context.
    """
    import copy

    import mujoco

    width, height = (int(v) for v in size)
    max_w, max_h = int(model.vis.global_.offwidth), int(model.vis.global_.offheight)
    if width % 2 or height % 2 or not (0 < width <= max_w and 0 < height <= max_h):
        raise ValueError(f"size must be even (width, height) within ({max_w}, {max_h}), got {size}")
    model = copy.deepcopy(model)
    model.vis.headlight.ambient[:] = HEADLIGHT_AMBIENT
    model.vis.headlight.diffuse[:] = HEADLIGHT_DIFFUSE
    try:
        renderer = mujoco.Renderer(model, height, width)
    except Exception as e:  # no EGL/OSMesa/GLFW context on this machine
        raise RuntimeError(f"offscreen rendering unavailable ({e}); set MUJOCO_GL=egl or osmesa") from e
    for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION):
        renderer.scene.flags[flag] = False
    return model, mujoco.MjData(model), renderer


def _draw(model, data, renderer, qpos: np.ndarray, camera, row: int, decorate) -> np.ndarray:
    """One frame ``(height, width, 3)`` uint8 of ``model`` at ``qpos``; ``decorate(row, renderer)``
    renders it instead of ``renderer.render()`` (it may add to ``renderer.scene`` first)."""
    import mujoco

    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    renderer.update_scene(data, camera)
    return renderer.render() if decorate is None else decorate(row, renderer)


def render_frame(model, qpos, camera, *, size: tuple[int, int] = (480, 360), decorate=None, row: int = 0) -> np.ndarray:
    """One frame of ``model`` at ``qpos (model.nq,)`` as :func:`write_video` draws it.

    Args:
      model, camera, size, decorate: as :func:`write_video`.
      qpos: ``(model.nq,)`` positions (finite).
      row: the row index handed to ``decorate``.

    Returns:
      ``(height, width, 3)`` uint8 RGB.

    Raises:
      ValueError, RuntimeError: as :func:`write_video`.
    """
    qpos = np.asarray(qpos, dtype=float)
    if qpos.shape != (model.nq,) or not np.all(np.isfinite(qpos)):
        raise ValueError(f"qpos must be ({model.nq},) finite, got {qpos.shape}")
    model, data, renderer = _renderer(model, size)
    try:
        return _draw(model, data, renderer, qpos, camera, row, decorate)
    finally:
        renderer.close()


def write_video(model, t, qpos, path: Path | str, camera, *, fps: float = 8.0, size: tuple[int, int] = (480, 360),
                progress: bool = True, decorate=None) -> VideoInfo:
    """Render ``model`` through the states ``qpos`` at times ``t`` to an MP4 at ``path``.

    Shadows and reflections are off, which halves the cost of software (Mesa) rendering on a
    CPU-only machine; the headlight is brightened (``HEADLIGHT_*``). ``model`` is not changed.

    Args:
      model: the ``mujoco.MjModel`` to draw.
      t: ``(n,)`` non-decreasing times [s].
      qpos: ``(n, model.nq)`` positions at ``t`` (no NaN).
      path: the MP4 file (parent folders created).
      camera: a ``mujoco.MjvCamera``.
      fps: frames per second; the video lasts ``t[-1] - t[0]`` (:func:`frame_rows`).
      size: ``(width, height)`` [pixels], both even (yuv420p) and at most the model's offscreen
        buffer.
      progress: show progress (:func:`uvms_jax.progress.bar`).
      decorate: None, or ``decorate(row, renderer) -> (height, width, 3) uint8``: called for each
        frame once the scene holds ``model`` at ``qpos[row]``, it renders the frame in place of
        ``renderer.render()`` (adding geoms to ``renderer.scene`` first, drawing on the image
        after).

    Raises:
      ValueError: on bad shapes, NaN, decreasing times, or a bad ``fps``/``size``.
      RuntimeError: no offscreen GL context (set ``MUJOCO_GL=egl`` or ``osmesa`` before MuJoCo
        is first imported).
    """
    import imageio

    from uvms_jax import progress as progress_lines

    t, qpos = np.asarray(t, dtype=float), np.asarray(qpos, dtype=float)
    if t.ndim != 1 or len(t) == 0 or qpos.shape != (len(t), model.nq):
        raise ValueError(f"t must be (n,) and qpos (n, {model.nq}) with n > 0, got t {t.shape}, qpos {qpos.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(qpos))):
        raise ValueError("t and qpos must be finite (drop the log rows without a measured state)")
    if np.any(np.diff(t) < 0):
        raise ValueError("t must be non-decreasing")
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number, got {fps}")
    model, data, renderer = _renderer(model, size)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = frame_rows(t, fps)
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
                    writer.append_data(_draw(model, data, renderer, qpos[i], camera, int(i), decorate))
    finally:
        renderer.close()
    info = VideoInfo(path, len(rows), float(fps), time.perf_counter() - start)
    log.info("video %s: %d frames (%.0f s at %g fps, %dx%d) in %.1f s", path.name, info.frames,
             info.duration_s, fps, *size, info.seconds)
    return info
