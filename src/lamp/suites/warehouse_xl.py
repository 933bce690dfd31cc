"""The ``warehouse-xl`` family: warehouse-scale single-object scenes (20-50 m maps).

Each scene is a rectangular hall of ``W x H`` metres (each side drawn in [20, 50]) with
rows of shelf rectangles (0.8-1.4 m deep) separated by aisles, cut into bays by
cross-aisles every 5-12 m, a dock band along one wall with cargo stacked against it, and
pallets in the aisles: most narrow an aisle from one side (leaving at least the object's
width plus two robot-room margins), some fill an aisle bay across (the route must go
round by a cross-aisle). Every aisle and cross-aisle is at least the object's width plus
two robot diameters wide. Objects are sampled as in the paper's families (even index:
rectangle with sides in [0.15, 0.50] m; odd: circle of radius [0.10, 0.30] m), with 3
robots of radius 0.05 m placed 0.12-0.7 m outside the object's bounding circle.
Start and goal are aisle crossings at least ``MIN_SPAN`` apart (straight line); the
accepted scene's free route is ``ROUTE_RANGE`` long.

Checks (``lamp.suites.checks``) run on a coarser lattice than the paper's families:
``RESOLUTION`` m cells and ``N_HEADINGS`` headings for the route search, ``REACH_RESOLUTION``
m cells for robot reachability. What they guarantee is unchanged by the resolution: a
route found is certified free with its clearance everywhere (bisection-certified straight
SE(2) motions), and a robot reported as reaching the object can (4-neighbour moves between
cells whose exact clearance bounds the motion). A coarse lattice can only miss routes
(report none, or a longer one than exists), so the reported lengths are upper bounds on
the shortest routes keeping each clearance.

Every scene is a pure function of its index: ``np.random.default_rng([SUITE_SEED,
STREAM, index])``, with rejected attempts drawn from the same stream.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lamp.scene.model import Scene, shape_from_dict
from lamp.suites import checks as C
from lamp.suites.generators import parse_scene, place_robots, scene_dict
from lamp.suites.layout import (
    END_CLEARANCE,
    ROBOT_RADIUS,
    SUITE_SEED,
    ObjectSpec,
    circle,
    obstacles_of,
    rect,
    rnd,
    sample_object,
    wrap_angle,
)

NAME = "warehouse-xl"
N_SCENES = 25
#: the family's random stream: ``default_rng([SUITE_SEED, STREAM, index])`` (the paper's
#: families use streams 0-3)
STREAM = 10
#: range of each side of the hall (m)
SIDE_RANGE = (20.0, 50.0)
#: the object's start and goal are at least this far apart (straight line, m)
MIN_SPAN = 18.0
#: accepted length range (m) of the free route
ROUTE_RANGE = (20.0, 70.0)
#: an aisle is wider than the object by at least this much: two robot diameters
AISLE_MIN_EXTRA = 4 * ROBOT_RADIUS
#: route lattice resolution (m), headings per symmetry period, reachability grid (m)
RESOLUTION = 0.05
N_HEADINGS = 16
REACH_RESOLUTION = 0.05
#: clearance ladder of the route profile (the paper families' ladder)
CLEARANCE_LADDER = C.CLEARANCE_LADDER
MAX_ATTEMPTS = 20


def scene_name(index: int) -> str:
    return f"{NAME}-{index + 1:02d}"


@dataclass
class XLLayout:
    """A generated hall: workspace, obstacle dicts, crossing sites (x, y, heading): the
    dock band's crossings first (``info["cross_aisles"]`` of them), then the aisles'."""

    workspace: tuple[float, float]
    obstacles: list[dict[str, Any]]
    sites: np.ndarray
    info: dict[str, Any]
    #: widths (m) of the aisles between shelf rows and of the cross-aisles
    aisle_widths: tuple[float, ...] = ()


def _aisle(rng: np.random.Generator, obj: ObjectSpec) -> float:
    """An aisle for this object: object width + 2 robot diameters + 0.25-0.9 m, and wide
    enough for a rectangle to turn a right-angle corner with robot room."""
    s = obj.width + AISLE_MIN_EXTRA + rng.uniform(0.25, 0.9)
    if not obj.is_circle:
        turn = (0.5 * obj.length + obj.width + 0.375) / math.sqrt(2.0) + 0.1
        s = max(s, turn, obj.length + 0.4)
    return s


def _xl_rows(rng: np.random.Generator, obj: ObjectSpec, Lv: float, dock: float
             ) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """(v0, v1) of the shelf rows and of the aisles (the dock band first) alternating up to
    the far wall; the last aisle takes what is left."""
    rows: list[tuple[float, float]] = []  # (v0, v1) of shelf rows
    aisles_v: list[tuple[float, float]] = [(0.0, dock)]
    pos = dock
    while True:
        depth = rng.uniform(0.8, 1.4)
        a = _aisle(rng, obj)
        if pos + depth + a > Lv:
            break
        rows.append((pos, pos + depth))
        aisles_v.append((pos + depth, pos + depth + a))
        pos += depth + a
    # the last aisle takes what is left up to the far wall
    v0, _ = aisles_v[-1]
    aisles_v[-1] = (v0, Lv)
    return rows, aisles_v


def _xl_cross_aisles(rng: np.random.Generator, obj: ObjectSpec, Lu: float
                     ) -> list[tuple[float, float]]:
    """(u0, u1) of the cross-aisles: an end aisle at each side wall, bays of 5-12 m between."""
    cross: list[tuple[float, float]] = []
    a = _aisle(rng, obj)
    cross.append((0.0, a))
    pos = a
    while True:
        bay = rng.uniform(5.0, 12.0)
        a = _aisle(rng, obj)
        if pos + bay + a > Lu - 3.0:
            break
        cross.append((pos + bay, pos + bay + a))
        pos += bay + a
    a = _aisle(rng, obj)
    cross.append((Lu - a, Lu))
    return cross


def _xl_shelves(rng: np.random.Generator, rows: list[tuple[float, float]],
                bays: list[tuple[float, float]]) -> list[dict[str, Any]]:
    """The shelves: in each row, one or two shelf units per bay."""
    obstacles: list[dict[str, Any]] = []
    for r0, r1 in rows:
        for b0, b1 in bays:
            # a shelf row bay is one or two shelf units
            if b1 - b0 > 8.0 and rng.random() < 0.5:
                m = rng.uniform(b0 + 3.0, b1 - 3.0)
                obstacles.append(_box(b0, m - 0.05, r0, r1))
                obstacles.append(_box(m + 0.05, b1, r0, r1))
            else:
                obstacles.append(_box(b0, b1, r0, r1))
    return obstacles


def _xl_pallets(rng: np.random.Generator, obj: ObjectSpec, aisles_v: list[tuple[float, float]],
                bays: list[tuple[float, float]], obstacles: list[Any]) -> tuple[int, int]:
    """Append pallets in the aisle bays between shelf rows (not the dock band or the last
    aisle): stacks filling an aisle across, or pallets against one side leaving robot room.
    Returns (stacks across, pallets aside)."""
    plugged = 0
    narrowed = 0
    for k in range(1, len(aisles_v) - 1):
        w0, w1 = aisles_v[k]
        for b0, b1 in bays:
            x = rng.random()
            if x < 0.12:  # a pallet stack filling the aisle across
                ln = rng.uniform(0.8, 1.2)
                if b1 - b0 < 2 * ln + 0.1:
                    continue
                um = rng.uniform(b0 + ln, b1 - ln)
                obstacles.append(_box(um - ln / 2, um + ln / 2, w0, w1))
                plugged += 1
            elif x < 0.55:  # pallets against one side, leaving robot room
                fill_max = (w1 - w0) - (obj.width + 2 * C.ROBOT_ROOM + 0.06)
                if fill_max < 0.2:
                    continue
                for _ in range(int(rng.integers(1, 3))):
                    fill = rng.uniform(0.2, min(0.8, fill_max))
                    ln = rng.uniform(0.8, 1.2)
                    if b1 - b0 < 2 * ln + 0.1:
                        continue
                    um = rng.uniform(b0 + ln, b1 - ln)
                    if rng.random() < 0.5:
                        obstacles.append(_box(um - ln / 2, um + ln / 2, w0, w0 + fill))
                    else:
                        obstacles.append(_box(um - ln / 2, um + ln / 2, w1 - fill, w1))
                    narrowed += 1
    return plugged, narrowed


def _xl_dock_cargo(rng: np.random.Generator, obj: ObjectSpec, Lu: float, dock: float,
                   obstacles: list[Any]) -> None:
    """Append cargo (boxes, and barrels as ``("circle", u, v, r)``) against the dock wall,
    leaving most of the band free."""
    room = dock - (obj.width + 2 * END_CLEARANCE + 2 * C.ROBOT_ROOM)
    for _ in range(int(rng.integers(4, 12))):
        if room < 0.3:
            break
        depth = rng.uniform(0.3, min(0.8, room))
        ln = rng.uniform(0.5, 1.2)
        um = rng.uniform(ln / 2, Lu - ln / 2)
        if rng.random() < 0.35:
            obstacles.append(("circle", um, depth / 2, depth / 2))
        else:
            obstacles.append(_box(um - ln / 2, um + ln / 2, 0.0, depth))


def layout_xl(rng: np.random.Generator, obj: ObjectSpec) -> XLLayout:
    """Shelf rows along u, aisles between them, cross-aisles across; then transposed or
    mirrored at random (the frame (u, v) maps to (x, y) or (y, x))."""
    Lu = rnd(rng.uniform(*SIDE_RANGE), 1)
    Lv = rnd(rng.uniform(*SIDE_RANGE), 1)
    dock = rng.uniform(1.5, 2.5)
    # rows: shelf depth / aisle alternating above the dock band
    rows, aisles_v = _xl_rows(rng, obj, Lv, dock)
    cross = _xl_cross_aisles(rng, obj, Lu)
    bays = [(cross[k][1], cross[k + 1][0]) for k in range(len(cross) - 1)]
    obstacles: list[Any] = _xl_shelves(rng, rows, bays)
    plugged, narrowed = _xl_pallets(rng, obj, aisles_v, bays, obstacles)
    _xl_dock_cargo(rng, obj, Lu, dock, obstacles)
    # sites: centres of the crossings of the aisles with the cross-aisles
    sites = [
        (0.5 * (c0 + c1), 0.5 * (a0 + a1), 0.0) for a0, a1 in aisles_v for c0, c1 in cross
    ]
    transpose = bool(rng.random() < 0.5)
    flip_u = bool(rng.random() < 0.5)
    flip_v = bool(rng.random() < 0.5)

    def to_xy(u: float, v: float) -> tuple[float, float]:
        u = Lu - u if flip_u else u
        v = Lv - v if flip_v else v
        return (v, u) if transpose else (u, v)

    out: list[dict[str, Any]] = []
    for ob in obstacles:
        if isinstance(ob, tuple):  # barrel
            _, u, v, r = ob
            x, y = to_xy(u, v)
            out.append(circle(x, y, r))
        else:
            u0, u1, v0_, v1_ = ob["box"]
            x0, y0 = to_xy(u0, v0_)
            x1, y1 = to_xy(u1, v1_)
            out.append(rect(0.5 * (x0 + x1), 0.5 * (y0 + y1), abs(x1 - x0), abs(y1 - y0)))
    site_xy = np.array(
        [[*to_xy(u, v), 0.5 * math.pi if transpose else 0.0] for u, v, _ in sites]
    )
    W, H = (Lv, Lu) if transpose else (Lu, Lv)
    info = {
        "workspace": [W, H],
        "shelf_rows": len(rows),
        "cross_aisles": len(cross),
        "pallets_across": plugged,
        "pallets_aside": narrowed,
        "transposed": transpose,
    }
    widths = tuple(b - a for a, b in [*aisles_v[1:], *cross])
    return XLLayout((W, H), out, site_xy, info, widths)


def _box(u0: float, u1: float, v0: float, v1: float) -> dict[str, Any]:
    return {"box": (u0, u1, v0, v1)}


def _place(
    rng: np.random.Generator, obj: ObjectSpec, world: C.World, site: np.ndarray
) -> np.ndarray | None:
    """A pose near a crossing with clearance >= END_CLEARANCE (None when none found)."""
    shape = shape_from_dict(obj.shape)
    for t in range(30):
        j = 0.15 if t < 25 else 0.0
        th = 0.0
        if not obj.is_circle:
            th = (
                wrap_angle(site[2] + 0.5 * math.pi * int(rng.integers(4)))
                if rng.random() < 0.5 or t >= 27
                else rng.uniform(-math.pi, math.pi)
            )
        pose = np.array(
            [rnd(site[0] + rng.uniform(-j, j)), rnd(site[1] + rng.uniform(-j, j)), rnd(th, 4)]
        )
        if C.clearance(shape, world, pose) >= END_CLEARANCE:
            return pose
    return None


@dataclass
class GeneratedXL:
    """A generated warehouse-xl scene with its file dict, loaded Scene and check report."""

    index: int
    scene_dict: dict[str, Any]
    scene: Scene
    report: C.ObjectReport
    attempts: int
    layout_info: dict[str, Any]


def route_finder(scene: Scene) -> C.RouteFinder:
    """The family's route search for the scene's object (coarse lattice)."""
    return C.RouteFinder(
        scene.objects[0].shape, C.object_world(scene, 0), RESOLUTION, N_HEADINGS
    )


def generate_scene(index: int, *, full_checks: bool = True) -> GeneratedXL:
    """Generate scene ``index`` (0-based); deterministic in ``index``.

    The accepted scene loads, has a free route (clearance >= FREE_CLEARANCE) of
    ``ROUTE_RANGE`` length and a robot-room route (clearance >= ROBOT_ROOM), and every
    robot reaches the object's contact ring. ``full_checks=False`` skips the clearance
    ladder and keeps the cheaper checks (tests that only compare the scene dict).
    """
    if not (isinstance(index, int) and 0 <= index < N_SCENES):
        raise ValueError(f"index must be an int in [0, {N_SCENES}), got {index!r}")
    rng = np.random.default_rng([SUITE_SEED, STREAM, index])
    obj = sample_object(rng, index)
    name = scene_name(index)
    rejected: dict[str, int] = {}

    def reject(why: str) -> None:
        rejected[why] = rejected.get(why, 0) + 1

    for attempt in range(1, MAX_ATTEMPTS + 1):
        lay = layout_xl(rng, obj)
        s = lay.sites
        eu = np.hypot(s[:, None, 0] - s[None, :, 0], s[:, None, 1] - s[None, :, 1])
        cand = np.argwhere(eu >= MIN_SPAN)
        if len(cand) == 0:
            reject("no far-apart crossings")
            continue
        a, b = cand[int(rng.integers(len(cand)))]
        world = C.build_world(lay.workspace, obstacles_of(lay.obstacles))
        start = _place(rng, obj, world, s[a])
        goal = _place(rng, obj, world, s[b])
        if start is None or goal is None:
            reject("no start/goal pose")
            continue
        robots = place_robots(rng, world, shape_from_dict(obj.shape), start, obj.reach,
                              lay.workspace)
        if robots is None:
            reject("no robot starts")
            continue
        d = scene_dict(name, lay.workspace, robots, lay.obstacles, obj.shape, start, goal)
        scene = parse_scene(d)
        if scene is None:
            reject("invalid scene")
            continue
        finder = route_finder(scene)
        free = finder.find(start, goal, C.FREE_CLEARANCE)
        if free is None:
            reject("no free route")
            continue
        if not ROUTE_RANGE[0] <= free.length <= ROUTE_RANGE[1]:
            reject("free route length out of range")
            continue
        roomy = finder.find(start, goal, C.ROBOT_ROOM)
        if roomy is None:
            reject("no robot-room route")
            continue
        reach = C.robot_reach(scene, 0, resolution=REACH_RESOLUTION, ring_width=0.06)
        if not reach.all_reach or reach.ring_fraction < 0.5:
            reject("robots cannot reach the object")
            continue
        known = {C.FREE_CLEARANCE: free, C.ROBOT_ROOM: roomy}
        if full_checks:
            report = check_object(scene, finder, known)
        else:
            report = C.ObjectReport(0, 0.0, 0.0, free, roomy, {}, reach)
        return GeneratedXL(index, d, scene, report, attempt, lay.info)
    raise RuntimeError(
        f"{name}: no valid scene after {MAX_ATTEMPTS} attempts (rejected: {rejected})"
    )


def check_object(
    scene: Scene,
    finder: C.RouteFinder | None = None,
    known: dict[float, C.Route | None] | None = None,
) -> C.ObjectReport:
    """The checks of ``checks.check_object`` with this family's resolutions: routes on
    the coarse lattice for every clearance of ``CLEARANCE_LADDER``, reachability on the
    ``REACH_RESOLUTION`` grid."""
    obj = scene.objects[0]
    finder = route_finder(scene) if finder is None else finder
    routes = dict(known or {})

    def route(t: float) -> C.Route | None:
        for k, v in routes.items():
            if math.isclose(k, t):
                return v
        routes[t] = finder.find(obj.start, obj.goal, t)
        return routes[t]

    c_start, c_goal = C.clearance(obj.shape, finder.world, np.array([obj.start, obj.goal]))
    free = route(C.FREE_CLEARANCE)
    roomy = route(C.ROBOT_ROOM) if free is not None else None
    profile: dict[float, float | None] = {}
    for t in CLEARANCE_LADDER:
        rt = route(t) if free is not None else None
        profile[t] = None if rt is None else rt.length
    reach = C.robot_reach(scene, 0, resolution=REACH_RESOLUTION, ring_width=0.06)
    return C.ObjectReport(0, float(c_start), float(c_goal), free, roomy, profile, reach)
