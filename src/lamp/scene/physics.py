"""The physics of a scene: what a user's robots and loads really are, set in the scene file.

Scene format (``lamp-scene/1``, all optional, additive)::

    physics: {contact_friction: 0.5, ground_damping: 30.0}
    robots:  {speed: 0.25, force_limit: 60.0, ...}
    objects: [{..., mass: 1.0, friction: 0.5}]

This module owns the defaults (the simulator's calibrated values: a file without these
keys means what it always meant) and the ranges a value must lie in, each end with its
reason (what the simulator serves: its time step, its memory, its contacts); beyond them a
scene is refused naming the field and the range, not run into an unstable simulation.
``lamp.sim.mjcf`` and ``lamp.sim.simulator`` read :class:`Physics` and the per-object
:class:`ObjectPhysics` where the simulator is built.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

from lamp.geometry.team import DEFAULT_TEAM

__all__ = ["DEFAULT_PHYSICS", "OBJECT_RANGES", "PHYSICS_RANGES", "Bound", "ObjectPhysics",
           "Physics", "check_range"]


@dataclass(frozen=True)
class Bound:
    """The values a physical field may take, ``low <= value <= high``, and why."""

    low: float
    high: float
    why: str


#: Valid values per field, both ends included, with the reason for each end: friction is a
#: Coulomb coefficient, damping N s/m per kg of object mass, speed m/s, force N per axis,
#: mass kg. ``tests/test_physics.py`` pushes an object at both ends of every range and
#: checks the simulation stays stable there.
PHYSICS_RANGES: dict[str, Bound] = {
    "contact_friction": Bound(0.01, 2.0, "Coulomb coefficients of real materials (wet ice "
                              "to rubber on rubber); the contact model was checked there"),
    "ground_damping": Bound(0.1, 500.0, "a released object's speed decays with time "
                            "constant 1/damping: 10 s at the low end (it coasts long after "
                            "a push), 2 ms (one physics step) at the high end"),
    "robot_speed": Bound(0.05, 2.0, "a motion is simulated step by step in memory, 10/speed "
                         "physics steps per 2 cm row (200 at 0.05 m/s); the robots' "
                         "controller tracks its target up to 2 m/s"),
    "robot_force_limit": Bound(0.1, 1000.0, "the actuators of a 2.2 kg robot, from "
                               "barely moving it to 1000 N: the range the contacts were "
                               "checked for"),
}
OBJECT_RANGES: dict[str, Bound] = {
    "mass": Bound(0.01, 100.0, "MuJoCo refuses moving bodies of almost no mass; 10 g to "
                  "100 kg against 2.2 kg robots is the range the contacts were checked for"),
    "friction": PHYSICS_RANGES["contact_friction"],
}


def check_range(name: str, value: Any, bound: Bound) -> str | None:
    """Why ``value`` is not a number in ``bound`` (None when it is)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return f"must be a finite number, got {value!r}"
    if not bound.low <= value <= bound.high:
        return f"must be in [{bound.low:g}, {bound.high:g}] ({bound.why}), got {value:g}"
    return None


def _validate(obj: Any, ranges: dict[str, Bound]) -> None:
    for f in fields(obj):
        value = getattr(obj, f.name)
        if value is None:
            continue
        why = check_range(f.name, value, ranges[f.name])
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
