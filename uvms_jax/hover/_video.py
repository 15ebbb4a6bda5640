"""The video of a hovering run, drawn in the planning scene of the docked run.

Every frame is the ``hw`` stage's (:func:`uvms_jax.plan.render_run_video`): the planning
scene's model (tables, objects, floor) from :func:`uvms_jax.plan.scene_camera`, at the same
frame rate and size, so the two videos compare side by side. The planning scene's own arm, its
mount and the vehicle's boxes are hidden; the hovering vehicle and its arm are added from the
run's MuJoCo model at each logged state (``mjv_addGeoms``), with, as MuJoCo user geoms: the
docked hull's edges, the tool's target path (where the docked arm holds it), the tool's path so
far, and the current as an arrow. An overlay gives the time, the current's speed and the tool
error at the last gate passed.
"""

from __future__ import annotations

import copy
from pathlib import Path

import mujoco
import numpy as np

from uvms_jax import frames
from uvms_jax.plan import VEHICLE_PREFIX, Scene, scene_camera
from uvms_jax.video import VideoInfo, render_frame, write_video

from ._plan import HoverRun

__all__ = ["HoverFilm", "hover_frame", "write_hover_video"]

TARGET_RGBA = (0.1, 0.75, 0.2, 1.0)  # the tool's target path: green
ACTUAL_RGBA = (0.9, 0.1, 0.1, 1.0)  # the tool's path so far: red
OUTLINE_RGBA = (1.0, 1.0, 1.0, 1.0)  # the docked hull's edges: white
CURRENT_RGBA = (0.15, 0.45, 1.0, 1.0)  # the current's arrow: blue
LINE_PX = 3.0  # width of the paths' and the outline's lines [pixels]
# Points of a drawn path at most: the demo's ~92 s run gets one per ~0.3 s, finer than the
# tool moves visibly at 480 × 360. Of those, only the points where the path bends by more than
# PATH_TOLERANCE_M are drawn (Ramer–Douglas–Peucker): each line geom costs the software
# renderer about as much per frame as the rest of the scene's detail (300 points a path: 30 %
# of the video's time), and a chord within 2 mm of the path is under a pixel at these sizes.
PATH_POINTS = 300
PATH_TOLERANCE_M = 0.002
ARROW_S = 2.0  # the arrow is as long as the water flows in this time [s]: 0.3 m/s → 0.6 m
ARROW_RADIUS_M = 0.015  # the arrow's shaft [m]
ARROW_ASIDE_M = 0.3  # the arrow's middle: this far out from the docked hull's side nearest the camera [m]
TEXT_HEIGHT = 1 / 26  # overlay text height as a fraction of the frame's height
TEXT_MIN_PX = 8  # smallest legible text [pixels]
MOUNT_GEOM = "mount"  # the planning scene's mount box under the arm's base (uvms_jax.plan.Scene)


def scene_stage(scene: Scene) -> mujoco.MjModel:
    """A copy of the planning scene's model with the arm (every geom off the world body), its
    mount and the vehicle's boxes hidden (alpha 0: MuJoCo draws none of them): the stage that a
    hovering run is drawn on."""
    m = copy.deepcopy(scene.model)
    names = [m.geom(i).name for i in range(m.ngeom)]
    hidden = (m.geom_bodyid != 0) | np.array([n == MOUNT_GEOM or n.startswith(VEHICLE_PREFIX) for n in names])
    m.geom_rgba[hidden, 3] = 0.0
    return m


def box_edges(size, T: np.ndarray) -> np.ndarray:
    """``(12, 2, 3)`` the edges of a box of ``size (3,)`` [m] centred at the pose ``T (4, 4)``
    (world), each as its two corners [m]."""
    half = np.asarray(size, dtype=float) / 2
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    corners = (signs * half) @ T[:3, :3].T + T[:3, 3]
    pairs = [(i, j) for i in range(8) for j in range(i + 1, 8) if np.sum(signs[i] != signs[j]) == 1]
    return np.stack([corners[[i, j]] for i, j in pairs])


def _beside(xyz, size, camera: mujoco.MjvCamera) -> np.ndarray:
    """``(3,)`` [m]: at the bottom of a box of ``size`` centred at ``xyz``, :data:`ARROW_ASIDE_M`
    beyond its horizontal half-diagonal towards the camera (in view, clear of the hull)."""
    az = np.radians(camera.azimuth)
    towards = -np.array([np.cos(az), np.sin(az), 0.0])  # MuJoCo's free camera looks along +azimuth
    half = np.asarray(size, dtype=float) / 2
    return np.asarray(xyz, dtype=float) + towards * (np.hypot(half[0], half[1]) + ARROW_ASIDE_M) - [0.0, 0.0, half[2]]


def _thinned(n: int) -> np.ndarray:
    """Rows of an ``n``-row path that are drawn: at most :data:`PATH_POINTS`, first and last kept."""
    return np.unique(np.linspace(0, n - 1, min(n, PATH_POINTS)).round().astype(int))


def simplified(points: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices (sorted, first and last included) of the points ``(n, 3)`` [m] that a polyline
    needs so that every point lies within ``tolerance`` [m] of it (Ramer–Douglas–Peucker: the
    point farthest from the chord of a stretch is kept while it lies beyond the tolerance)."""
    n = len(points)
    keep = np.zeros(n, dtype=bool)
    keep[[0, n - 1]] = n > 0
    stack = [(0, n - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        a, inner = points[i], points[i + 1:j]
        chord = points[j] - a
        length2 = float(chord @ chord)
        s = np.clip((inner - a) @ chord / length2, 0.0, 1.0) if length2 > 0 else np.zeros(len(inner))
        distance = np.linalg.norm(inner - a - s[:, None] * chord, axis=-1)
        k = int(np.argmax(distance))
        if distance[k] > tolerance:
            keep[i + 1 + k] = True
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return np.flatnonzero(keep)


_ZERO, _EYE = np.zeros(3), np.eye(3).ravel()


def _add(scn: mujoco.MjvScene, kind: mujoco.mjtGeom, width: float, a, b, rgba) -> None:
    """A connector geom (line, arrow) from ``a`` to ``b`` [m] into ``scn``."""
    if scn.ngeom >= scn.maxgeom:
        raise RuntimeError(f"the scene holds {scn.maxgeom} geoms at most: draw fewer path points (PATH_POINTS)")
    g = scn.geoms[scn.ngeom]
    mujoco.mjv_initGeom(g, kind, _ZERO, _ZERO, _EYE, np.asarray(rgba, dtype=np.float32))
    mujoco.mjv_connector(g, kind, width, np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    scn.ngeom += 1


def _polyline(scn: mujoco.MjvScene, points: np.ndarray, rgba) -> None:
    for a, b in zip(points[:-1], points[1:]):
        _add(scn, mujoco.mjtGeom.mjGEOM_LINE, LINE_PX, a, b, rgba)


class HoverFilm:
    """What a frame of a hovering run shows over the planning scene: the ``decorate`` of
    :func:`uvms_jax.video.write_video` (the model drawn is :attr:`stage`, held still).

    Args:
      run: from :func:`~uvms_jax.hover.execute_plan_hovering` or
        :func:`~uvms_jax.hover.run_plan_hovering` (its ``world`` holds the model and the pose).
      scene: the planning scene the run's plan was made in (the docked one).

    Raises:
      ValueError: a run without its world.
    """

    def __init__(self, run: HoverRun, scene: Scene) -> None:
        if run.world is None:
            raise ValueError("the hovering run has no world to draw (make it with execute_plan_hovering or "
                             "run_plan_hovering)")
        w, log = run.world, run.log
        self.run, self.scene, self.stage = run, scene, scene_stage(scene)
        self.model, self.data = w.model, mujoco.MjData(w.model)
        self.qpos = w.replay_qpos(log)  # (k, nq) of the hovering model
        self.opt, self.pert = mujoco.MjvOption(), mujoco.MjvPerturb()
        self.outline = box_edges(w.vehicle.size, frames.pose(frames.rpy_matrix(w.rpy), w.xyz))
        rows = _thinned(len(log.time))
        self.target_rows = rows[simplified(run.tool_target[rows], PATH_TOLERANCE_M)]
        self.path_rows = rows[simplified(log.tool[rows], PATH_TOLERANCE_M)]  # of the tool's whole path
        # The row of each gate, as the run judged its tool there (a gate just after the last
        # control period: the last row).
        self.gate_rows = np.searchsorted(log.time, run.gate_times - 1e-9).clip(max=len(log.time) - 1)
        self.camera = scene_camera(scene)
        self.arrow_middle = _beside(w.xyz, w.vehicle.size, self.camera)  # [m], world
        self.font = None

    # -- geometry --------------------------------------------------------------------------------
    def add_geoms(self, row: int, scn: mujoco.MjvScene) -> None:
        """Add the vehicle and arm at log row ``row``, the docked hull's edges, the paths (the
        tool's up to ``row``) and the current's arrow to ``scn``."""
        run, log = self.run, self.run.log
        self.data.qpos[:] = self.qpos[row]
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mjv_addGeoms(self.model, self.data, self.opt, self.pert, mujoco.mjtCatBit.mjCAT_ALL, scn)
        for a, b in self.outline:
            _add(scn, mujoco.mjtGeom.mjGEOM_LINE, LINE_PX, a, b, OUTLINE_RGBA)
        _polyline(scn, run.tool_target[self.target_rows], TARGET_RGBA)
        done = self.path_rows[self.path_rows < row]
        _polyline(scn, log.tool[np.append(done, row)], ACTUAL_RGBA)
        v = log.current[row]
        if np.linalg.norm(v) > 0:
            half = v * ARROW_S / 2
            _add(scn, mujoco.mjtGeom.mjGEOM_ARROW, ARROW_RADIUS_M, self.arrow_middle - half, self.arrow_middle + half,
                 CURRENT_RGBA)

    # -- overlay ---------------------------------------------------------------------------------
    def lines(self, row: int) -> list[str]:
        """The overlay's text at log row ``row``: time, current, the last gate's tool error."""
        run, log = self.run, self.run.log
        t = float(log.time[row])
        speed = float(np.linalg.norm(log.current[row]))
        passed = int(np.sum(self.gate_rows <= row))  # the gates are in time order
        n = len(run.gate_times)
        gate = (f"gate {passed}/{n}: tool error {1e3 * run.gate_tool_error[passed - 1]:.1f} mm" if passed
                else f"gate 0/{n}: none passed yet")
        water = f"current {speed:.2f} m/s (blue arrow)" if speed > 0 else "still water"
        return [f"t = {t:.1f} s, {water}", gate, f"tool error now {1e3 * run.tool_error[row]:.1f} mm"]

    def overlay(self, row: int, image: np.ndarray) -> np.ndarray:
        """``image (h, w, 3)`` uint8 with :meth:`lines` written in its top-left corner on a dark
        panel (a new array)."""
        from PIL import Image, ImageDraw, ImageFont

        h = image.shape[0]
        px = max(TEXT_MIN_PX, round(TEXT_HEIGHT * h))
        if self.font is None or self.font.size != px:
            self.font = ImageFont.load_default(size=px)
        img = Image.fromarray(image)
        draw = ImageDraw.Draw(img)
        text = "\n".join(self.lines(row))
        box = draw.multiline_textbbox((px // 2, px // 2), text, font=self.font)
        draw.rectangle((0, 0, box[2] + px // 2, box[3] + px // 2), fill=(20, 20, 30))
        draw.multiline_text((px // 2, px // 2), text, fill=(255, 255, 255), font=self.font)
        return np.asarray(img)

    def __call__(self, row: int, renderer: mujoco.Renderer) -> np.ndarray:
        self.add_geoms(row, renderer.scene)
        return self.overlay(row, renderer.render())

    def row_at(self, time_s: float) -> int:
        """The log row shown at ``time_s`` [s]: the last at or before it."""
        t = self.run.log.time
        if not t[0] <= time_s <= t[-1]:
            raise ValueError(f"time_s must be within the run, [{t[0]}, {t[-1]}] s, got {time_s}")
        return int(np.searchsorted(t, time_s + 1e-9, side="right") - 1)


def write_hover_video(run: HoverRun, scene: Scene, path: Path | str, *, fps: float = 8.0,
                      size: tuple[int, int] = (480, 360), progress: bool = True) -> VideoInfo:
    """The hovering run as an MP4 at ``path``, framed as the ``hw`` stage's video of the same
    plan in ``scene`` (:class:`HoverFilm`; ``fps``, ``size``, ``progress``: as
    :func:`uvms_jax.video.write_video`)."""
    film = HoverFilm(run, scene)
    still = np.tile(film.stage.qpos0, (len(run.log.time), 1))
    return write_video(film.stage, run.log.time, still, path, film.camera, fps=fps, size=size,
                       progress=progress, decorate=film)


def hover_frame(run: HoverRun, scene: Scene, time_s: float, *, size: tuple[int, int] = (480, 360)) -> np.ndarray:
    """``(height, width, 3)`` uint8: the frame of :func:`write_hover_video` at ``time_s`` [s]."""
    film = HoverFilm(run, scene)
    return render_frame(film.stage, film.stage.qpos0, film.camera, size=size, decorate=film,
                        row=film.row_at(time_s))
