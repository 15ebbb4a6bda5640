"""``plan.json``: the joint-space plan that planning writes and the hardware runner executes.

Format (version 1; JSON object)::

    {
      "version": 1,
      "meta": {"gripper_steps": "jaws"},            # optional notes, kept as they are
      "joint_names": ["G", "F", "E", "D", "C", "B"],
      "arm": {"name": "my_arm", "dof": 6,           # optional: the arm the plan was made for
              "joint_names": [...], "gripper": {"joint": "A", "lower_m": 0.0, "upper_m": 0.035,
              "velocity_mps": 0.1}, "source": "...", "sha256": "..."},   # (uvms_jax.robot.Robot.record)
      "base_rpy": [3.14159, 0.0, 0.0],              # optional: the arm base's orientation in the
                                                    # world the plan was made for (URDF roll,
                                                    # pitch, yaw [rad]; sets gravity in simulation)
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
the jaws [mm, within the gripper's limits] and waits for them the same way. A segment's first waypoint must repeat
the previous segment's last one (continuity); the plan's first waypoint is where the arm must
already be. Joint angles are in rad, within the arm's limits.

``meta`` (optional) holds notes that the runner does not read. The planning stage records there how
the arm takes the gripper steps: ``gripper_steps: jaws``, or for an arm without a gripper
``{gripper_steps: dwell, dwell_s: …}``: its plan has, instead of each gripper step, a segment
where the arm holds still for ``dwell_s`` [s], named ``… (dwell: no gripper)``.

``arm`` (optional; plans written before it existed have none) is the ``record()`` of the
:class:`uvms_jax.robot.Robot` the plan was made for: its name, joint names (equal to the plan's),
gripper (joint name, opening limits [m], speed [m/s]; null for none), description source and
SHA-256. The hardware runner refuses to run a plan on another arm, and checks a plan against
the arm's limits before any motion (:func:`uvms_jax.hw.check_plan`).

**ROS-shaped trajectories.** :func:`to_joint_trajectory` writes a plan as a plain object shaped
like ``trajectory_msgs/JointTrajectory`` (no ROS needed) and :func:`from_joint_trajectory`
reads one back; :func:`load_plan` and :func:`save_plan` pick YAML (``.yaml``/``.yml``) or JSON by
the file suffix, and :func:`load_plan` tells the two formats apart by their keys::

    joint_names: [G, F, E, D, C, B, A]          # the gripper's joint (here A) only if the
                                                # plan has gripper steps
    points:
      - positions: [...rad..., jaws m]          # one value per joint name
        velocities: [0, 0, 0, 0, 0, 0, 0]       # [rad/s, m/s]
        time_from_start: {sec: 0, nanosec: 0}   # strictly increasing

- Waypoints: every waypoint becomes a point at its time from the plan's start; a segment's first
  waypoint, which repeats the previous one, is written once.
- Velocities are zero at every point: the plan moves rest to rest between waypoints (the
  synchronised profile of :mod:`uvms_jax.motion` has ``ds/dt = 0`` at both ends of every move,
  and the executor stops at each gate). A controller that interpolates with these velocities
  (cubic or quintic splines) therefore stays on the straight joint-space line between
  waypoints, the line the planner collision-checked.
- Gripper steps: the jaws are the gripper's prismatic joint in metres (the plan speaks
  millimetres); its name, limits and speed come from the plan's ``arm["gripper"]`` or from a
  gripper passed in (a :class:`uvms_jax.robot.Gripper`, a robot, or an ``arm["gripper"]``
  record). A gripper step is a point where the arm stands still and the jaws joint moves to
  the new opening, ``(upper - lower) / velocity`` of the jaws later (their full travel at
  their speed limit, e.g. 35 mm at 0.1 m/s: 0.35 s; the executor waits for the jaws' gate
  anyway).
  Before the first gripper step the jaws hold ``jaws_start_mm`` (by default the first step's
  opening). Reading back, a point where the arm stands still is a gripper step; so a plan with
  gripper steps that stands still at a motion waypoint, or starts with a gripper step, cannot be
  written. A plan with gripper steps and no gripper known cannot be written; read back without
  a gripper known, every joint is an arm joint. A plan without gripper steps (e.g. an arm
  without a gripper, which dwells instead) may stand still: a point that repeats the previous
  positions later, read back as such.
- What a JointTrajectory cannot hold is lost: segment names and the boundaries between two
  motions (a plan read back has one motion segment between gripper steps, named after its
  points), ``base_rpy``, ``arm`` (unless a robot is passed in) and ``meta``. Times
  keep nanosecond resolution. The motion itself (every waypoint, the time between waypoints,
  every gripper step) survives the round trip.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml

from uvms_jax.files import json_text, write_atomic
from uvms_jax.settings import load_yaml

__all__ = [
    "MAX_MOTION_S",
    "MAX_NESTING",
    "PLAN_VERSION",
    "Plan",
    "PlanError",
    "Segment",
    "from_joint_trajectory",
    "load_plan",
    "parse_arm",
    "parse_plan",
    "plan_to_dict",
    "save_plan",
    "to_joint_trajectory",
]

PLAN_VERSION = 1
# Sanity limit on a plan's total motion time (the sum of its segments' planned times) [s]: a
# pick-and-place intervention of the thesis plans a few minutes; a plan of more than an hour is
# a unit or typing error (1e9 s), never a plan to run unattended.
MAX_MOTION_S = 3600.0
# Deepest nesting of objects and lists in a plan file (plan.json has 4: plan → segments → q →
# row); deeper files are refused before they are parsed.
MAX_NESTING = 16


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
    """A parsed plan: joint names (arm joints, in order) and segments.

    Attributes:
      joint_names: arm joint letters, in the order of every waypoint's values.
      segments: the segments, in execution order.
      base_rpy: orientation of the arm's base in the world the plan was made for, URDF roll,
        pitch, yaw [rad] (``(π, 0, 0)``: hanging under a vehicle); None where not recorded. The
        simulated arm takes its gravity and buoyancy from it.
      arm: the ``record()`` of the robot the plan was made for (module docstring), or None
        where not recorded.
      meta: notes kept with the plan and not interpreted (module docstring), or None.
    """

    joint_names: tuple[str, ...]
    segments: tuple[Segment, ...]
    base_rpy: tuple[float, float, float] | None = None
    arm: dict | None = None
    meta: dict | None = None

    def __post_init__(self) -> None:
        if self.arm is not None:  # checked, and kept as plan.json holds it
            object.__setattr__(self, "arm", parse_arm(self.arm, self.joint_names))
        total = sum(s.t[-1] - s.t[0] for s in self.segments if s.t)
        if not total <= MAX_MOTION_S:  # NaN too
            raise PlanError(f"plan: total planned motion time {total:g} s is not within the sanity limit of "
                            f"{MAX_MOTION_S:g} s (planfile.MAX_MOTION_S)")

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
    if isinstance(version, bool) or version != PLAN_VERSION:  # true == 1 in Python, not in a plan
        raise PlanError(f"unsupported plan version {version!r} (expected {PLAN_VERSION})")
    unknown = set(obj) - {"version", "joint_names", "segments", "base_rpy", "arm", "meta"}
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
    base_rpy = obj.get("base_rpy")
    if base_rpy is not None:
        base_rpy = _floats(base_rpy, "plan.base_rpy")
        if len(base_rpy) != 3 or not all(math.isfinite(v) for v in base_rpy):
            raise PlanError(f"plan.base_rpy: expected 3 finite angles (roll, pitch, yaw) [rad], got {list(base_rpy)}")
    meta = obj.get("meta")
    if meta is not None and not isinstance(meta, Mapping):
        raise PlanError(f"plan.meta: expected an object, got {type(meta).__name__}")
    return Plan(tuple(names), tuple(out), base_rpy, parse_arm(obj.get("arm"), tuple(names)),
                None if meta is None else dict(meta))


# What an arm record must hold; any further keys a newer Robot.record() writes are kept as they are.
_ARM_KEYS = {"name", "dof", "joint_names", "gripper", "source", "sha256"}
_GRIPPER_KEYS = {"joint", "lower_m", "upper_m", "velocity_mps"}


def parse_arm(arm: Any, joint_names: Sequence[str] | None = None) -> dict | None:
    """Check a plan's ``arm`` record (``Robot.record()``) and return it as a plain dict.

    Raises:
      PlanError: not a mapping with at least the record's keys, wrong types, a gripper record
        without a finite opening interval and a positive speed, or joint names other than
        ``joint_names`` (the plan's).
    """
    if arm is None:
        return None
    if not isinstance(arm, Mapping) or not _ARM_KEYS <= set(arm):
        got = sorted(arm) if isinstance(arm, Mapping) else type(arm).__name__
        raise PlanError(f"plan.arm: expected an object with keys {sorted(_ARM_KEYS)}, got {got}")
    names = arm["joint_names"]
    if not isinstance(names, Sequence) or isinstance(names, str) or not all(isinstance(n, str) for n in names):
        raise PlanError("plan.arm.joint_names must be a list of joint names")
    if not all(isinstance(arm[k], str) for k in ("name", "source", "sha256")):
        raise PlanError("plan.arm: name, source and sha256 must be strings")
    if isinstance(arm["dof"], bool) or arm["dof"] != len(names):
        raise PlanError(f"plan.arm.dof {arm['dof']!r} is not the number of its joint names ({len(names)})")
    if joint_names is not None and tuple(names) != tuple(joint_names):
        raise PlanError(f"plan.arm.joint_names {list(names)} differ from plan.joint_names {list(joint_names)}")
    g = arm["gripper"]
    if g is not None:
        if not isinstance(g, Mapping) or set(g) != _GRIPPER_KEYS or not isinstance(g["joint"], str):
            raise PlanError(f"plan.arm.gripper: expected null or an object with keys {sorted(_GRIPPER_KEYS)}")
        lo, hi, v = _floats([g["lower_m"], g["upper_m"], g["velocity_mps"]], "plan.arm.gripper")
        if not (all(map(math.isfinite, (lo, hi, v))) and lo < hi and v > 0):
            raise PlanError(f"plan.arm.gripper: needs finite lower_m < upper_m and velocity_mps > 0, got {dict(g)}")
        g = {"joint": g["joint"], "lower_m": lo, "upper_m": hi, "velocity_mps": v}
    return {**arm, "name": arm["name"], "dof": int(arm["dof"]), "joint_names": list(names), "gripper": g,
            "source": arm["source"], "sha256": arm["sha256"]}


def _gripper_record(gripper: Any) -> dict | None:
    """``arm["gripper"]``'s record of a gripper given as a record (mapping), a
    :class:`uvms_jax.robot.Gripper` or a robot (its ``gripper``); None for None."""
    if gripper is None or isinstance(gripper, Mapping):
        return None if gripper is None else parse_arm(
            {"name": "", "dof": 0, "joint_names": [], "gripper": gripper, "source": "", "sha256": ""})["gripper"]
    if hasattr(gripper, "record") and hasattr(gripper, "gripper"):  # a robot
        return gripper.record()["gripper"]
    if all(hasattr(gripper, k) for k in ("joint", "lower", "upper", "velocity")):  # a Gripper
        return {"joint": gripper.joint, "lower_m": float(gripper.lower), "upper_m": float(gripper.upper),
                "velocity_mps": float(gripper.velocity)}
    raise TypeError(f"gripper must be a Gripper, a robot or an arm gripper record, got {type(gripper).__name__}")


_YAML_SUFFIXES = (".yaml", ".yml")
_NS_PER_S = 1_000_000_000
_MM_PER_M = 1000.0


def _jaws_step_s(g: Mapping[str, Any]) -> float:
    """Time between the point before a gripper step and the step's point: the jaws' full
    travel at their speed limit [s]."""
    return (g["upper_m"] - g["lower_m"]) / g["velocity_mps"]


def _is_joint_trajectory(obj: Any) -> bool:
    return isinstance(obj, Mapping) and "points" in obj and "segments" not in obj


def load_plan(path: str | Path, gripper: Any = None) -> Plan:
    """Read a plan file: ``plan.json`` or a JointTrajectory object (see the module docstring),
    as YAML (``.yaml``/``.yml``) or JSON (any other suffix).

    ``gripper`` (a Gripper, a robot, or an ``arm["gripper"]`` record) names the jaws' joint of
    a JointTrajectory (:func:`from_joint_trajectory`); a ``plan.json`` records its own.

    Raises:
      PlanError: unreadable file, malformed YAML/JSON, a key repeated in an object (the last
        would win without a word), nesting deeper than :data:`MAX_NESTING`, or a malformed plan
        or trajectory; one line.
    """
    path = Path(path)
    try:
        text = path.read_text()
        if path.suffix.lower() in _YAML_SUFFIXES:
            obj = load_yaml(text)  # bounded: repeated keys, aliases, nesting
        else:
            _check_nesting(text)
            obj = json.loads(text, object_pairs_hook=_unique_keys)
    except (OSError, UnicodeDecodeError, ValueError, yaml.YAMLError) as e:  # JSONDecodeError is a ValueError
        raise PlanError(f"cannot read plan {path}: {' '.join(str(e).split())}") from e
    return from_joint_trajectory(obj, gripper) if _is_joint_trajectory(obj) else parse_plan(obj)


def _check_nesting(text: str) -> None:
    """Raise ValueError for JSON ``text`` nested deeper than :data:`MAX_NESTING` (brackets
    outside strings), before a recursive parser meets it."""
    brackets = re.findall(r"[\[\]{}]", re.sub(r'"(?:[^"\\]|\\.)*"', "", text))
    depth = max(itertools.accumulate(1 if b in "[{" else -1 for b in brackets), default=0)
    if depth > MAX_NESTING:
        raise ValueError(f"nested {depth} levels deep; a plan has at most {MAX_NESTING}")


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object's dict; ValueError for a key that it repeats."""
    keys = [k for k, _ in pairs]
    dup = sorted({k for k in keys if keys.count(k) > 1})
    if dup:
        raise ValueError(f"repeated keys {dup} in one object (which one counts?)")
    return dict(pairs)


def save_plan(plan: Plan, path: str | Path, *, joint_trajectory: bool = False,
              jaws_start_mm: float | None = None, gripper: Any = None) -> None:
    """Write ``plan`` to ``path`` as ``plan.json``'s object or, with ``joint_trajectory``, as a
    JointTrajectory object (:func:`to_joint_trajectory`, with ``jaws_start_mm`` and
    ``gripper``); YAML for ``.yaml``/``.yml``, JSON otherwise (laid out by
    :func:`uvms_jax.files.json_text`); atomically (:func:`uvms_jax.files.write_atomic`).

    Raises:
      PlanError: the plan cannot be written as a JointTrajectory (see :func:`to_joint_trajectory`).
    """
    path = Path(path)
    obj = to_joint_trajectory(plan, jaws_start_mm, gripper) if joint_trajectory else plan_to_dict(plan)
    text = yaml.safe_dump(obj, sort_keys=False, default_flow_style=None) if path.suffix.lower() in _YAML_SUFFIXES \
        else json_text(obj) + "\n"
    write_atomic(path, text)


def _duration(t: float) -> dict[str, int]:
    """``builtin_interfaces/Duration`` of ``t`` [s] (t ≥ 0), rounded to the nanosecond."""
    ns = round(t * _NS_PER_S)
    return {"sec": ns // _NS_PER_S, "nanosec": ns % _NS_PER_S}


def to_joint_trajectory(plan: Plan, jaws_start_mm: float | None = None, gripper: Any = None) -> dict[str, Any]:
    """``plan`` as a ``trajectory_msgs/JointTrajectory``-shaped object (module docstring).

    Args:
      plan: the plan; its segment times must increase strictly (as ``hw.check_plan`` asks).
      jaws_start_mm: jaws opening before the first gripper step [mm]; None: that step's opening.
      gripper: the jaws (a Gripper, a robot, or an ``arm["gripper"]`` record); None: the
        plan's ``arm["gripper"]``. Needed only if the plan has gripper steps.

    Returns:
      ``{"joint_names": [...], "points": [{"positions", "velocities", "time_from_start"}]}``;
      ``(n + 1,)`` positions per point (``n`` without gripper steps) in rad (arm) and m (the
      jaws, last), velocities all zero, times ``{sec, nanosec}``.

    Raises:
      PlanError: a plan that starts with a gripper step, stands still at a motion waypoint
        while it has gripper steps, is not continuous between segments, has non-increasing
        times, already names a joint as the jaws, has gripper steps but no gripper known, or a
        ``jaws_start_mm`` outside the jaws' travel.
    """
    jaws = [s.jaws_mm for s in plan.segments if s.jaws_mm is not None]
    names = list(plan.joint_names)
    g = _gripper_record(gripper) if gripper is not None else (plan.arm or {}).get("gripper")
    if jaws:
        if g is None:
            arm = "no arm record" if plan.arm is None else f"arm {plan.arm['name']!r} has no gripper"
            raise PlanError(f"plan has gripper steps but no gripper is known ({arm}): pass the gripper or robot")
        if g["joint"] in names:
            raise PlanError(f"plan already has a joint {g['joint']!r}, the jaws' name")
        names.append(g["joint"])
    jaws_m = (jaws[0] if jaws_start_mm is None else jaws_start_mm) / _MM_PER_M if jaws else None
    if jaws and not g["lower_m"] <= jaws_m <= g["upper_m"]:
        raise PlanError(f"jaws_start_mm {jaws_start_mm} outside [{g['lower_m'] * _MM_PER_M}, "
                        f"{g['upper_m'] * _MM_PER_M}] mm")
    points: list[dict[str, Any]] = []
    q_last: tuple[float, ...] | None = None
    t_last = 0.0  # time from the plan's start of the last point [s]

    def add(q: tuple[float, ...], t: float) -> None:
        nonlocal q_last, t_last
        positions = list(q) + ([jaws_m] if jaws else [])
        points.append({"positions": positions, "velocities": [0.0] * len(positions),
                       "time_from_start": _duration(t)})
        q_last, t_last = q, t

    for i, s in enumerate(plan.segments):
        where = f"segment {i} ({s.name})"
        if any(b <= a for a, b in zip(s.t, s.t[1:])):
            raise PlanError(f"{where}: times must increase strictly, got {list(s.t)}")
        t0 = t_last
        for k, (t, q) in enumerate(zip(s.t, s.q)):
            if q_last is None:
                add(q, t0 + t - s.t[0])
            elif k == 0:
                if q != q_last:
                    raise PlanError(f"{where}: first waypoint does not repeat the previous one")
            elif q == q_last and jaws:
                raise PlanError(f"{where}.q[{k}]: the arm stands still, which a JointTrajectory "
                                "reads as a gripper step")
            else:
                add(q, t0 + t - s.t[0])
        if s.jaws_mm is not None:
            if q_last is None:
                raise PlanError(f"{where}: the plan starts with a gripper step, before any arm position")
            jaws_m = s.jaws_mm / _MM_PER_M
            add(q_last, t_last + _jaws_step_s(g))
    return {"joint_names": names, "points": points}


def _nanoseconds(d: Any, where: str) -> int:
    if not isinstance(d, Mapping) or set(d) != {"sec", "nanosec"}:
        raise PlanError(f"{where}: expected {{sec: int, nanosec: int}}, got {d!r}")
    sec, nsec = d["sec"], d["nanosec"]
    if any(isinstance(v, bool) or not isinstance(v, int) for v in (sec, nsec)) or not 0 <= nsec < _NS_PER_S:
        raise PlanError(f"{where}: sec must be an integer and nanosec an integer in [0, 1e9), got {d!r}")
    return sec * _NS_PER_S + nsec


def from_joint_trajectory(obj: Mapping[str, Any], gripper: Any = None) -> Plan:
    """A :class:`Plan` from a ``trajectory_msgs/JointTrajectory``-shaped object (module docstring).

    The gripper's joint (``gripper``: a Gripper, a robot, or an ``arm["gripper"]`` record), if
    present, is the jaws [m]; every other name is an arm joint, in the given order. Without a
    gripper every name is an arm joint. Given a robot, the plan records it as its ``arm``.
    Velocities, accelerations and efforts are checked for length and otherwise ignored: the
    executor times every move itself. ``header`` is ignored.

    Raises:
      PlanError: a malformed object (missing or unknown keys, wrong lengths, non-numbers,
        times not strictly increasing) or a jaws value that is not finite.
    """
    if not isinstance(obj, Mapping):
        raise PlanError(f"JointTrajectory must be an object, got {type(obj).__name__}")
    unknown = set(obj) - {"header", "joint_names", "points"}
    if unknown:
        raise PlanError(f"JointTrajectory: unknown keys {sorted(unknown)}")
    names = obj.get("joint_names")
    if (not isinstance(names, Sequence) or isinstance(names, (str, bytes)) or not names
            or not all(isinstance(n, str) for n in names) or len(set(names)) != len(names)):
        raise PlanError(f"JointTrajectory.joint_names must be a non-empty list of distinct names, got {names!r}")
    pts = obj.get("points")
    if not isinstance(pts, Sequence) or isinstance(pts, (str, bytes)) or not pts:
        raise PlanError("JointTrajectory.points must be a non-empty list")
    names = list(names)
    g = _gripper_record(gripper)
    i_jaws = names.index(g["joint"]) if g is not None and g["joint"] in names else None
    arm = [i for i in range(len(names)) if i != i_jaws]
    if not arm:
        raise PlanError("JointTrajectory.joint_names has no arm joint")
    rows: list[tuple[int, tuple[float, ...], float | None]] = []  # (time [ns], arm q [rad], jaws [mm])
    for k, p in enumerate(pts):
        where = f"JointTrajectory.points[{k}]"
        if not isinstance(p, Mapping):
            raise PlanError(f"{where}: expected an object")
        bad = set(p) - {"positions", "velocities", "accelerations", "effort", "time_from_start"}
        if bad:
            raise PlanError(f"{where}: unknown keys {sorted(bad)}")
        pos = _floats(p.get("positions"), f"{where}.positions")
        for key in ("positions", "velocities", "accelerations", "effort"):
            vals = pos if key == "positions" else _floats(p.get(key, []), f"{where}.{key}")
            if vals and len(vals) != len(names) or (key == "positions" and not vals):
                raise PlanError(f"{where}.{key}: {len(vals)} values for {len(names)} joints")
        if not all(math.isfinite(v) for v in pos):
            raise PlanError(f"{where}.positions: values must be finite, got {list(pos)}")
        ns = _nanoseconds(p.get("time_from_start"), f"{where}.time_from_start")
        if rows and ns <= rows[-1][0]:
            raise PlanError(f"{where}.time_from_start must be later than the previous point's")
        jaws = None if i_jaws is None else pos[i_jaws] * _MM_PER_M
        rows.append((ns, tuple(pos[i] for i in arm), jaws))

    segments: list[Segment] = []
    run: list[int] = [0]  # point indices of the motion being collected

    def close_motion() -> None:
        if run:
            t0 = rows[run[0]][0]
            segments.append(Segment(f"points {run[0]}-{run[-1]}", tuple((rows[j][0] - t0) / _NS_PER_S for j in run),
                                    tuple(rows[j][1] for j in run)))

    for k in range(1, len(rows)):
        if rows[k][1] == rows[k - 1][1] and i_jaws is not None:  # the arm stands still: a jaws step
            close_motion()
            segments.append(Segment(f"jaws {rows[k][2]:g} mm", (), (), rows[k][2]))
            run = []
        else:
            run = run or [k - 1]  # a motion after a jaws step starts where the arm stands
            run.append(k)
    close_motion()
    joint_names = tuple(names[i] for i in arm)
    record = gripper.record() if hasattr(gripper, "record") else None
    if record is not None and tuple(record["joint_names"]) != joint_names:
        raise PlanError(f"JointTrajectory arm joints {list(joint_names)} are not robot "
                        f"{record['name']!r}'s {record['joint_names']}")
    return Plan(joint_names, tuple(segments), arm=parse_arm(record, joint_names))


def plan_to_dict(plan: Plan) -> dict[str, Any]:
    """The JSON object of ``plan`` (inverse of :func:`parse_plan`); a gripper-only step has
    no ``t``/``q``."""

    def segment(s: Segment) -> dict[str, Any]:
        motion = {"t": list(s.t), "q": [list(r) for r in s.q]} if s.q else {}
        return {"name": s.name, **motion, "gripper": None if s.jaws_mm is None else {"jaws_mm": s.jaws_mm}}

    base = {} if plan.base_rpy is None else {"base_rpy": list(plan.base_rpy)}
    arm = {} if plan.arm is None else {"arm": parse_arm(plan.arm, plan.joint_names)}
    meta = {} if plan.meta is None else {"meta": dict(plan.meta)}
    return {"version": PLAN_VERSION, **meta, "joint_names": list(plan.joint_names), **arm, **base,
            "segments": [segment(s) for s in plan.segments]}
