"""The hover stage: the scheduled plan's motion with the vehicle hovering at the docked pose
(``hover.execute_plan_hovering``, ``hover.run_plan_hovering``)."""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path

import numpy as np

from uvms_jax import hover, progress
from uvms_jax.pipeline._precheck import vehicle_hull
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.pipeline.stages._flow import VIDEO_FPS, VIDEO_SIZE, Flow
from uvms_jax.pipeline.stages._flow import film_scene as _film_scene
from uvms_jax.pipeline.stages._flow import rounded as _pose
from uvms_jax.text import md_table

__all__ = ["run"]

log = logging.getLogger(__name__)


def run(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """The scheduled plan's motion with the vehicle hovering at the docked pose instead of fixed
    to it, in still water and in the configured current: how good the docking pose is if the
    vehicle only hovers there."""
    hs, scene = s.hover, s.docking.scene
    hull = vehicle_hull(scene)
    vehicle = dataclasses.replace(hs.vehicle, size=tuple(hull.size), mount_xyz=tuple(scene.mount_xyz),
                                  mount_rpy=tuple(scene.mount_rpy))
    cases = {"still water": ((0.0, 0.0, 0.0), False)}
    flowing = f"current {_pose(hs.current)} m/s"
    if any(hs.current):
        cases[flowing] = (tuple(hs.current), False)
        if hs.coordinate:
            cases[f"{flowing}, whole-body controller"] = (tuple(hs.current), True)
    runs = {}
    for label, (v, coordinate) in progress.bar(list(cases.items()), desc="hover", unit="run"):
        current = hover.CurrentSettings(velocity=v)
        if coordinate:  # the executor streams the plan's waypoints: the controller runs on HoverSim
            runs[label] = hover.run_plan_hovering(
                flow.robot, flow.plan, flow.pose, vehicle, hs.controller, current, dwell_s=hs.dwell_s,
                gripper_s=hs.gripper_s, tool_tolerance_m=hs.tool_tolerance_m,
                joint_tolerance_rad=hs.joint_tolerance_rad, control="whole_body", whole_body=hs.whole_body,
                tool_tolerance_deg=hs.tool_tolerance_deg, navigation=hs.navigation)
        else:  # the hw stage's executor and gates; its simulated arm on the hovering vehicle
            runs[label] = hover.execute_plan_hovering(
                flow.robot, flow.plan, flow.pose, vehicle, hs.controller, current, config=s.hw.executor,
                sim=s.hw.sim, tool_tolerance_m=hs.tool_tolerance_m)
    summaries = {label: r.summary() for label, r in runs.items()}
    rows = [[label, m["driver"], f"{m['status']}" + (f": {m['reason']}" if m["reason"] else ""),
             f"{m['gates_reached']}/{m['gates']}", f"{m['gates_tool_within_tolerance']}/{m['gates']}",
             1e3 * m["max_drift_m"], 1e3 * m["max_tool_error_m"], 1e3 * m["max_gate_tool_error_m"], m["max_tilt_deg"],
             m["peak_thrust_N"]] for label, m in summaries.items()]
    docked = flow.reports.get("hw")
    if docked is not None:
        g = docked.results.get("gates", "—")
        rows.insert(0, ["docked (hw stage)", "BPL executor", docked.results.get("status", ""), f"{g}/{g}", f"{g}/{g}",
                        0.0, 0.0, 0.0, 0.0, 0.0])
    table = md_table(["vehicle", "arm driven by", "result", "gates passed", "gates with the tool within "
                      f"{1e3 * hs.tool_tolerance_m:.0f} mm", "max drift [mm]", "max tool error [mm]",
                      "max tool error at a gate [mm]", "max roll/pitch [°]", "peak thrust [N]"], rows)
    main = flowing if flowing in summaries else "still water"
    res = {**summaries[main], "runs": summaries}
    if f"{flowing}, whole-body controller" in summaries:
        plain, coord = summaries[flowing], summaries[f"{flowing}, whole-body controller"]
        res["coordination_removes"] = {k: 1.0 - coord[k] / plain[k] for k in ("max_tool_error_m", "max_gate_tool_error_m")}
    _plot_hover(runs, out / "hover.png")
    if s.hw.plot:
        video_note = _hover_video(s, flow, runs[main], main, out, res)
    notes = [f"The scheduled plan on the vehicle floating at the docked pose (MuJoCo, `uvms_jax.hover`, docs/hover.md): "
             f"{len(vehicle.thrusters)} thrusters of ±{max(t.max_thrust for t in vehicle.thrusters):g} N, station "
             "keeping on x, y, z, ψ, the hull ballasted neutral and level for the arm at the plan's start. The BPL "
             "executor of the hw stage runs the plan with its settings, gates and safety checks on the simulated arm "
             "mounted on the hovering vehicle: its gates are on the encoders, which the vehicle's motion does not "
             "move, so it passes them as on a fixed base while the tool is off; the column after them counts the "
             f"gates where the tool was also within {1e3 * hs.tool_tolerance_m:.0f} mm of where the docked arm holds "
             "it at the same joint angles (tool error: the vehicle's motion, seen at the tool). "
             "The whole-body controller (docs/hover.md) keeps the tool on the plan's docked path through the "
             "vehicle–arm Jacobian (`kin.uvms`), station keeping in that task's null space, with a model-based "
             "feed-forward on the thrusters; the executor, streaming the plan's waypoints, does not do this, so that "
             f"run is on the simulator's position servos, dwelling {hs.dwell_s} s at each segment's end (its gate), "
             f"and its gates are judged on the tool's world pose (within {1e3 * hs.tool_tolerance_m:.0f} mm and "
             f"{hs.tool_tolerance_deg:g}°; servo lag included). "
             "`hover/hover.png`: drift and tool error over time."] + ([video_note] if s.hw.plot else [])
    return StageReport("hover", "Hovering instead of docked: the same motion on thrusters (docs/hover.md)", [table],
                       res, notes)


def _hover_video(s: PipelineSettings, flow: Flow, run: hover.HoverRun, label: str, out: Path, res: dict) -> str:
    """``out/hover.mp4`` in the hw video's scene, camera and frames, and ``out/hover_frame.png``
    (also at ``hover.frame_png``): the frame at the gate of the largest tool error. Returns the
    summary note."""
    scene = _film_scene(s, flow)
    if scene is None:
        return "No video of the hovering run: no scene (run the plan stage or give a scenario)."
    try:
        video = hover.write_hover_video(run, scene, out / "hover.mp4", fps=VIDEO_FPS, size=VIDEO_SIZE)
        worst = run.gate_times[np.argmax(run.gate_tool_error)] if len(run.gate_times) else run.log.time[-1]
        still = hover.hover_frame(run, scene, float(min(worst, run.log.time[-1])), size=VIDEO_SIZE)
    except RuntimeError as e:  # no offscreen GL context on this machine
        log.warning("no video of the hovering run: %s", e)
        return f"No video of the hovering run: {e}."
    from PIL import Image

    paths = [out / "hover_frame.png"] + ([Path(s.hover.frame_png)] if s.hover.frame_png else [])
    for path in paths:
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(still).save(path, optimize=True)
    res["video_frames"], res["video_render_s"] = video.frames, video.seconds
    link = f"{out.name}/{video.path.name}"
    return (f"Video of the {label} run: [{link}]({link}) — the vehicle and the arm as simulated in the hw video's "
            "scene, camera and frames (compare side by side), with the docked hull's outline (white), the tool's "
            "target path (green: where the docked arm holds it) and its path so far (red), the current (blue "
            f"arrow) and the time and the tool error at the last gate; {video.fps:g} fps, {video.frames} frames, "
            f"rendered in {video.seconds:.1f} s. `{out.name}/hover_frame.png`: the frame at the gate of the largest "
            "tool error.")


def _plot_hover(runs: dict, path: Path) -> None:
    """Drift of the vehicle and tool error over time, one line per run → PNG."""
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
