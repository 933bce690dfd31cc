"""The ``fleet`` family: multi-object scenes for the concurrent schedule (sub-teams of up
to 3 robots moving several objects at once).

25 scenes, ``fleet-00`` .. ``fleet-24``, every one with ``schedule: concurrent``. Scene
``k`` is of kind ``KINDS[k % 5]`` and size level ``(k // 5 + k % 5) % 5`` (so every kind
comes at every level once); level ``l`` draws both map sides in ``LEVELS[l]`` (6-50 m; the
shorter side of level 0 is 6 m and the longer side of level 4 is 50 m) and the number of
objects in ``OBJECTS[l]`` (2-12). The kinds (maps: ``lamp.suites.fleet_layout``,
``lamp.suites.fleet_open`` and ``lamp.suites.fleet_warehouse``):

* ``rooms``: a grid of rooms behind thin walls with doors; each object goes from one room
  to a room one or two doors away (circles, rectangles and polygons);
* ``aisles``: a warehouse of shelf rows, aisles and a dock band; pallets (rectangles) are
  put away into slots in the shelves, picked from them, or moved between them;
* ``yard``: an open yard with posts, containers and rubble; circles, rectangles and
  polygons go 1.5-12 m in any direction;
* ``swap``: two halls joined by a single door; one to three pairs of objects swap sides
  through it (objects 0 and 1 always), the others cross or stay in their hall;
* ``after``: a warehouse whose shelves hold lanes, each with a load at its back and a
  blocker in front: the load waits for the blocker (``after = [blocker]``) and cannot get
  out before it is cleared (checked).

Objects are 0.2-0.6 m (circle diameters, rectangle sides, polygon widths and diameters;
pallets 0.3-0.6 m). Teams have 6-24 robots of radius ``DEFAULT_TEAM.radius``: at least 3
per object when ``rng`` says so and 3 per object fit in 24 (``RICH_SHARE``), else fewer
than 3 per object (but at least one per object and at least 6). Robots start spread over
the map, near the objects, outside doors, slots and lanes (``fleet_layout.place_team``).

Guarantees of every accepted scene: it loads (``lamp.scene.scene_from_dict``: inside the
workspace, no overlaps); start and goal footprints are apart by ``OBJECT_GAP`` and clear of
the obstacles by ``END_CLEARANCE``; and the checks of ``lamp.suites.fleet_checks`` pass for
every object (a certified robot-room route with the others standing where the schedule
may have left them, robots reach its contact ring, a load is really blocked until its
blocker is placed). A drawn attempt that fails anything is redrawn from the same stream,
so a scene is a pure function of its index: ``np.random.default_rng([SUITE_SEED, STREAM,
index])``.

Beyond the family: :func:`generate_custom` draws a kind at any size, and
:func:`generate_on_map` puts the yard kind's objects and robots on a map of the user's (a
scene file's obstacles, or a Moving AI grid map of ``lamp.scene.mapf``), with the same
checks (``lamp suite fleet-scene``).

Routes are searched on a ``RESOLUTION`` lattice (``COARSE_RESOLUTION`` on maps over
``COARSE_ABOVE`` m a side) with ``N_HEADINGS`` headings per period; robot reach on a
``REACH_RESOLUTION`` grid. A coarse lattice can only miss routes, never report a false one.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from lamp.scene.loader import scene_from_dict
from lamp.scene.model import Obstacle, Scene, Shape
from lamp.suites import checks as C
from lamp.suites import fleet_checks as FC
from lamp.suites import fleet_layout as FL
from lamp.suites import fleet_open as FO
from lamp.suites import fleet_warehouse as FW
from lamp.suites.generators import parse_scene
from lamp.suites.layout import END_CLEARANCE, ROBOT_RADIUS, SUITE_SEED, rnd

NAME = "fleet"
N_SCENES = 25
#: the family's random stream (the paper's families use 0-3, warehouse-xl 10, corridor 11)
STREAM = 12
KINDS = ("rooms", "aisles", "yard", "swap", "after")
#: per size level: range of each map side (m) and of the number of objects
LEVELS = ((6.0, 8.0), (8.0, 14.0), (14.0, 24.0), (24.0, 36.0), (36.0, 50.0))
OBJECTS = ((2, 4), (3, 6), (4, 8), (6, 10), (8, 12))
ROBOTS = (6, 24)
#: robots per object a sub-team may hold, and the share of scenes aiming at that many
TEAM = 3
RICH_SHARE = 0.6
OBJECT_GAP = FL.OBJECT_GAP
#: route lattice (m), the coarser one on large maps, headings per period; reach grid (m)
RESOLUTION = 0.05
COARSE_RESOLUTION = 0.1
COARSE_ABOVE = 12.0
N_HEADINGS = 8
REACH_RESOLUTION = 0.05
REACH_RING_WIDTH = 0.06
MAX_ATTEMPTS = 30
#: what ``generate_custom`` accepts: the longest map side (m), objects and robots
CUSTOM_MAX_SIDE = 150.0
CUSTOM_MAX_OBJECTS = 200
CUSTOM_MAX_ROBOTS = 1000
#: draws of one object on a user's map until its route passes (``generate_on_map``)
MAP_TRIES = 10

__all__ = ["END_CLEARANCE", "KINDS", "LEVELS", "NAME", "N_SCENES", "OBJECTS", "OBJECT_GAP",
           "GeneratedFleet", "generate_custom", "generate_on_map", "generate_scene",
           "manifest_entry", "scene_name"]


def scene_name(index: int) -> str:
    return f"{NAME}-{index:02d}"


def scene_kind(index: int) -> str:
    return KINDS[index % len(KINDS)]


def scene_level(index: int) -> int:
    return (index // len(KINDS) + index % len(KINDS)) % len(LEVELS)


def _workspace(rng: np.random.Generator, level: int) -> tuple[float, float]:
    lo, hi = LEVELS[level]
    a, b = (rnd(v, 1) for v in rng.uniform(lo, hi, size=2))
    if level == 0:
        a = lo
    if level == len(LEVELS) - 1:
        a = hi
    return (a, b) if rng.random() < 0.5 else (b, a)


def team_size(rng: np.random.Generator, n_objects: int) -> int:
    """6-24 robots: >= TEAM per object (RICH_SHARE of the time, when that fits in 24),
    else fewer than TEAM per object but at least one per object."""
    lo, hi = ROBOTS
    lean_lo, lean_hi = max(lo, n_objects), min(hi, TEAM * n_objects - 1)
    if TEAM * n_objects <= hi and (rng.random() < RICH_SHARE or lean_lo > lean_hi):
        return int(rng.integers(max(lo, TEAM * n_objects), min(hi, TEAM * n_objects + 6) + 1))
    return int(rng.integers(lean_lo, lean_hi + 1))


def sample_objects(rng: np.random.Generator, kind: str, n: int) -> list[FL.FleetObject]:
    """The scene's objects: pallets in the warehouse kinds (``after``: blocker, load pairs
    first, see ``fleet_warehouse.layout_lanes``), mixed shapes elsewhere."""
    if kind == "aisles":
        return [FW.pallet(rng) for _ in range(n)]
    if kind == "after":
        out = []
        for _ in range(n_pairs(n)):
            load = FW.pallet(rng)
            out += [FW.blocker_for(rng, load), load]
        return out + [FW.pallet(rng) for _ in range(n - len(out))]
    shapes = ("circle", "rectangle", "polygon")
    return [FL.sample_object(rng, shapes[int(rng.integers(3))]) for _ in range(n)]


def n_pairs(n_objects: int) -> int:
    """Blocker / load pairs of an ``after`` scene: 1, 2 from 5 objects, 3 from 9."""
    return 1 + (n_objects >= 5) + (n_objects >= 9)


#: ``on_attempt(attempt, of, rejected)``: a draw is about to be made (1-based, of ``of``
#: at most; ``rejected``: why earlier draws failed, reason -> count).
OnAttempt = Callable[[int, int, dict[str, int]], None]

LAYOUTS: dict[str, Callable[..., FL.FleetLayout | None]] = {
    "rooms": FL.layout_rooms,
    "aisles": FW.layout_aisles,
    "yard": FO.layout_yard,
    "swap": FO.layout_swap,
    "after": lambda rng, ws, objs: FW.layout_lanes(rng, ws, objs, n_pairs(len(objs))),
}


def scene_dict(name: str, lay: FL.FleetLayout, robots: list[list[float]]) -> dict[str, Any]:
    """The ``lamp-scene/1`` dict of a fleet scene (``schedule: concurrent``)."""
    objects = []
    for k, obj in enumerate(lay.objects):
        d = {**obj.shape, "start": [float(v) for v in lay.starts[k]],
             "goal": [float(v) for v in lay.goals[k]]}
        if lay.after and lay.after[k]:
            d["after"] = [int(j) for j in lay.after[k]]
        objects.append(d)
    return {
        "format": "lamp-scene/1",
        "name": name,
        "workspace": [lay.workspace[0], lay.workspace[1]],
        "schedule": "concurrent",
        "robots": {"radius": ROBOT_RADIUS, "starts": robots},
        "obstacles": lay.obstacles,
        "objects": objects,
    }


@dataclass
class GeneratedFleet:
    """A generated fleet scene with its file dict, loaded Scene and check reports."""

    index: int
    kind: str
    scene_dict: dict[str, Any]
    scene: Scene
    reports: list[FC.FleetObjectReport]
    attempts: int
    layout_info: dict[str, Any]
    #: the keep-out zones (x0, y0, x1, y1): door mouths, slots and lanes with their mouths
    keep_out: list[tuple[float, float, float, float]]


def resolution_for(workspace: tuple[float, float]) -> float:
    return COARSE_RESOLUTION if max(workspace) > COARSE_ABOVE else RESOLUTION


def generate_scene(index: int, held_out: bool = False) -> GeneratedFleet:
    """Generate scene ``index`` (0-based); deterministic in ``index``. The accepted scene
    has every guarantee of the module docstring; RuntimeError (with the rejection counts)
    when ``MAX_ATTEMPTS`` draws fail.

    With ``held_out`` the index runs on past the family (``index >= N_SCENES``, named
    ``fleet-heldout-NN``): scenes of the same kinds, levels and checks that no default
    was ever tuned on (``benchmarks/fleet_heldout.py``)."""
    low, high = (N_SCENES, None) if held_out else (0, N_SCENES)
    if not (isinstance(index, int) and not isinstance(index, bool) and index >= low
            and (high is None or index < high)):
        span = f"[{low}, {high})" if high is not None else f">= {low}"
        raise ValueError(f"index must be an int {span}, got {index!r}")
    rng = np.random.default_rng([SUITE_SEED, STREAM, index])
    kind, level = scene_kind(index), scene_level(index)
    ws = _workspace(rng, level)
    n_obj = int(rng.integers(OBJECTS[level][0], OBJECTS[level][1] + 1))
    objects = sample_objects(rng, kind, n_obj)
    n_robots = team_size(rng, n_obj)
    name = f"{NAME}-heldout-{index:02d}" if held_out else scene_name(index)
    return _draw(rng, index, name, kind, {"level": level}, ws, objects, n_robots)


def generate_custom(kind: str, workspace: tuple[float, float], n_objects: int,
                    n_robots: int, seed: int = 0,
                    on_attempt: OnAttempt | None = None) -> GeneratedFleet:
    """A scene of the family's ``kind`` at any size: ``n_objects`` objects and
    ``n_robots`` robots on a ``workspace`` map (m), with every guarantee of the module
    docstring; deterministic in its arguments (its own random stream, apart from the
    family's). For fleets beyond the family's 24 robots and 12 objects
    (``benchmarks/bench_fleet_scale.py``). ValueError names a bad argument; RuntimeError
    as :func:`generate_scene` when no draw passes the checks. ``on_attempt(attempt,
    MAX_ATTEMPTS, rejected so far)`` is called before each draw (for a progress line)."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    W, H = (float(v) for v in workspace)
    low = LEVELS[0][0]
    if not (low <= min(W, H) and max(W, H) <= CUSTOM_MAX_SIDE):
        raise ValueError(f"workspace sides must be {low:g}-{CUSTOM_MAX_SIDE:g} m, "
                         f"got {W} x {H}")
    _check_counts(n_objects, n_robots, 2 if kind == "after" else 1, " (2+ for 'after')")
    rng = np.random.default_rng([SUITE_SEED, STREAM, 1_000_000 + seed,
                                 KINDS.index(kind), int(W * 10), int(H * 10), n_objects,
                                 n_robots])
    objects = sample_objects(rng, kind, n_objects)
    name = f"{NAME}-{kind}-{W:g}x{H:g}-{n_robots}r{n_objects}o-s{seed}"
    return _draw(rng, -1, name, kind, {"custom": True}, (W, H), objects, n_robots,
                 on_attempt=on_attempt)


def _check_counts(n_objects: int, n_robots: int, least: int = 1, note: str = "") -> None:
    """ValueError naming ``n_objects`` (at least ``least``; ``note`` says why) or
    ``n_robots`` when a custom scene cannot have that many."""
    if not least <= n_objects <= CUSTOM_MAX_OBJECTS:
        raise ValueError(f"n_objects must be 1-{CUSTOM_MAX_OBJECTS}{note}, got {n_objects}")
    if not n_objects <= n_robots <= CUSTOM_MAX_ROBOTS:
        raise ValueError(f"n_robots must be {n_objects}-{CUSTOM_MAX_ROBOTS} (one per object "
                         f"at least), got {n_robots}")


def generate_on_map(base: Scene, n_objects: int, n_robots: int,
                    seed: int = 0, on_attempt: OnAttempt | None = None) -> GeneratedFleet:
    """A fleet scene on ``base``'s map (a user's scene file, or a grid map of
    ``lamp.scene.mapf``): its workspace, obstacles and physics, with ``n_objects`` new
    objects of the ``yard`` kind's shapes, each going 1.5-12 m in any direction
    (``fleet_open.layout_on``), and ``n_robots`` robots near them; ``base``'s own robots
    and objects are not used. Every guarantee of the module docstring holds;
    deterministic in its arguments (the stream hashes the map). ValueError names a bad
    argument; RuntimeError as :func:`generate_scene` when no draw passes the checks;
    ``on_attempt`` as in :func:`generate_custom`."""
    W, H = (float(v) for v in base.workspace)
    if max(W, H) > CUSTOM_MAX_SIDE:
        raise ValueError(f"workspace sides must be at most {CUSTOM_MAX_SIDE:g} m, "
                         f"got {W:g} x {H:g}")
    if abs(base.robot_radius - ROBOT_RADIUS) > 1e-9:
        raise ValueError(f"robots.radius must be {ROBOT_RADIUS:g} m (the robots the checks "
                         f"place), got {base.robot_radius:g}")
    _check_counts(n_objects, n_robots)
    d = base.to_dict()
    obstacles = d["obstacles"]
    digest = hashlib.sha256(json.dumps([d["workspace"], obstacles]).encode()).digest()
    rng = np.random.default_rng([SUITE_SEED, STREAM, 2_000_000 + seed, n_objects, n_robots,
                                 int.from_bytes(digest[:4], "little")])
    objects = sample_objects(rng, "yard", n_objects)
    name = f"{base.name}-fleet-{n_robots}r{n_objects}o-s{seed}"

    def route_ok(obj: FL.FleetObject, start: np.ndarray, goal: np.ndarray,
                 placed: list[tuple[Shape, np.ndarray]]) -> bool:
        """A robot-room route with the objects before it at their starts and goals (the
        checks' world so far): on a cluttered map one object is drawn again, not all."""
        world = C.build_world((W, H), [*base.obstacles, *(Obstacle(shape, tuple(pose))
                                                         for shape, pose in placed)])
        finder = C.RouteFinder(obj.geom, world, resolution_for((W, H)), N_HEADINGS)
        return finder.find(start, goal, C.ROBOT_ROOM) is not None

    def layout(rng: np.random.Generator, ws: tuple[float, float],
               objects: list[FL.FleetObject]) -> FL.FleetLayout | None:
        return FO.layout_on(rng, ws, objects, obstacles, {"map": base.name}, route_ok,
                            MAP_TRIES)

    gen = _draw(rng, -1, name, "map", {"custom": True}, (W, H), objects, n_robots, layout,
                on_attempt)
    extra = {k: v for k, v in d["robots"].items() if k not in ("radius", "starts")}
    if not extra and "physics" not in d:
        return gen
    out = dict(gen.scene_dict)
    out["robots"] = {**out["robots"], **extra}
    if "physics" in d:
        out["physics"] = d["physics"]
    return replace(gen, scene_dict=out, scene=scene_from_dict(out, source=out["name"]))


def _draw(rng: np.random.Generator, index: int, name: str, kind: str, tag: dict[str, Any],
          ws: tuple[float, float], objects: list[FL.FleetObject], n_robots: int,
          layout: Callable[..., FL.FleetLayout | None] | None = None,
          on_attempt: OnAttempt | None = None) -> GeneratedFleet:
    """Lay out ``objects`` and ``n_robots`` robots on a ``kind`` map (or with ``layout``)
    until a draw passes every check (at most ``MAX_ATTEMPTS``, each from ``rng``
    onwards); ``on_attempt`` hears of each draw before it is made."""
    rejected: dict[str, int] = {}

    def reject(why: str) -> None:
        rejected[why] = rejected.get(why, 0) + 1

    for attempt in range(1, MAX_ATTEMPTS + 1):
        if on_attempt is not None:
            on_attempt(attempt, MAX_ATTEMPTS, dict(rejected))
        lay = (layout or LAYOUTS[kind])(rng, ws, objects)
        if lay is None:
            reject("objects do not fit")
            continue
        robots = FL.place_team(rng, lay.placer, lay.starts, [o.reach for o in objects],
                               n_robots)
        if robots is None:
            reject("no robot starts")
            continue
        d = scene_dict(name, lay, robots)
        scene = parse_scene(d)
        if scene is None:
            reject("invalid scene")
            continue
        reports = FC.check_objects(scene, resolution_for(ws), N_HEADINGS, REACH_RESOLUTION,
                                   REACH_RING_WIDTH)
        if isinstance(reports, str):  # counted by kind: "object 3" reads "an object"
            reject(re.sub(r"\bobject \d+", "an object", reports))
            continue
        info = {"kind": kind, **tag, "workspace": list(ws), **lay.info}
        return GeneratedFleet(index, kind, d, scene, reports, attempt, info,
                              list(lay.placer.zone_boxes))
    raise RuntimeError(
        f"{name}: no valid scene after {MAX_ATTEMPTS} attempts (rejected: {rejected})"
    )


def manifest_entry(gen: GeneratedFleet, text: str) -> dict[str, Any]:
    """Manifest entry of one generated scene (``text``: its file)."""
    keys = ("type", "size", "radius", "points", "start", "goal")
    objs = [{**{k: o[k] for k in keys if k in o}, **r.to_dict()}
            for o, r in zip(gen.scene_dict["objects"], gen.reports, strict=True)]
    return {
        "name": gen.scene_dict["name"],
        "file": f"{gen.scene_dict['name']}.yaml",
        "sha256": hashlib.sha256(text.encode()).hexdigest(),
        "kind": gen.kind,
        "n_robots": len(gen.scene_dict["robots"]["starts"]),
        "n_objects": len(objs),
        "n_obstacles": len(gen.scene_dict["obstacles"]),
        "attempts": gen.attempts,
        "layout": gen.layout_info,
        "objects": objs,
    }


def check_settings() -> dict[str, Any]:
    """The manifest's record of the family's checks."""
    return {
        "robot_room": FC.C.ROBOT_ROOM,
        "free_clearance": FC.C.FREE_CLEARANCE,
        "end_clearance": END_CLEARANCE,
        "object_gap": OBJECT_GAP,
        "lattice_resolution": RESOLUTION,
        "coarse_lattice_resolution": COARSE_RESOLUTION,
        "coarse_above": COARSE_ABOVE,
        "headings_per_period": N_HEADINGS,
        "reach_resolution": REACH_RESOLUTION,
        "reach_ring_width": REACH_RING_WIDTH,
        "min_ring_fraction": FC.MIN_RING,
        "levels": [list(v) for v in LEVELS],
        "objects": [list(v) for v in OBJECTS],
        "robots": list(ROBOTS),
    }
