"""Loading scene files (format ``lamp-scene/1``) with validation.

``load_scene(path)`` reads a YAML or JSON file, ``scene_from_dict(d)`` validates a dict of
the same form; both return a :class:`lamp.scene.model.Scene` or raise :class:`SceneError`.
Every message has the form ``<file>: <field path>: <reason>``, for example
``maze.yaml: objects[1].size[0]: must be > 0, got -0.2``; ``<dict>`` stands in for the file
when a dict without a source is validated. No other exception escapes for any input.

Rules (``/work/shared/spec/scene-format.md``), checked in this order so that the first
message is about the first thing to fix:

1. structure: ``format`` is exactly ``lamp-scene/1``; required fields are present; no
   unknown keys anywhere; types are right (bools and strings are not numbers); numbers are
   finite; sizes and radii are > 0; polygons have >= 3 vertices, no repeated consecutive
   vertex, are simple (not self-intersecting) and have positive area. An optional field
   written as ``null`` counts as absent (``obstacles:`` with nothing under it is common).
2. geometry, with exact footprints (disks, rotated rectangles, polygons) and the scene format's (``docs/scene-format.md``)
   absolute rounding tolerance ``EPS = 1e-6`` m (a wall written with ``angle: 1.5708``
   that touches the border is inside it): obstacles, robots and objects (at start and at goal) lie
   inside the workspace (touching the border is allowed, crossing by more than ``EPS``
   is not); robots do not overlap each other, an obstacle, or an object at its start; no
   object overlaps an obstacle at its start or at its goal.
   Two rules beyond the format's list, because such a scene is physically impossible:
   objects do not overlap each other at their starts, nor at their goals.

"Overlap" means a positive-area intersection: for two disks, centre distance below the sum
of the radii minus ``EPS``; for a disk and a polygon, distance from the centre to the
polygon below the radius minus ``EPS``; for two polygons, one polygon shrunk by ``EPS``
still intersects the other (so exact touching, up to rounding, is allowed).

YAML is read with PyYAML's safe loader plus two fixes: YAML 1.2 style floats without a
dot or exponent sign (``1e-3``) are numbers, not strings, and a key repeated in one
mapping is an error (it would otherwise silently win). ``.json`` files are read with the
``json`` module (same duplicate-key rule).
"""

from __future__ import annotations

import graphlib
import json
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import shapely
import yaml

from lamp.geometry.team import DEFAULT_TEAM
from lamp.scene.errors import Ctx, SceneError, fmt_xy, show, value_kind
from lamp.scene.fields import (
    MAX_ANGLE,
    field_angle,
    field_items,
    field_mapping,
    field_number,
    field_pose,
    field_string,
    field_vector,
)
from lamp.scene.geometry_checks import check_geometry
from lamp.scene.model import (
    SCHEDULES,
    Circle,
    Obstacle,
    Polygon,
    Rectangle,
    Scene,
    SceneObject,
    Shape,
)
from lamp.scene.physics import (
    DEFAULT_PHYSICS,
    OBJECT_RANGES,
    PHYSICS_RANGES,
    Bound,
    ObjectPhysics,
    Physics,
    check_range,
)
from lamp.scene.tasks import parse_tasks

__all__ = ["DEFAULT_ROBOT_RADIUS", "FORMAT", "MAX_ANGLE", "MAX_WORKSPACE_SIDE", "SceneError", "load_scene", "scene_from_dict"]

FORMAT = "lamp-scene/1"
DEFAULT_ROBOT_RADIUS = DEFAULT_TEAM.radius
#: Largest workspace side (m) the planners' grids serve: the object lattice (0.1 m, 16
#: headings) keeps one validity byte per pose, 64 M poses at 200 m x 200 m, filled only
#: where a search goes; beyond that a scene is refused rather than run out of memory.
MAX_WORKSPACE_SIDE = 200.0
SHAPE_TYPES = ("circle", "rectangle", "polygon")

# Allowed keys per mapping: (required, optional).
_TOP_KEYS = (("format", "name", "workspace", "robots", "objects"),
             ("obstacles", "physics", "schedule", "tasks"))
_ROBOT_KEYS = (("starts",), ("radius", "speed", "force_limit"))
_PHYSICS_KEYS = ((), ("contact_friction", "ground_damping"))
_OBSTACLE_KEYS = {
    "circle": (("type", "center", "radius"), ()),
    "rectangle": (("type", "center", "size"), ("angle",)),
    "polygon": (("type", "points"), ()),
}
_OBJECT_KEYS = {
    "circle": (("type", "radius", "start", "goal"), ("mass", "friction", "after")),
    "rectangle": (("type", "size", "start", "goal"), ("mass", "friction", "after")),
    "polygon": (("type", "points", "start", "goal"), ("mass", "friction", "after")),
}


# --------------------------------------------------------------------------- parsing


class _YamlLoader(yaml.SafeLoader):
    """PyYAML's safe loader with YAML 1.2 floats and an error on repeated keys."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set[tuple[str, str]] = set()
        for key_node, _ in node.value:
            if isinstance(key_node, yaml.ScalarNode) and key_node.tag != "tag:yaml.org,2002:merge":
                key = (key_node.tag, key_node.value)
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        "while constructing a mapping",
                        node.start_mark,
                        f"found repeated key {key_node.value!r}",
                        key_node.start_mark,
                    )
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


# PyYAML implements YAML 1.1, where ``1e-3`` and ``1.0e3`` are strings; make them floats.
_YamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def _json_pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"repeated key {k!r}")
        out[k] = v
    return out


def _parse(data: bytes, ctx: Ctx, as_json: bool) -> Any:
    """Bytes of a scene file -> Python data; every failure becomes a SceneError."""
    try:
        if as_json:
            return json.loads(data.decode("utf-8-sig"), object_pairs_hook=_json_pairs)
        return yaml.load(data, Loader=_YamlLoader)  # noqa: S506 (a SafeLoader subclass)
    except UnicodeDecodeError as exc:
        ctx.fail("(file)", f"not valid UTF-8 text ({exc.reason} at byte {exc.start})")
    except json.JSONDecodeError as exc:
        ctx.fail("(file)", f"JSON syntax error: {exc.msg} (line {exc.lineno}, column {exc.colno})")
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        what = exc.problem or exc.context or "malformed YAML"
        ctx.fail("(file)", f"YAML syntax error: {what}{where}")
    except yaml.YAMLError as exc:
        ctx.fail("(file)", f"YAML error: {exc}")
    except RecursionError:
        ctx.fail("(file)", "nested too deeply to parse")
    except ValueError as exc:  # json duplicate keys; odd YAML scalars (bad timestamps)
        ctx.fail("(file)", f"cannot parse: {exc}")


# --------------------------------------------------------------------------- leaf checks




def _polygon_points(ctx: Ctx, v: Any, field: str) -> tuple[tuple[float, float], ...]:
    """>= 3 finite [x, y] vertices forming a simple polygon of positive area."""
    raw = field_items(ctx, v, field, min_len=3, what="points")
    pts = tuple(field_vector(ctx, p, f"{field}[{i}]", 2, "x, y") for i, p in enumerate(raw))
    arr = np.asarray(pts, dtype=float)
    repeated = np.flatnonzero(np.all(arr == np.roll(arr, -1, axis=0), axis=1))
    if repeated.size:
        i = int(repeated[0])
        first, later = (0, i) if i == len(pts) - 1 else (i, i + 1)
        ctx.fail(
            f"{field}[{later}]",
            f"repeats vertex {field}[{first}] {fmt_xy(pts[first])}; list each vertex once "
            "(the polygon closes itself)",
        )
    if shapely.MultiPoint(arr).convex_hull.area == 0.0:
        ctx.fail(field, f"polygon must have positive area (all points on one line), got {show(v)}")
    poly = shapely.Polygon(arr)
    if not (shapely.is_simple(poly.exterior) and shapely.is_valid(poly)):
        ctx.fail(field, f"polygon must be simple (edges must not cross), got {show(v)}")
    return pts  # type: ignore[return-value]


def _shape(ctx: Ctx, d: Mapping[str, Any], field: str, kind: str) -> Shape:
    """The size part of an object entry (obstacle circles/rectangles are built separately)."""
    if kind == "circle":
        return Circle(field_number(ctx, d["radius"], f"{field}.radius", positive=True))
    if kind == "rectangle":
        return Rectangle(field_vector(ctx, d["size"], f"{field}.size", 2, "sx, sy", positive=True))
    return Polygon(_polygon_points(ctx, d["points"], f"{field}.points"))


def _shape_type(ctx: Ctx, v: Any, field: str) -> str:
    if not isinstance(v, Mapping):
        ctx.fail(field, f"must be a mapping, got {show(v)} ({value_kind(v)})")
    if "type" not in v:
        ctx.fail(f"{field}.type", f"missing required field (one of {', '.join(SHAPE_TYPES)})")
    kind = v["type"]
    if not isinstance(kind, str) or kind not in SHAPE_TYPES:
        ctx.fail(f"{field}.type", f"must be one of {', '.join(SHAPE_TYPES)}, got {show(kind)}")
    return kind


# --------------------------------------------------------------------------- structure


def _obstacle(ctx: Ctx, v: Any, field: str) -> Obstacle:
    kind = _shape_type(ctx, v, field)
    d = field_mapping(ctx, v, field, _OBSTACLE_KEYS[kind])
    if kind == "polygon":  # world-frame vertices, identity pose
        return Obstacle(Polygon(_polygon_points(ctx, d["points"], f"{field}.points")))
    cx, cy = field_vector(ctx, d["center"], f"{field}.center", 2, "x, y")
    if kind == "circle":
        r = field_number(ctx, d["radius"], f"{field}.radius", positive=True)
        return Obstacle(Circle(r), (cx, cy, 0.0))
    size = field_vector(ctx, d["size"], f"{field}.size", 2, "sx, sy", positive=True)
    angle = field_angle(ctx, d["angle"], f"{field}.angle") if "angle" in d else 0.0
    return Obstacle(Rectangle(size), (cx, cy, angle))


def _object(ctx: Ctx, v: Any, field: str) -> SceneObject:
    kind = _shape_type(ctx, v, field)
    d = field_mapping(ctx, v, field, _OBJECT_KEYS[kind])
    shape = _shape(ctx, d, field, kind)
    start = field_pose(ctx, d["start"], f"{field}.start")
    goal = field_pose(ctx, d["goal"], f"{field}.goal")
    phys = {k: _ranged(ctx, d[k], f"{field}.{k}", OBJECT_RANGES[k]) for k in OBJECT_RANGES
            if k in d}
    after = _after(ctx, d.get("after") or [], f"{field}.after")
    return SceneObject(shape, start, goal, ObjectPhysics(**phys), after)  # type: ignore[arg-type]


def _after(ctx: Ctx, v: Any, field: str) -> tuple[int, ...]:
    """An object's ``after`` list: distinct non-negative integers (checked against the
    objects by :func:`_check_order`)."""
    out = []
    for i, k in enumerate(field_items(ctx, v, field, what="object indices")):
        if isinstance(k, bool) or not isinstance(k, int) or k < 0:
            ctx.fail(f"{field}[{i}]", f"must be an object index (an integer >= 0), got {show(k)}")
        if k in out:
            ctx.fail(f"{field}[{i}]", f"object {k} is listed twice")
        out.append(k)
    return tuple(out)


def _check_order(ctx: Ctx, objects: tuple[SceneObject, ...]) -> None:
    """Every ``after`` index names another object, and the ``after`` lists have no cycle
    (named by its objects, as a path ``a -> b -> a`` from its lowest index)."""
    n = len(objects)
    for i, o in enumerate(objects):
        for j, k in enumerate(o.after):
            if k >= n:
                ctx.fail(f"objects[{i}].after[{j}]", f"no object {k} (the scene has {n}: "
                         f"0..{n - 1})")
            if k == i:
                ctx.fail(f"objects[{i}].after[{j}]", "an object cannot wait for itself")
    try:
        graphlib.TopologicalSorter({i: o.after for i, o in enumerate(objects)}).prepare()
    except graphlib.CycleError as exc:
        cycle = exc.args[1][::-1][:-1]  # each waits for the next (graphlib: the reverse)
        first = cycle.index(min(cycle))
        cycle = [*cycle[first:], *cycle[:first], cycle[first]]
        ctx.fail(f"objects[{cycle[0]}].after", "the after lists have a cycle: "
                 + " -> ".join(f"objects[{k}]" for k in cycle)
                 + " (each waits for the next to be placed)")


def _ranged(ctx: Ctx, v: Any, field: str, bound: Bound) -> float:
    """A number within a physical parameter's range (``lamp.scene.physics``)."""
    x = field_number(ctx, v, field)
    why = check_range(field, x, bound)
    if why is not None:
        ctx.fail(field, why)
    return x


def _physics(ctx: Ctx, d: Mapping[str, Any], robots: Mapping[str, Any]) -> Physics:
    """The ``physics`` section and ``robots.speed`` / ``robots.force_limit``."""
    section = field_mapping(ctx, d.get("physics") or {}, "physics", _PHYSICS_KEYS)
    values = {k: _ranged(ctx, section[k], f"physics.{k}", PHYSICS_RANGES[k])
              for k in _PHYSICS_KEYS[1] if k in section}
    for key, attr in (("speed", "robot_speed"), ("force_limit", "robot_force_limit")):
        if key in robots:
            values[attr] = _ranged(ctx, robots[key], f"robots.{key}", PHYSICS_RANGES[attr])
    return Physics(**values) if values else DEFAULT_PHYSICS


def _structure(ctx: Ctx, raw: Any, source: str | None) -> Scene:
    d = field_mapping(ctx, raw, "", _TOP_KEYS)
    if not (isinstance(d["format"], str) and d["format"] == FORMAT):
        ctx.fail("format", f"must be exactly {FORMAT!r}, got {show(d['format'])}")
    name = field_string(ctx, d["name"], "name")
    workspace = field_vector(ctx, d["workspace"], "workspace", 2, "W, H", positive=True)
    if max(workspace) > MAX_WORKSPACE_SIDE:
        ctx.fail("workspace", f"sides up to {MAX_WORKSPACE_SIDE:g} m are supported (the "
                 f"planners' 1 cm and 0.1 m grids), got {list(workspace)}")
    robots = field_mapping(ctx, d["robots"], "robots", _ROBOT_KEYS)
    radius = (
        field_number(ctx, robots["radius"], "robots.radius", positive=True)
        if "radius" in robots
        else DEFAULT_ROBOT_RADIUS
    )
    starts = field_items(ctx, robots["starts"], "robots.starts", min_len=1, what="robot starts")
    robot_starts = tuple(
        field_vector(ctx, p, f"robots.starts[{i}]", 2, "x, y") for i, p in enumerate(starts)
    )
    obstacles = tuple(
        _obstacle(ctx, o, f"obstacles[{i}]")
        for i, o in enumerate(field_items(ctx, d.get("obstacles", []), "obstacles"))
    )
    objects = tuple(
        _object(ctx, o, f"objects[{i}]")
        for i, o in enumerate(field_items(ctx, d["objects"], "objects", min_len=1, what="objects"))
    )
    _check_order(ctx, objects)
    tasks = parse_tasks(ctx, d.get("tasks") or [], objects)
    # a lifelong scene is served by the fleet unless it says otherwise (sequential: the
    # first-come-first-served baseline, ``lamp.pipeline.schedule``)
    schedule = d.get("schedule") or ("concurrent" if tasks else "sequential")
    if not (isinstance(schedule, str) and schedule in SCHEDULES):
        ctx.fail("schedule", f"must be one of {', '.join(SCHEDULES)}, got {show(schedule)}")
    return Scene(
        schedule=schedule,
        name=name,
        workspace=workspace,  # type: ignore[arg-type]
        robot_starts=robot_starts,  # type: ignore[arg-type]
        objects=objects,
        obstacles=obstacles,
        robot_radius=radius,
        source=source,
        physics=_physics(ctx, d, robots),
        tasks=tasks,
    )


# --------------------------------------------------------------------------- public API

_UNEXPECTED = "unexpected error while validating"  # marks a loader bug; tests assert it never shows


def _guarded(ctx: Ctx, fn: Callable[[], Scene]) -> Scene:
    """Run ``fn``; let SceneError through, turn anything else into one.

    A safety net only: the checks above are meant to catch every bad input first, and the
    tests assert that the ``_UNEXPECTED`` message never appears.
    """
    try:
        return fn()
    except SceneError:
        raise
    except RecursionError:
        ctx.fail("(file)", "data nested too deeply")
    except Exception as exc:  # noqa: BLE001 - never leak a traceback for bad input
        ctx.fail("(file)", f"{_UNEXPECTED}: {type(exc).__name__}: {exc}")


def _validate(ctx: Ctx, raw: Any, source: str | None) -> Scene:
    """Structure first (types, values), then geometry; see the module docstring."""
    scene = _structure(ctx, raw, source)
    check_geometry(ctx, scene)
    return scene


def scene_from_dict(d: dict[str, Any], source: str | None = None) -> Scene:
    """Validate a scene dict (the scene-file form, as ``Scene.to_dict()`` writes it).

    ``source`` names the origin in messages and is stored as ``Scene.source``; without it
    messages say ``<dict>``. Raises :class:`SceneError` for any invalid input.
    """
    ctx = Ctx(source if source is not None else "<dict>", source)
    return _guarded(ctx, lambda: _validate(ctx, d, source))


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file (YAML, or JSON for ``.json``); see the module docstring.

    Raises :class:`SceneError` when the file is missing, unreadable, not valid YAML/JSON, not
    a mapping, or breaks any scene rule; the message starts with ``str(path)``.
    """
    label = str(path)
    ctx = Ctx(label, label)
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        ctx.fail("(file)", "file not found")
    except IsADirectoryError:
        ctx.fail("(file)", "is a directory, not a scene file")
    except OSError as exc:
        ctx.fail("(file)", f"cannot read file: {exc.strerror or exc}")
    as_json = Path(path).suffix.lower() == ".json"
    return _guarded(ctx, lambda: _validate(ctx, _parse(data, ctx, as_json), label))
