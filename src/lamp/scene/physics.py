"""The physics of a scene: what a user's robots and loads really are, set in the scene file.

Scene format (``lamp-scene/1``, all optional, additive)::

    physics: {contact_friction: 0.5, ground_damping: 30.0}
    robots:  {speed: 0.25, force_limit: 60.0, ...}
    objects: [{..., mass: 1.0, friction: 0.5}]

This module owns the defaults (the simulator's calibrated values: a file without these
keys means what it always meant) and the ranges a value must lie in (the ranges the
simulator was checked for; beyond them a scene is refused naming the field and the
range, not run into an unstable simulation). ``lamp.sim.mjcf`` and ``lamp.sim.simulator``
read :class:`Physics` and the per-object :class:`ObjectPhysics` where the simulator is
built.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

from lamp.geometry.team import DEFAULT_TEAM

__all__ = ["DEFAULT_PHYSICS", "OBJECT_RANGES", "PHYSICS_RANGES", "ObjectPhysics", "Physics",
           "check_range"]

#: Valid (lowest, highest) value per field, bounds excluded below and included above:
#: friction is a Coulomb coefficient, damping N s/m per kg of object mass, speed m/s,
#: force N per axis, mass kg.
PHYSICS_RANGES: dict[str, tuple[float, float]] = {
    "contact_friction": (0.0, 2.0),
    "ground_damping": (0.0, 500.0),
    "robot_speed": (0.0, 2.0),
    "robot_force_limit": (0.0, 1000.0),
}
OBJECT_RANGES: dict[str, tuple[float, float]] = {
    "mass": (0.0, 100.0),
    "friction": (0.0, 2.0),
}


def check_range(name: str, value: Any, low: float, high: float) -> str | None:
    """Why ``value`` is not a number in (``low``, ``high``] (None when it is)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return f"must be a finite number, got {value!r}"
    if not low < value <= high:
        return f"must be in ({low:g}, {high:g}], got {value:g}"
    return None


def _validate(obj: Any, ranges: dict[str, tuple[float, float]]) -> None:
    for f in fields(obj):
        value = getattr(obj, f.name)
        if value is None:
            continue
        why = check_range(f.name, value, *ranges[f.name])
        if why is not None:
            raise ValueError(f"{type(obj).__name__}.{f.name}: {why}")
        object.__setattr__(obj, f.name, float(value))


@dataclass(frozen=True)
class Physics:
    """A scene's physics: Coulomb friction of every contact (robot-object, object-object,
    object-wall), the objects' viscous ground friction (N s/m per kg), the robots' driving
    speed (m/s) and the force limit of their actuators (N per axis). Validated on
    construction (``ValueError`` naming the field and its range)."""

    contact_friction: float = 0.5
    ground_damping: float = 30.0
    robot_speed: float = DEFAULT_TEAM.speed
    robot_force_limit: float = 60.0

    def __post_init__(self) -> None:
        _validate(self, PHYSICS_RANGES)

    def to_dict(self) -> dict[str, float]:
        """The ``physics`` section's values that differ from the defaults."""
        return {k: v for k, v in vars(self).items()
                if k in ("contact_friction", "ground_damping")
                and v != getattr(DEFAULT_PHYSICS, k)}


@dataclass(frozen=True)
class ObjectPhysics:
    """One object's mass (kg) and the Coulomb friction of its contacts; None: the scene's
    (``OBJECT_MASS`` and ``Physics.contact_friction``)."""

    mass: float | None = None
    friction: float | None = None

    def __post_init__(self) -> None:
        _validate(self, OBJECT_RANGES)

    def to_dict(self) -> dict[str, float]:
        return {k: v for k, v in vars(self).items() if v is not None}


#: The defaults: what a scene file without physics keys means.
DEFAULT_PHYSICS = Physics()
#: Mass of an object whose file does not give one (kg; fixed, independent of its size).
OBJECT_MASS = 1.0
