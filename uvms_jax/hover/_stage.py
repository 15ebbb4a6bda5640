"""The hover stage: a scheduled plan executed over BPL with the vehicle hovering at the docked
pose (:func:`run_hover`), and what it writes (:func:`write_hover`: the plot, the video, its
frame at the worst gate, the results and the summary's table).

Every run is the BPL executor on the simulated arm mounted on the hovering vehicle
(:func:`~uvms_jax.hover.execute_plan_hovering`): in still water and in the current with the
station keeping alone (the executor streams the plan, its gates on the encoders), and in the
current with the whole-body controller between the plan and the arm (its gates on the tool).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from uvms_jax.hw import ExecutorSettings, SimSettings
from uvms_jax.planfile import Plan
from uvms_jax.robot import Robot
from uvms_jax.text import md_table
from uvms_jax.video import VideoInfo

from ._executed import executor_settings
from ._plan import HoverRun, execute_plan_hovering
from ._settings import ControllerSettings, CurrentSettings, NavigationSettings, VehicleSettings, WholeBodySettings

__all__ = ["HoverFilmed", "HoverStage", "film_hover", "run_hover", "write_hover"]

log = logging.getLogger(__name__)

STILL = "still water"


@dataclasses.dataclass(frozen=True)
class HoverFilmed:
    """The main run filmed (:func:`film_hover`).

    Attributes:
      video: the MP4 written, or None where this machine has no offscreen GL context.
      frame: ``(height, width, 3)`` uint8, the frame at the gate of the largest tool error (None
        without a video).
      label: the run's label; reason: why there is no video ("" with one).
    """

    video: VideoInfo | None
    frame: np.ndarray | None
    label: str
    reason: str = ""


@dataclasses.dataclass(frozen=True)
class HoverStage:
    """The hover stage's runs (:func:`run_hover`).

    Attributes:
      runs: by label: ``"still water"``, ``"current [vx, vy, vz] m/s"`` and, with the
        whole-body controller, ``"… m/s, whole-body controller"``.
      main: the label of the run ``results.json``'s ``hover`` entry describes (the whole-body
        controller's in the current, else the current's, else still water's).
      vehicle: the vehicle the runs were on; tool_tolerance_m, tool_tolerance_deg: the gates'
        tool tolerances [m, °].
      filmed: the main run's video (:func:`film_hover`), or None.
    """

    runs: dict[str, HoverRun]
    main: str
    vehicle: VehicleSettings
    tool_tolerance_m: float
    tool_tolerance_deg: float
    filmed: HoverFilmed | None = None

    def results(self) -> dict:
        """``results.json``'s ``hover`` entry: the main run's :meth:`HoverRun.summary`, ``runs``
        (every run's), and ``coordination_removes``: the share of the largest tool error (over
        the run, and at a gate) the whole-body controller removes against the station keeping
        alone in the same current."""
        summaries = {label: r.summary() for label, r in self.runs.items()}
        res = {**summaries[self.main], "runs": summaries}
        coordinated = [label for label, r in self.runs.items() if r.coordinated]
        plain = [label for label, r in self.runs.items() if not r.coordinated and label != STILL]
        if coordinated and plain:
            a, b = summaries[plain[0]], summaries[coordinated[0]]
            res["coordination_removes"] = {k: 1.0 - b[k] / a[k] for k in ("max_tool_error_m", "max_gate_tool_error_m")}
        return res


def run_hover(robot: Robot, plan: Plan, pose, vehicle: VehicleSettings, *, current: Sequence[float] = (0.0, 0.0, 0.0),
              controller: ControllerSettings = ControllerSettings(),
              whole_body: WholeBodySettings | None = WholeBodySettings(),
              navigation: NavigationSettings | None = None, tool_tolerance_m: float = 0.01,
              tool_tolerance_deg: float = 2.0, config: ExecutorSettings = ExecutorSettings(), sim: SimSettings = SimSettings(),
              progress: Callable[[str], None] | None = None,
              film: Callable[[HoverRun, str], HoverFilmed] | None = None) -> HoverStage:
    """``plan`` over BPL on the vehicle hovering at the docked ``pose`` ``(4,) = [x, y, z, ψ]``
    [m, rad]: in still water, and in ``current`` [m/s, world] (if not 0) with the station
    keeping alone and, unless ``whole_body`` is None, with the whole-body controller (its
    settings led for the simulated arm's servo, :func:`executor_settings`; seeing the vehicle
    through ``navigation``, None: exactly).

    Args:
      vehicle: the vehicle, built once (its hull and the arm's mount the docking scene's).
      config, sim: the executor's and the simulated arm's settings (the ``hw`` stage's).
      progress: called with each run's label when it is done.
      film: None, or called with the main run and its label (e.g. :func:`film_hover` with its
        scene and path bound) as soon as that run is done, in a thread of its own while the
        other runs go on: the main run goes first. Rendering waits mostly on OpenGL and ffmpeg,
        which leave Python's lock free, so on two cores the video costs little beyond the runs.
        What it returns is the stage's ``filmed``; what it raises, ``run_hover`` raises.
    """
    cases = {STILL: ((0.0, 0.0, 0.0), False)}
    flowing = f"current {[round(float(v), 3) + 0.0 for v in current]} m/s"
    if any(current):
        cases[flowing] = (tuple(current), False)
        if whole_body is not None:
            cases[f"{flowing}, whole-body controller"] = (tuple(current), True)
    main = list(cases)[-1]
    runs, filming = {}, None
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="hover-film") as pool:
        for label in [main, *list(cases)[:-1]]:
            v, coordinate = cases[label]
            runs[label] = execute_plan_hovering(
                robot, plan, pose, vehicle, controller, CurrentSettings(velocity=v), config=config, sim=sim,
                tool_tolerance_m=tool_tolerance_m, tool_tolerance_deg=tool_tolerance_deg,
                control="whole_body" if coordinate else "pid",
                whole_body=executor_settings(whole_body, sim.servo_gain) if coordinate else None, navigation=navigation)
            if label == main and film is not None:
                filming = pool.submit(film, runs[main], main)
            if progress is not None:
                progress(label)
        filmed = None if filming is None else filming.result()
    return HoverStage({label: runs[label] for label in cases}, main, vehicle, float(tool_tolerance_m),
                      float(tool_tolerance_deg), filmed)


def write_hover(stage: HoverStage, out: Path | str, *, frame_png: Path | str | None = None,
                docked: dict | None = None) -> tuple[dict, str, list[str]]:
    """Write ``out/hover.png`` (drift and tool error over time) and, for a filmed stage
    (:func:`film_hover`), ``out/hover_frame.png`` (also at ``frame_png``): the video's frame
    at the gate of the largest tool error.

    Args:
      docked: the ``hw`` stage's results (``status``, ``gates``) for the table's first row, or None.

    Returns:
      ``(results, table, notes)``: ``results.json``'s ``hover`` entry (:meth:`HoverStage.results`,
      with ``video_frames`` and ``video_render_s`` when filmed), the summary's markdown table and
      its notes.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    res = stage.results()
    plot_hover(stage.runs, out / "hover.png")
    notes = [_note(stage)]
    if stage.filmed is not None:
        notes.append(_film_note(stage.filmed, out, res, frame_png))
    return res, _table(stage, res["runs"], docked), notes


def film_hover(run: HoverRun, label: str, *, scene, path: Path | str, fps: float = 8.0,
               size: tuple[int, int] = (480, 360)) -> HoverFilmed:
    """``run`` as an MP4 at ``path`` in ``scene`` (the planning scene its plan was made in:
    :func:`~uvms_jax.hover.write_hover_video`) and its frame at the gate of the largest tool
    error; where this machine has no offscreen GL context, no video and the reason."""
    from ._video import hover_frame, write_hover_video

    try:
        video = write_hover_video(run, scene, path, fps=fps, size=size)
        worst = run.gate_times[np.argmax(run.gate_tool_error)] if len(run.gate_times) else run.log.time[-1]
        frame = hover_frame(run, scene, float(min(worst, run.log.time[-1])), size=size)
    except RuntimeError as e:  # no offscreen GL context on this machine
        log.warning("no video of the hovering run: %s", e)
        return HoverFilmed(None, None, label, str(e))
    return HoverFilmed(video, frame, label)


def _table(stage: HoverStage, summaries: dict, docked: dict | None) -> str:
    rows = [[label, m["driver"], f"{m['status']}" + (f": {m['reason']}" if m["reason"] else ""),
             f"{m['gates_reached']}/{m['gates']}", f"{m['gates_tool_within_tolerance']}/{m['gates']}",
             1e3 * m["max_drift_m"], 1e3 * m["max_tool_error_m"], 1e3 * m["max_gate_tool_error_m"], m["max_tilt_deg"],
             m["peak_thrust_N"]] for label, m in summaries.items()]
    if docked is not None:
        g = docked.get("gates", "—")
        rows.insert(0, ["docked (hw stage)", "BPL executor", docked.get("status", ""), f"{g}/{g}", f"{g}/{g}",
                        0.0, 0.0, 0.0, 0.0, 0.0])
    return md_table(["vehicle", "arm driven by", "result", "gates passed", "gates with the tool within "
                     f"{1e3 * stage.tool_tolerance_m:.0f} mm", "max drift [mm]", "max tool error [mm]",
                     "max tool error at a gate [mm]", "max roll/pitch [°]", "peak thrust [N]"], rows)


def _note(stage: HoverStage) -> str:
    v, mm = stage.vehicle, 1e3 * stage.tool_tolerance_m
    return (f"The scheduled plan on the vehicle floating at the docked pose (MuJoCo, `uvms_jax.hover`, docs/hover.md): "
            f"{len(v.thrusters)} thrusters of ±{max(t.max_thrust for t in v.thrusters):g} N, the hull ballasted "
            "neutral and level for the arm at the plan's start. Every run is the hw stage's BPL executor, with its "
            "settings and safety checks, on the simulated arm mounted on the hovering vehicle. With the station "
            "keeping alone (x, y, z, ψ) the executor streams the plan and its gates are on the encoders, which the "
            "vehicle's motion does not move: it passes them as on a fixed base while the tool is off, and the "
            f"column after them counts the gates where the tool was also within {mm:.0f} mm of where the docked "
            "arm holds it at the same joint angles. With the whole-body controller (docs/hover.md) between the plan "
            "and the arm, every tick's joint demands come from the measured joints and the vehicle's navigation "
            "estimate, the tool first on the plan's docked path through the vehicle–arm Jacobian (`kin.uvms`), "
            "station keeping in that task's null space, the thrusters with a model-based feed-forward; its gates "
            f"are on the tool's pose (within {mm:.0f} mm and {stage.tool_tolerance_deg:g}°). "
            "`hover/hover.png`: drift and tool error over time.")


def _film_note(filmed: HoverFilmed, out: Path, res: dict, frame_png: Path | str | None) -> str:
    """Save the video's frame at the worst gate; ``res`` gets the video's size and time; the
    summary's note."""
    if filmed.video is None:
        return f"No video of the hovering run: {filmed.reason}."
    from PIL import Image

    for path in [out / "hover_frame.png"] + ([Path(frame_png)] if frame_png else []):
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(filmed.frame).save(path, optimize=True)
    video = filmed.video
    res["video_frames"], res["video_render_s"] = video.frames, video.seconds
    link = f"{out.name}/{video.path.name}"
    return (f"Video of the {filmed.label} run: [{link}]({link}) — the vehicle and the arm as simulated in the hw "
            "video's scene, camera and frames (compare side by side), with the docked hull's outline (white), the "
            "tool's target path (green) and its path so far (red), the current (blue arrow) and the time and the tool "
            f"error at the last gate; {video.fps:g} fps, {video.frames} frames, rendered in {video.seconds:.1f} s. "
            f"`{out.name}/hover_frame.png`: the frame at the gate of the largest tool error.")


def plot_hover(runs: dict[str, HoverRun], path: Path) -> None:
    """Drift of the vehicle and tool error over time, one line per run → PNG at ``path``."""
    from uvms_jax.plotting import pyplot

    plt = pyplot()
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 5), sharex=True, layout="constrained")
    for label, r in runs.items():
        a.plot(r.log.time, 1e3 * r.drift, label=label)
        b.plot(r.log.time, 1e3 * r.tool_error, label=label)
        b.plot(r.gate_times, 1e3 * r.gate_tool_error, ".", color=b.lines[-1].get_color(), ms=4)
    a.set(ylabel="vehicle drift [mm]", title="Hovering at the docked pose")
    b.set(xlabel="time [s]", ylabel="tool error [mm] (dots: gates)")
    a.legend(fontsize=8)
    fig.savefig(path, dpi=100)
    plt.close(fig)
