"""The hover stage: the scheduled plan's motion over BPL with the vehicle hovering at the docked
pose (:func:`uvms_jax.hover.run_hover`, :func:`uvms_jax.hover.write_hover`)."""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

from uvms_jax import hover, progress
from uvms_jax.pipeline._precheck import vehicle_hull
from uvms_jax.pipeline._report import StageReport
from uvms_jax.pipeline._settings import PipelineSettings
from uvms_jax.pipeline.stages._flow import VIDEO_FPS, VIDEO_SIZE, Flow
from uvms_jax.pipeline.stages._flow import film_scene as _film_scene

__all__ = ["run"]


def run(s: PipelineSettings, out: Path, flow: Flow) -> StageReport:
    """The scheduled plan's motion over BPL with the vehicle hovering at the docked pose instead
    of fixed to it: the vehicle built once from the docking hull, run and written by the hover
    package."""
    hs, scene = s.hover, s.docking.scene
    vehicle = dataclasses.replace(hs.vehicle, size=tuple(vehicle_hull(scene).size), mount_xyz=tuple(scene.mount_xyz),
                                  mount_rpy=tuple(scene.mount_rpy))
    film_in = _film_scene(s, flow) if s.hw.plot else None
    film = None if film_in is None else functools.partial(hover.film_hover, scene=film_in, path=out / "hover.mp4",
                                                          fps=VIDEO_FPS, size=VIDEO_SIZE)
    with progress.bar(total=1 + any(hs.current) * (1 + hs.coordinate), desc="hover", unit="run") as bar:
        stage = hover.run_hover(flow.robot, flow.plan, flow.pose, vehicle, current=hs.current, controller=hs.controller,
                                whole_body=hs.whole_body if hs.coordinate else None, navigation=hs.navigation,
                                tool_tolerance_m=hs.tool_tolerance_m, tool_tolerance_deg=hs.tool_tolerance_deg,
                                config=s.hw.executor, sim=s.hw.sim, progress=lambda label: bar.update(1), film=film)
    docked = flow.reports["hw"].results if "hw" in flow.reports else None
    res, table, notes = hover.write_hover(stage, out, frame_png=hs.frame_png, docked=docked)
    return StageReport("hover", "Hovering instead of docked: the same motion on thrusters (docs/hover.md)", [table],
                       res, notes)
