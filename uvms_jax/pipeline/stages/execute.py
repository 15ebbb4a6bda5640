"""The hw stage: the scheduled plan (or ``hw.plan``) checked and executed on the simulated arm
(``hw.run_plan``), its log, its ROS-shaped trajectory and a video of the run."""

from __future__ import annotations

import dataclasses
import logging
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from uvms_jax import hw, planfile, progress
from uvms_jax import plan as planning
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.pipeline.stages._flow import VIDEO_FPS, VIDEO_SIZE, Flow, film_scene
from uvms_jax.text import md_table
from uvms_jax.video import VideoInfo

__all__ = ["run"]

log = logging.getLogger(__name__)


def run(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """Dry-run check, then execution of the scheduled plan (or ``hw.plan``) on the simulated arm."""
    hs = s.hw
    if hs.plan is not None:
        the_plan, source = planfile.load_plan(hs.plan), hs.plan
    elif flow.plan is not None:
        the_plan, source = flow.plan, flow.plan_source
    else:
        raise ValueError("the hw stage needs a plan: run the plan and schedule stages, or set hw.plan")
    # The simulated arm's gravity and buoyancy follow the base the plan was made for.
    sim = hs.sim if the_plan.base_rpy is None else dataclasses.replace(hs.sim, base_rpy=the_plan.base_rpy)
    with progress.bar(total=len(the_plan.segments), desc="hw", unit="seg") as bar:
        try:
            hw_run = hw.run_plan(the_plan, flow.robot, link=hs.link, config=hs.executor, sim=sim,
                                 progress=lambda i, n, name: bar.update(i - bar.n))  # i: segments finished
        except hw.RunInterrupted as stop:  # the arm was told to hold: keep what it did
            hw.write_run(stop.run, out, plot=False, plan_path=source)
            raise
        if hw_run.ok:
            bar.update(bar.total - bar.n)
    # The video renders in a thread of its own while the run's files are written: it waits mostly
    # on OpenGL and ffmpeg, which leave Python's lock to the plots.
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="hw-film") as pool:
        filming = pool.submit(_run_video, s, flow, hw_run.log, out) if hs.plot and hw_run.log.rows else None
        res = hw.write_run(hw_run, out, plot=hs.plot, plan_path=source)
        # The plan as a ROS-shaped JointTrajectory: what another arm's own controller executes.
        planfile.save_plan(the_plan, out / "joint_trajectory.yaml", joint_trajectory=True, gripper=flow.robot)
        filmed = None if filming is None else filming.result()
    if not hw_run.ok:
        log.warning("simulated run aborted (arm told to hold): %s", hw_run.result.reason)
    clock = "virtual clock" if hs.link == "loopback" else "real time"
    r, c = hw_run.result, hw_run.check
    table = md_table(
        ["plan", "segments", "waypoints", "estimated motion [s]", "result", "gates", "max gate error [rad]",
         "max gate error [mm]", f"run time ({clock}) [s]", "wall [s]", "demands outside limits"],
        [[f"`{Path(source).name}`", c.n_segments, c.n_waypoints, c.estimated_s, r.reason, len(r.gates),
          res["max_gate_error_rad"], res["max_gate_error_mm"], r.duration_s, hw_run.wall_s,
          hw_run.sim.limit_violations]])
    notes = [f"Link: {hs.link} ({clock}); reached-gate threshold {hs.executor.gate_threshold_rad} rad "
             "(thesis 4.6: every encoder within the threshold before the next motion). The thesis validated its "
             "real-arm runs with motion capture (~2 mm); `run.csv` logs commanded vs measured states for the same "
             "comparison. Same plan on a real arm: `uvms-hw run PLAN --dry-run`, then `--udp 192.168.2.3:6789`; "
             "`joint_trajectory.yaml`: the plan as a ROS-shaped JointTrajectory for any arm's own controller."]
    if filmed is not None:
        note, video = filmed
        notes.append(note)
        if video is not None:
            res["video_frames"], res["video_render_s"] = video.frames, video.seconds
    return StageReport("hw", f"Execution on the simulated {flow.robot.name} (docs/theory.md §6, thesis 4.6)", [table],
                       res, notes)


def _run_video(s: PipelineSettings, flow: Flow, run_log: hw.RunLog, out: Path) -> tuple[str, VideoInfo | None]:
    """``out/run.mp4``: the measured run in the planning stage's scene, else the scenario's
    (the example plan was planned in the thesis cage of ``configs/scenario/thesis_cage.yaml``);
    returns the summary note and the video (None: none made)."""
    scene = film_scene(s, flow)
    if scene is None:
        return "No video of the run: no scene (run the plan stage or give a scenario).", None
    t, q = run_log.measured(scene.robot.joint_names)
    if len(t) == 0:
        return "No video of the run: no complete measured state was logged.", None
    try:
        video = planning.render_run_video(scene, t, q, out / "run.mp4", fps=VIDEO_FPS, size=VIDEO_SIZE)
    except RuntimeError as e:  # no offscreen GL context on this machine
        log.warning("no video of the run: %s", e)
        return f"No video of the run: {e}.", None
    link = f"{out.name}/{video.path.name}"
    return (f"Video of the run: [{link}]({link}) — measured joint angles in the MuJoCo scene, {video.fps:g} fps, "
            f"{VIDEO_SIZE[0]}×{VIDEO_SIZE[1]}, {video.frames} frames, rendered offscreen in {video.seconds:.1f} s "
            "(arm only: the jaws' opening and the carried objects are not drawn).", video)
