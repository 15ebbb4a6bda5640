"""The schema of an arm's settings and of an arm card (``uvms_jax/robot/descriptions/*.yaml``,
docs/robots.md): every key, its type and its allowed values, checked before the description is
read (:func:`check_arm`, :func:`read_card`).

Settings dataclasses of :mod:`uvms_jax.settings`, as the scenario schema
(:mod:`uvms_jax.plan._schema`): every number finite, sizes and speeds positive and within a
sanity limit, no unknown key. A refusal is a :class:`~uvms_jax.settings.SettingsError` naming
the card file and the key path (e.g. ``arm card my_arm.yaml: gripper.velocity: expected a value
in (0, 10], got -1.0``), every bad key in one line.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from uvms_jax.settings import SettingsError, check_keys, from_mapping, read_yaml, setting

__all__ = ["ArmKeys", "check_arm", "read_card"]

Vec3 = tuple[float, float, float]
# Sanity limits (SI units), far beyond any arm a vehicle carries: a link capsule of 0.5 m radius
# is a 1 m thick link; no jaws open faster than 10 m/s or wider than 1 m; no link displaces 1 m³.
MAX_LINK_RADIUS = 0.5  # [m]
MAX_JAWS_SPEED = 10.0  # [m/s]
MAX_JAWS_SIZE = 1.0  # [m]: the jaws' opening, a finger's edges
MAX_LINK_VOLUME = 1.0  # [m³]
PROTOCOLS = ("bpl",)  # the hardware runner speaks Blueprint Lab's Reach protocol
DEVICE_IDS = (1, 254)  # a BPL device id (0 and 255 are the broadcast ids)


@dataclasses.dataclass(frozen=True, kw_only=True)
class GripperKeys:
    """``gripper`` given in settings (a description without jaws): the jaws' ``joint`` name, its
    opening limits ``lower`` < ``upper`` [m], speed ``velocity`` [m/s], ``effort`` [N]."""

    joint: str
    lower: float = setting(ge=0, le=MAX_JAWS_SIZE)
    upper: float = setting(gt=0, le=MAX_JAWS_SIZE)
    velocity: float = setting(gt=0, le=MAX_JAWS_SPEED)
    effort: float = setting(0.0, ge=0)

    def __post_init__(self) -> None:
        if not self.lower < self.upper:
            raise ValueError(f"expected lower < upper [m], got lower {self.lower}, upper {self.upper}")


@dataclasses.dataclass(frozen=True, kw_only=True)
class BuoyancyKeys:
    """One link of ``buoyancy``: its displaced ``volume`` [m³] and centre of buoyancy ``cob``
    [m, in the link's frame]."""

    volume: float = setting(ge=0, le=MAX_LINK_VOLUME)
    cob: Vec3


@dataclasses.dataclass(frozen=True, kw_only=True)
class HardwareKeys:
    """``hardware``: the wire ``protocol`` and one device id per actuator (joint name → id)."""

    protocol: str = setting(choices=PROTOCOLS)
    device_ids: Mapping[str, int]

    def __post_init__(self) -> None:
        lo, hi = DEVICE_IDS
        bad = {k: v for k, v in self.device_ids.items() if not lo <= v <= hi}
        if bad:
            raise ValueError(f"device_ids: expected ids in {lo} … {hi}, got {bad}")
        if len(set(self.device_ids.values())) != len(self.device_ids):
            raise ValueError(f"device_ids: expected distinct ids, got {dict(self.device_ids)}")


@dataclasses.dataclass(frozen=True, kw_only=True)
class ArmKeys:
    """An arm's settings (:func:`uvms_jax.robot.robot_from_config`; a card holds all of them but
    ``card``): the keyword arguments of :func:`uvms_jax.robot.load_robot` by name, ``None``
    where not given (the loader's default)."""

    card: str | None = None
    description: str | None = None
    tip: str | None = None
    base: str | None = None
    gripper: str | GripperKeys | None = None
    gripper_velocity: float | None = setting(None, gt=0, le=MAX_JAWS_SPEED)
    finger_size: Vec3 | None = setting(None, gt=0, le=MAX_JAWS_SIZE)
    link_radius: float | None = setting(None, gt=0, le=MAX_LINK_RADIUS)
    buoyancy: Mapping[str, BuoyancyKeys] | None = None
    hardware: HardwareKeys | None = None
    name: str | None = None
    collision: str | None = setting(None, choices=("description", "capsules"))

    def given(self) -> dict[str, Any]:
        """The keys given (not ``None``), nested settings as plain mappings."""
        return {k: v for k, v in dataclasses.asdict(self).items() if v is not None}


def check_arm(mapping: Any, where: str = "arm") -> ArmKeys:
    """An arm's settings ``mapping`` checked against the schema (:class:`ArmKeys`).

    Raises:
      SettingsError: every bad key (unknown, of the wrong type, not finite, out of range),
        named by its key path under ``where``, in one message.
    """
    return from_mapping(ArmKeys, mapping, where)


def read_card(path: Path) -> ArmKeys:
    """The arm card at ``path``: a YAML mapping of arm settings (no ``card`` of its own), read
    with the package's bounded YAML loader and checked against the schema.

    Raises:
      SettingsError: (a ValueError) an unreadable file, malformed YAML, a repeated key, an
        alias bomb, or a bad key; one line starting ``arm card PATH``.
    """
    mapping = read_yaml(path, "arm card")
    if not isinstance(mapping, Mapping):
        raise SettingsError(f"arm card {path}: expected a mapping of arm settings, got {type(mapping).__name__}")
    if "card" in mapping:
        raise SettingsError(f"arm card {path}: card: a card must not name another card")
    try:
        check_keys(mapping, [f.name for f in dataclasses.fields(ArmKeys) if f.name != "card"])
        return check_arm(mapping, "")
    except SettingsError as e:
        raise SettingsError(f"arm card {path}: {e}") from None
