"""``plan.json``: the joint-space plan that planning writes and the hardware runner executes.

Format (version 1; JSON object)::

    {
      "version": 1,
      "joint_names": ["G", "F", "E", "D", "C", "B"],
      "segments": [
        {"name": "0->2 pre-grasp",                  # free text, used in logs and errors
         "t": [0.0, 1.5, 3.0],                      # [s] from the segment's start, t[0] = 0, increasing
         "q": [[...6 rad...], [...], [...]],        # one row per time, joint order as joint_names
         "gripper": null},                          # or {"jaws_mm": 30.0}: set the jaws after the motion
        {"name": "open", "gripper": {"jaws_mm": 30.0}}   # a gripper-only step (no "t"/"q")
      ]
    }

Semantics: segments run in order. A motion visits every waypoint; between two waypoints all
joints move together (synchronised arrival) within the velocity and acceleration limits, taking
at least the planned time; at every waypoint the executor waits until every encoder is within
the gate threshold (thesis 4.6) before going on. After the motion, ``gripper`` (if given) drives
the jaws [mm, 0 … 35] and waits for them the same way. A segment's first waypoint must repeat
the previous segment's last one (continuity); the plan's first waypoint is where the arm must
already be. Joint angles are in rad, within the limits of docs/theory.md §1.3.

The hardware runner checks a plan against the arm's limits before any motion
(:func:`uvms_jax.hw.check_plan`).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["PLAN_VERSION", "Plan", "PlanError", "Segment", "load_plan", "parse_plan", "plan_to_dict"]

PLAN_VERSION = 1


class PlanError(ValueError):
    """A plan that must not run; the message lists every problem found."""


@dataclasses.dataclass(frozen=True)
class Segment:
    """One plan segment.

    Attributes:
      name: label for logs and errors.
      t: (k,) waypoint times from the segment start [s] (k may be 0 for a gripper-only step).
      q: (k, n_joints) waypoint joint angles [rad].
      jaws_mm: jaw opening to set after the motion [mm], or None.
    """

    name: str
    t: tuple[float, ...]
    q: tuple[tuple[float, ...], ...]
    jaws_mm: float | None = None


@dataclasses.dataclass(frozen=True)
class Plan:
    """A parsed plan: joint names (arm joints, in order) and segments."""

    joint_names: tuple[str, ...]
    segments: tuple[Segment, ...]

    def waypoints(self) -> list[tuple[int, int, tuple[float, ...]]]:
        """All ``(segment index, waypoint index, q)`` in execution order."""
        return [(i, k, q) for i, s in enumerate(self.segments) for k, q in enumerate(s.q)]


def _floats(x: Any, where: str) -> tuple[float, ...]:
    if not isinstance(x, Sequence) or isinstance(x, (str, bytes)):
        raise PlanError(f"{where}: expected a list of numbers, got {type(x).__name__}")
    out = []
    for v in x:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise PlanError(f"{where}: expected numbers, got {v!r}")
        out.append(float(v))
    return tuple(out)


def parse_plan(obj: Mapping[str, Any]) -> Plan:
    """Build a :class:`Plan` from the JSON object; raises PlanError on a malformed structure."""
    if not isinstance(obj, Mapping):
        raise PlanError(f"plan must be a JSON object, got {type(obj).__name__}")
    version = obj.get("version", PLAN_VERSION)
    if version != PLAN_VERSION:
        raise PlanError(f"unsupported plan version {version!r} (expected {PLAN_VERSION})")
    unknown = set(obj) - {"version", "joint_names", "segments", "meta"}
    if unknown:
        raise PlanError(f"unknown plan keys {sorted(unknown)}")
    names = obj.get("joint_names")
    if not isinstance(names, Sequence) or not all(isinstance(n, str) for n in names):
        raise PlanError("plan.joint_names must be a list of joint letters")
    segs = obj.get("segments")
    if not isinstance(segs, Sequence) or isinstance(segs, (str, bytes)) or not segs:
        raise PlanError("plan.segments must be a non-empty list")
    out = []
    for i, s in enumerate(segs):
        where = f"segment {i}"
        if not isinstance(s, Mapping):
            raise PlanError(f"{where}: expected an object")
        bad = set(s) - {"name", "t", "q", "gripper"}
        if bad:
            raise PlanError(f"{where}: unknown keys {sorted(bad)}")
        name = str(s.get("name", f"segment {i}"))
        where = f"segment {i} ({name})"
        t = _floats(s.get("t", []), f"{where}.t")
        q_raw = s.get("q", [])
        if not isinstance(q_raw, Sequence) or isinstance(q_raw, (str, bytes)):
            raise PlanError(f"{where}.q: expected a list of rows")
        q = tuple(_floats(row, f"{where}.q[{k}]") for k, row in enumerate(q_raw))
        if len(t) != len(q):
            raise PlanError(f"{where}: {len(t)} times but {len(q)} waypoints")
        for k, row in enumerate(q):
            if len(row) != len(names):
                raise PlanError(f"{where}.q[{k}]: {len(row)} values for {len(names)} joints")
        g = s.get("gripper")
        jaws = None
        if g is not None:
            if not isinstance(g, Mapping) or set(g) != {"jaws_mm"}:
                raise PlanError(f"{where}.gripper: expected null or {{\"jaws_mm\": number}}")
            jaws = _floats([g["jaws_mm"]], f"{where}.gripper.jaws_mm")[0]
        if not q and jaws is None:
            raise PlanError(f"{where}: neither waypoints nor a gripper step")
        out.append(Segment(name, t, q, jaws))
    return Plan(tuple(names), tuple(out))


def load_plan(path: str | Path) -> Plan:
    """Read and parse ``plan.json``; raises PlanError for unreadable or malformed files."""
    try:
        obj = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise PlanError(f"cannot read plan {path}: {e}") from e
    return parse_plan(obj)


def plan_to_dict(plan: Plan) -> dict[str, Any]:
    """The JSON object of ``plan`` (inverse of :func:`parse_plan`); a gripper-only step has
    no ``t``/``q``."""

    def segment(s: Segment) -> dict[str, Any]:
        motion = {"t": list(s.t), "q": [list(r) for r in s.q]} if s.q else {}
        return {"name": s.name, **motion, "gripper": None if s.jaws_mm is None else {"jaws_mm": s.jaws_mm}}

    return {"version": PLAN_VERSION, "joint_names": list(plan.joint_names),
            "segments": [segment(s) for s in plan.segments]}
