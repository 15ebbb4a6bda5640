"""OMPL's geometric planners by name, with their parameters from a config.

Every planner class of ``ompl.geometric`` can be named (``RRTConnect``, ``BKPIECE1``, ``PRM``,
``RRTstar``, ``BITstar``, ``FMT``, …). Its parameters are its setters with one number or flag:
``setRange(distance)`` is the parameter ``range``, ``setGoalBias`` is ``goal_bias``,
``setMaxNearestNeighbors`` is ``max_nearest_neighbors``. Lengths (``range``) are Euclidean
distances in joint space [rad]. (The bindings cannot return OMPL's own ``ParamSet``, hence the
setters.)
"""

from __future__ import annotations

import functools
import re
from collections.abc import Mapping
from typing import Any

from ompl import base as ob
from ompl import geometric as og

__all__ = ["joint_space", "make_planner", "ompl_planners", "planner_parameters"]

_SETTER = re.compile(r"^set\w*\(self, \w+: (float|int|bool)\) -> None")
_TYPES = {"float": float, "int": int, "bool": bool}
# Left out: destroying an AORRTC planner segfaults in the Python bindings of OMPL 2.0.1.
_UNUSABLE = frozenset({"AORRTC"})


def joint_space(lower, upper) -> tuple:
    """OMPL's joint space of the box ``lower``–``upper`` ``(n,)`` [rad or m] and a planning setup
    on it: ``(space, SimpleSetup, SpaceInformation)``."""
    n = len(lower)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(lower[i]))
        bounds.setHigh(i, float(upper[i]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    return space, ss, ss.getSpaceInformation()


def _snake(name: str) -> str:
    """``GoalBias`` → ``goal_bias``, ``ExtendedFMT`` → ``extended_fmt``."""
    return re.sub(r"(?<=[a-z0-9])(?=[A-Z])|(?<=[A-Z])(?=[A-Z][a-z])", "_", name).lower()


@functools.cache
def ompl_planners() -> tuple[str, ...]:
    """Names of every geometric planner of the installed OMPL, sorted (less any known to crash
    in the bindings)."""
    return tuple(sorted(n for n in dir(og) if n != "Planner" and n not in _UNUSABLE
                        and isinstance(getattr(og, n), type) and issubclass(getattr(og, n), ob.Planner)))


def planner_parameters(name: str) -> dict[str, type]:
    """Parameter name → type (float, int or bool) of planner ``name``.

    Raises:
      ValueError: unknown planner (the valid names are listed).
    """
    return {k: t for k, (_, t) in _setters(name).items()}


@functools.cache
def _setters(name: str) -> dict[str, tuple[str, type]]:
    cls = _planner_class(name)
    out = {}
    for attr in dir(cls):
        if attr.startswith("set") and attr not in dir(ob.Planner):
            m = _SETTER.match((getattr(cls, attr).__doc__ or "").strip())
            if m:
                out[_snake(attr[3:])] = (attr, _TYPES[m.group(1)])
    return out


def _planner_class(name: str) -> type:
    if name not in ompl_planners():
        raise ValueError(f"unknown planner {name!r} (OMPL's geometric planners: {', '.join(ompl_planners())})")
    return getattr(og, name)


def check_parameters(name: str, params: Mapping[str, Any]) -> None:
    """Raise ValueError naming an unknown parameter of planner ``name`` or a value of the
    wrong type, with the valid parameters."""
    valid = planner_parameters(name)
    for key, value in params.items():
        if key not in valid:
            raise ValueError(f"planner {name} has no parameter {key!r} "
                             f"(its parameters: {', '.join(f'{k}: {t.__name__}' for k, t in valid.items()) or 'none'})")
        t = valid[key]
        ok = isinstance(value, bool) if t is bool else isinstance(value, (int, float)) and not isinstance(value, bool)
        if not ok or (t is int and float(value) != int(value)):
            raise ValueError(f"planner {name}: parameter {key!r} must be {t.__name__}, got {value!r}")


def make_planner(name: str, si, params: Mapping[str, Any] | None = None):
    """The OMPL planner ``name`` on space information ``si`` with ``params`` set.

    Raises:
      ValueError: unknown planner or parameter, or a value of the wrong type (all named).
    """
    cls = _planner_class(name)
    params = dict(params or {})
    check_parameters(name, params)
    planner = cls(si)
    setters = _setters(name)
    for key, value in params.items():
        setter, kind = setters[key]
        getattr(planner, setter)(kind(value))
    return planner
