"""The scene format ``lamp-scene/1`` as a JSON Schema (draft 2020-12), for editors.

The schema states the structural rules of ``scene-format.md``: required fields, no
unknown keys, types, positive sizes and radii, list lengths. The geometric rules
(containment, overlaps, simple polygons) are beyond JSON Schema; ``lamp validate``
checks everything. Every file ``load_scene`` accepts validates against this schema (the
tests check it on the scene format's example and the built-in suites).
"""

from __future__ import annotations

from typing import Any

from lamp.scene.loader import DEFAULT_ROBOT_RADIUS, FORMAT, MAX_WORKSPACE_SIDE
from lamp.scene.model import SCHEDULES
from lamp.scene.physics import DEFAULT_PHYSICS, OBJECT_RANGES, PHYSICS_RANGES, Bound

SCHEMA_ID = "urn:lamp:scene-format:1"


def _numbers(n: int, description: str, *, positive: bool = False,
             maximum: float | None = None) -> dict[str, Any]:
    item: dict[str, Any] = {"type": "number"}
    if positive:
        item["exclusiveMinimum"] = 0
    if maximum is not None:
        item["maximum"] = maximum
    return {"type": "array", "items": item, "minItems": n, "maxItems": n,
            "description": description}


def _positive(description: str) -> dict[str, Any]:
    return {"type": "number", "exclusiveMinimum": 0, "description": description}


def _points(description: str) -> dict[str, Any]:
    return {"type": "array", "items": _numbers(2, "[x, y]"), "minItems": 3,
            "description": description}


def _ranged(bound: Bound, description: str, default: float | None = None) -> dict[str, Any]:
    out: dict[str, Any] = {"type": ["number", "null"], "minimum": bound.low,
                           "maximum": bound.high, "description": f"{description}: {bound.why}"}
    if default is not None:
        out["default"] = default
    return out


def _closed(kind: str, properties: dict[str, Any], required: list[str]) -> dict[str, Any]:
    return {"type": "object", "properties": {"type": {"const": kind}, **properties},
            "required": ["type", *required], "additionalProperties": False}


#: A lifelong scene's ``tasks`` (``lamp.scene.tasks``).
_TASKS: dict[str, Any] = {
    "type": ["array", "null"],
    "items": {
        "type": "object",
        "properties": {
            "object": {"type": "integer", "minimum": 0,
                       "description": "index into objects"},
            "goal": _numbers(3, "[x, y, theta]"),
            "release_s": {"type": ["number", "null"], "minimum": 0, "default": 0,
                          "description": "simulated time (s) from which it "
                                         "may be served"},
        },
        "required": ["object", "goal"], "additionalProperties": False,
    },
    "description": "lifelong tasks beyond each object's own goal (its first "
                   "task): the object goes to goal once released, after its "
                   "earlier tasks",
}


def scene_schema() -> dict[str, Any]:
    """The JSON Schema of a scene file (a fresh dict each call)."""
    pose = _numbers(3, "pose [x, y, theta] (metres, radians)")
    centre = _numbers(2, "centre [x, y] in the world frame (metres)")
    obstacle = {"oneOf": [
        _closed("circle", {"center": centre, "radius": _positive("radius (m)")},
                ["center", "radius"]),
        _closed("rectangle", {"center": centre,
                              "size": _numbers(2, "extent [sx, sy] (m)", positive=True),
                              "angle": {"type": ["number", "null"],
                                        "description": "rotation (rad), default 0"}},
                ["center", "size"]),
        _closed("polygon", {"points": _points("world-frame vertices of a simple polygon")},
                ["points"]),
    ]}
    motion = {"start": pose, "goal": pose,
              "mass": _ranged(OBJECT_RANGES["mass"], "the object's mass (kg), default 1"),
              "friction": _ranged(OBJECT_RANGES["friction"], "Coulomb friction of the "
                                  "object's contacts, default physics.contact_friction"),
              "after": {"type": ["array", "null"], "items": {"type": "integer", "minimum": 0},
                        "uniqueItems": True,
                        "description": "indices of the objects placed before this one moves "
                                       "(concurrent schedule; no cycles)"}}
    obj = {"oneOf": [
        _closed("circle", {"radius": _positive("radius (m)"), **motion},
                ["radius", "start", "goal"]),
        _closed("rectangle", {"size": _numbers(2, "extent along the object's own x and y "
                                                  "axes (m)", positive=True), **motion},
                ["size", "start", "goal"]),
        _closed("polygon", {"points": _points("vertices in the object's own frame, around "
                                              "its origin"), **motion},
                ["points", "start", "goal"]),
    ]}
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        "title": f"LAMP scene ({FORMAT})",
        "description": "A multi-robot manipulation scene. Units: metres and radians; the "
                       "workspace is [0, W] x [0, H]. Geometric rules (containment, "
                       "overlaps) are checked by `lamp validate`.",
        "type": "object",
        "properties": {
            "format": {"const": FORMAT},
            "name": {"type": "string"},
            "workspace": _numbers(2, f"[W, H] (m), each at most {MAX_WORKSPACE_SIDE:g}",
                                  positive=True, maximum=MAX_WORKSPACE_SIDE),
            "robots": {
                "type": "object",
                "properties": {
                    "radius": {"type": ["number", "null"], "exclusiveMinimum": 0,
                               "default": DEFAULT_ROBOT_RADIUS,
                               "description": "robot disk radius (m)"},
                    "starts": {"type": "array", "items": _numbers(2, "[x, y]"),
                               "minItems": 1},
                    "speed": _ranged(PHYSICS_RANGES["robot_speed"], "driving speed (m/s)",
                                     DEFAULT_PHYSICS.robot_speed),
                    "force_limit": _ranged(PHYSICS_RANGES["robot_force_limit"],
                                           "actuator force limit per axis (N)",
                                           DEFAULT_PHYSICS.robot_force_limit),
                },
                "required": ["starts"], "additionalProperties": False,
            },
            "obstacles": {"type": ["array", "null"], "items": obstacle,
                          "description": "static obstacles"},
            "physics": {
                "type": ["object", "null"],
                "properties": {
                    "contact_friction": _ranged(PHYSICS_RANGES["contact_friction"],
                                                "Coulomb friction of every contact",
                                                DEFAULT_PHYSICS.contact_friction),
                    "ground_damping": _ranged(PHYSICS_RANGES["ground_damping"],
                                              "objects' viscous ground friction "
                                              "(N s/m per kg)", DEFAULT_PHYSICS.ground_damping),
                },
                "additionalProperties": False,
                "description": "the physics of the scene (default: the simulator's)",
            },
            "objects": {"type": "array", "items": obj, "minItems": 1,
                        "description": "moved one after another in this order (schedule "
                                       "sequential), or several at once (concurrent)"},
            "schedule": {"enum": [*SCHEDULES, None], "default": "sequential",
                         "description": "sequential: one object after another by the whole "
                                        "team (the paper's; with tasks: first come, first "
                                        "served); concurrent: several at once by sub-teams "
                                        "(the default of a scene with tasks)"},
            "tasks": _TASKS,
        },
        "required": ["format", "name", "workspace", "robots", "objects"],
        "additionalProperties": False,
    }
