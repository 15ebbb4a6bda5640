"""A video of an executed run: the arm in the planning scene, rendered offscreen by MuJoCo
(:func:`uvms_jax.video.write_video`), and the camera of every view of the cage."""

from __future__ import annotations

import copy
from pathlib import Path

from uvms_jax.plan._scene import Scene
from uvms_jax.video import VideoInfo, write_video

__all__ = ["VideoInfo", "render_run_video", "scene_camera"]

# Camera of every rendered view of the cage (frames and videos): from the +x+y corner, above
# the tables, the whole arm and all four tables in view.
CAMERA_LOOKAT = (0.0, 0.0, 0.45)  # [m], world frame
CAMERA_DISTANCE = 2.2  # [m]
CAMERA_AZIMUTH = 135.0  # [deg]
CAMERA_ELEVATION = -30.0  # [deg]
CAGE_BASE_Z = 0.94  # [m] height of the arm's base in the cage (configs/scenario/thesis_cage.yaml)


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


def render_run_video(scene: Scene, t, q, path: Path | str, *, fps: float = 8.0,
                     size: tuple[int, int] = (480, 360), progress: bool = True) -> VideoInfo:
    """Render the arm moving through ``q`` over ``t`` in ``scene`` to an MP4 at ``path``
    (:func:`uvms_jax.video.write_video`, from :func:`scene_camera`).

    The arm only: the scene model's jaws are two fixed fingers (no jaw joint), so the jaws'
    opening is not shown, and the objects stay where the scenario puts them (the in-hand
    copies of the collision model are hidden).

    Args:
      scene: from :func:`build_scene`; its model is copied, not changed.
      t: ``(n,)`` non-decreasing times [s] (e.g. the run log's ``t_s``).
      q: ``(n, 6)`` joint angles G…B [rad] at ``t`` (e.g. the measured ones; no NaN).
      path, fps, size, progress: as :func:`uvms_jax.video.write_video` (``size`` at most the
        scene's offscreen buffer, 960 × 720).

    Raises:
      ValueError: on bad shapes, NaN, decreasing times, or a bad ``fps``/``size``.
      RuntimeError: no offscreen GL context.
    """
    model = copy.deepcopy(scene.model)
    model.geom_rgba[list(scene.held_geoms.values()), 3] = 0.0
    return write_video(model, t, q, path, scene_camera(scene), fps=fps, size=size, progress=progress)
