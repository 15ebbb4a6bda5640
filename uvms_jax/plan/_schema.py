"""The schema of a scenario file (``configs/scenario/*.yaml``): every key, its type and its
allowed values, checked before anything is built from it (:func:`check_scenario`).

Settings dataclasses of :mod:`uvms_jax.settings` (the package's one settings mechanism): every
number finite, sizes positive, names unique, references (an object's table, a base's ``fits``)
resolving, no unknown key. A refusal is a :class:`~uvms_jax.settings.SettingsError` naming the
key path (e.g. ``scenario.tables[1].size[2]``) and what is allowed, every bad key in one line.
docs/scenarios.md lists the keys and their ranges.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from typing import Any

from uvms_jax.settings import from_mapping, setting

__all__ = ["MOUNT_KEYS", "ScenarioKeys", "check_scenario", "node_numbers"]

Vec3 = tuple[float, float, float]
# Sanity ranges of the materials (SI units): water and everything an arm lifts under water is
# lighter than osmium (22 590 kg/m³); water densities up to a saturated brine's; gravity up to
# Jupiter's 24.8 m/s² (0: weightless, a check of the buoyancy-free case).
MAX_DENSITY = 25_000.0  # [kg/m³]
MAX_WATER_DENSITY = 1_300.0  # [kg/m³]
MAX_GRAVITY = 25.0  # [m/s²]
# Names of tables, objects, bases and obstacles: they name MuJoCo geoms (and ':' joins a node's
# number and name there).
NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*")

#: Keys of a scenario's ``arm`` mapping that place the arm in the scene; the others are the
#: arm's own settings (:func:`uvms_jax.robot.robot_from_config`: ``card``, ``description``, …).
MOUNT_KEYS = ("mount_pos", "mount_rpy", "mount_size", "jaws_open")


def _needs(kind: str, shape: str, given: Mapping[str, Any], needed: tuple[str, ...], optional: tuple[str, ...]) -> None:
    """Raise ValueError unless exactly ``needed`` of the shape keys ``optional`` are given."""
    missing = [k for k in needed if given[k] is None]
    extra = [k for k in optional if k not in needed and given[k] is not None]
    if missing or extra:
        raise ValueError(f"{kind} shape {shape!r} takes {', '.join(needed) or 'none of ' + ', '.join(optional)}"
                         f"{'; missing ' + ', '.join(missing) if missing else ''}"
                         f"{'; not ' + ', '.join(extra) if extra else ''}")


@dataclasses.dataclass(frozen=True, kw_only=True)
class CageKeys:
    """``cage``: the aluminium-profile cage (null: open water). Sizes [m]."""

    size: Vec3 = setting(gt=0)
    profile: float = setting(gt=0)
    ceiling_thickness: float = setting(gt=0)


@dataclasses.dataclass(frozen=True, kw_only=True)
class MountKeys:
    """The mount keys of ``arm`` (:data:`MOUNT_KEYS`): the base link's position [m] and roll,
    pitch, yaw [rad] in the world, the mounting plate's size [m], the open jaws' gap [m]."""

    mount_pos: Vec3
    mount_rpy: Vec3
    mount_size: Vec3 = setting(gt=0)
    jaws_open: float = setting(ge=0, le=1)


@dataclasses.dataclass(frozen=True, kw_only=True)
class TableKeys:
    """One of ``tables``: a box, centre ``pos`` [m], full ``size`` [m], ``rpy`` [rad]."""

    name: str
    pos: Vec3
    size: Vec3 = setting(gt=0)
    rpy: Vec3 = (0.0, 0.0, 0.0)


_OBJECT_DIMS = {"box": ("size",), "cylinder": ("radius", "height"), "hex_prism": ("edge", "height")}


@dataclasses.dataclass(frozen=True, kw_only=True)
class ObjectKeys:
    """One of ``objects``: a pick object on ``table`` at (u, v) of its top [m], ``yaw`` [rad];
    ``shape`` box (``size``), cylinder (``radius``, ``height``) or hex_prism (``edge``,
    ``height``) [m]; ``node`` its task-graph number (default: its place in the file)."""

    name: str
    shape: str = setting(choices=tuple(_OBJECT_DIMS))
    table: str
    at: tuple[float, float]
    yaw: float = 0.0
    node: int | None = setting(None, ge=1)
    size: Vec3 | None = setting(None, gt=0)
    radius: float | None = setting(None, gt=0)
    height: float | None = setting(None, gt=0)
    edge: float | None = setting(None, gt=0)

    def __post_init__(self) -> None:
        dims = ("size", "radius", "height", "edge")
        _needs("object", self.shape, {k: getattr(self, k) for k in dims}, _OBJECT_DIMS[self.shape], dims)


@dataclasses.dataclass(frozen=True, kw_only=True)
class BaseKeys:
    """One of ``bases``: a base plate of full ``size`` [m] on ``table`` at (u, v) [m], ``yaw``
    [rad]; ``fits``: the objects it takes (names or node numbers)."""

    name: str
    size: Vec3 = setting(gt=0)
    table: str
    at: tuple[float, float]
    yaw: float = 0.0
    node: int | None = setting(None, ge=1)
    fits: tuple[int | str, ...]


_OBSTACLE_DIMS = {"box": ("size",), "cylinder": ("radius", "height"), "sphere": ("radius",),
                  "capsule": ("radius", "length"), "mesh": ("file",)}


@dataclasses.dataclass(frozen=True, kw_only=True)
class ObstacleKeys:
    """One of ``obstacles`` (:class:`uvms_jax.plan.Obstacle`): ``shape`` box (``size``),
    cylinder (``radius``, ``height``), sphere (``radius``), capsule (``radius``, ``length``) or
    mesh (``file``, times ``scale``) [m], at ``pos`` [m], ``rpy`` [rad] or ``quat`` (a unit
    quaternion w, x, y, z)."""

    name: str
    shape: str = setting(choices=tuple(_OBSTACLE_DIMS))
    pos: Vec3
    rpy: Vec3 = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] | None = None
    size: Vec3 | None = setting(None, gt=0)
    radius: float | None = setting(None, gt=0)
    height: float | None = setting(None, gt=0)
    length: float | None = setting(None, gt=0)
    file: str | None = setting(None, file=True)
    scale: float | None = setting(None, gt=0)

    def __post_init__(self) -> None:
        dims = ("size", "radius", "height", "length", "file")
        _needs("obstacle", self.shape, {k: getattr(self, k) for k in dims}, _OBSTACLE_DIMS[self.shape], dims)
        if self.scale is not None and self.shape != "mesh":
            raise ValueError(f"obstacle shape {self.shape!r} takes no scale (a mesh's)")
        if self.quat is not None and (abs(sum(v * v for v in self.quat) - 1.0) > 1e-6 or any(self.rpy)):
            raise ValueError(f"obstacle {self.name!r}: quat must be a unit quaternion (w, x, y, z), given instead "
                             f"of rpy; got {list(self.quat)}")


@dataclasses.dataclass(frozen=True, kw_only=True)
class GraspKeys:
    """``grasp``: the tool stops ``standoff`` above an object's top face; pre- and post-poses
    back off by ``approach`` [m]."""

    standoff: float = setting(0.05, ge=0, le=1)
    approach: float = setting(0.08, gt=0, le=1)


@dataclasses.dataclass(frozen=True, kw_only=True)
class ScenarioKeys:
    """A scenario file's keys (module docstring; docs/scenarios.md). ``arm`` holds the mount
    (:class:`MountKeys`) and the arm's own settings, which the arm's loader checks."""

    name: str = ""
    cage: CageKeys | None = None
    arm: Mapping[str, Any]
    tables: tuple[TableKeys, ...]
    objects: tuple[ObjectKeys, ...]
    bases: tuple[BaseKeys, ...]
    obstacles: tuple[ObstacleKeys, ...] = ()
    object_density: float = setting(gt=0, le=MAX_DENSITY)
    water_density: float = setting(ge=0, le=MAX_WATER_DENSITY)
    gravity: float = setting(ge=0, le=MAX_GRAVITY)
    start_q: tuple[float, ...] | None = None
    grasp: GraspKeys = GraspKeys()

    def __post_init__(self) -> None:
        for key in ("tables", "objects", "bases"):
            if not getattr(self, key):
                raise ValueError(f"{key}: expected at least one, got none")
        tables = [t.name for t in self.tables]
        for x in (*self.objects, *self.bases):
            if x.table not in tables:
                raise ValueError(f"{x.name!r}: table {x.table!r} is not one of the tables {tables}")
        names = [*tables, *(x.name for x in (*self.obstacles, *self.objects, *self.bases))]
        bad = [n for n in names if not NAME.fullmatch(n)]
        if bad:
            raise ValueError(f"names {bad}: expected letters, digits, '_', '.' and '-', starting with a letter, "
                             "digit or '_'")
        _unique("table and obstacle", [*tables, *(o.name for o in self.obstacles)])
        _unique("object and base", [x.name for x in (*self.objects, *self.bases)])
        nodes = node_numbers(self)
        if len(set(nodes.values())) != len(nodes):
            raise ValueError(f"object and base node numbers must be unique, got {nodes}")
        objects = {o.name: nodes[o.name] for o in self.objects}
        for b in self.bases:
            bad = [f for f in b.fits if f not in (objects if isinstance(f, str) else objects.values())]
            if not b.fits or bad:
                raise ValueError(f"base {b.name!r}: fits {list(b.fits)}: expected objects by name or node, "
                                 f"{objects}{'; unknown ' + str(bad) if bad else ''}")


def _unique(what: str, names: list[str]) -> None:
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"{what} names must be unique; repeated: {dup}")


def check_scenario(mapping: Any, where: str = "scenario") -> ScenarioKeys:
    """The scenario ``mapping`` checked against the schema (:class:`ScenarioKeys`, the mount in
    ``arm``: :class:`MountKeys`).

    Raises:
      SettingsError: every bad key (unknown, missing, of the wrong type, not finite, out of
        range, a repeated name, a reference that does not resolve), named by its key path under
        ``where``, in one message.
    """
    keys = from_mapping(ScenarioKeys, mapping, where)
    from_mapping(MountKeys, {k: v for k, v in keys.arm.items() if k in MOUNT_KEYS}, f"{where}.arm")
    return keys


def node_numbers(keys: ScenarioKeys) -> dict[str, int]:
    """Every object's and base's task-graph node by name: the given numbers, or by default the
    objects 1 … k and the bases k + 1 … in the file's order."""
    items = [*keys.objects, *keys.bases]
    return {x.name: x.node if x.node is not None else i + 1 for i, x in enumerate(items)}
