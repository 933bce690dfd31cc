"""Pieces of the ``fleet`` family (``lamp.suites.fleet``): its objects, the placement of
their starts and goals, the robot team, and its rooms maps (the open yard and the door
swap are ``lamp.suites.fleet_open``, the warehouse kinds ``lamp.suites.fleet_warehouse``).

What the pieces guarantee, for every pose they return:

* an object pose keeps exact clearance >= ``END_CLEARANCE`` from the static obstacles and
  the border, and its footprint stays >= ``OBJECT_GAP`` from every start and goal
  footprint placed before it (every object's start and goal, the object's own included)
  and >= ``ZONE_GAP`` from the keep-out zones (door mouths, shelf slots and lanes), unless
  a layout places it inside its own slot or lane on purpose;
* a robot start keeps >= ``ROBOT_MARGIN`` beyond its radius from the static obstacles,
  the border and every start and goal footprint, lies outside every keep-out zone and
  >= 2 radii + ``ROBOT_SPACING`` from every other robot.

Doors are as wide as the widest object across plus two robot diameters plus
``DOOR_EXTRA`` (the warehouse families' aisle rule), so an object passes with a robot on
either side.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely

from lamp.geometry.shapes import narrowest_width, to_shapely
from lamp.scene.model import Obstacle, Shape, shape_from_dict
from lamp.suites import checks as C
from lamp.suites.layout import END_CLEARANCE, ROBOT_RADIUS, obstacles_of, rect, rnd

#: object extents (m): circle diameters, rectangle sides, polygon widths and diameters
OBJECT_RANGE = (0.2, 0.6)
#: least distance (m) between any two start / goal footprints: robots fit between them
OBJECT_GAP = 0.3
#: least distance (m) of an object footprint from a keep-out zone
ZONE_GAP = 0.05
#: a door (or aisle) is wider than the widest object across by 2 robot diameters + this
DOOR_EXTRA = (0.25, 0.6)
DOOR_MIN_EXTRA = 4 * ROBOT_RADIUS
#: depth (m) of a door's keep-out zone on either side of the wall
DOOR_APPROACH = 0.6
#: robot starts: clearance beyond the radius, and spacing beyond touching (m)
ROBOT_MARGIN = 0.03
ROBOT_SPACING = 0.05
#: robots start this far (m) beyond their anchor object's bounding circle
ROBOT_RING = (0.1, 1.2)

Box = tuple[float, float, float, float]


# --------------------------------------------------------------------------- objects
@dataclass(frozen=True)
class FleetObject:
    """An object: its scene-file shape dict, the Shape, narrowest width (``across``),
    diameter (``along``: largest extent) and bounding radius (``reach``)."""

    shape: dict[str, Any]
    geom: Shape
    across: float
    along: float
    reach: float

    @property
    def kind(self) -> str:
        return str(self.shape["type"])


def make_object(shape: dict[str, Any]) -> FleetObject:
    geom = shape_from_dict(shape)
    if shape["type"] == "circle":
        d = 2.0 * shape["radius"]
        return FleetObject(shape, geom, d, d, 0.5 * d)
    if shape["type"] == "rectangle":
        a, b = shape["size"]
        return FleetObject(shape, geom, min(a, b), max(a, b), 0.5 * math.hypot(a, b))
    pts = np.asarray(shape["points"], float)
    diam = float(np.max(np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))))
    return FleetObject(shape, geom, narrowest_width(geom), diam,
                       float(np.max(np.hypot(pts[:, 0], pts[:, 1]))))


def sample_object(rng: np.random.Generator, kind: str,
                  lo: float = OBJECT_RANGE[0], hi: float = OBJECT_RANGE[1]) -> FleetObject:
    """A ``kind`` object with every extent in [lo, hi]: a circle of diameter in [lo, hi], a
    rectangle with sides in [lo, hi], or a convex polygon (3-6 vertices on a circle of
    diameter <= hi, jittered from regular) at least ``lo`` across."""
    if kind == "circle":
        return make_object({"type": "circle", "radius": rnd(0.5 * rng.uniform(lo, hi))})
    if kind == "rectangle":
        a, b = (rnd(v) for v in rng.uniform(lo, hi, size=2))
        return make_object({"type": "rectangle", "size": [a, b]})
    while True:
        n = int(rng.integers(3, 7))
        big = rng.uniform(lo, hi)
        step = 2.0 * math.pi / n
        ang = rng.uniform(0, step) + step * np.arange(n) + rng.uniform(-0.2, 0.2, n) * step
        pts = [[rnd(0.5 * big * math.cos(a)), rnd(0.5 * big * math.sin(a))] for a in ang]
        obj = make_object({"type": "polygon", "points": pts})
        if lo <= obj.across and obj.along <= hi:
            return obj


# --------------------------------------------------------------------------- placement
def box_geom(b: Box) -> shapely.Geometry:
    return shapely.box(*b)


class Placer:
    """Start / goal poses with the clearances of the module docstring (see there)."""

    def __init__(self, workspace: tuple[float, float], obstacles: list[dict[str, Any]]):
        self.workspace = workspace
        self.obstacles = obstacles
        self.world = C.build_world(workspace, obstacles_of(obstacles))
        self.zones: list[shapely.Geometry] = []
        self.zone_boxes: list[Box] = []
        self.footprints: list[tuple[Shape, np.ndarray]] = []
        self._geoms: list[shapely.Geometry] = []

    def add_zone(self, b: Box) -> None:
        self.zone_boxes.append(b)
        self.zones.append(box_geom(b))

    def fits(self, obj: FleetObject, pose: np.ndarray, zones: bool = True) -> bool:
        if C.clearance(obj.geom, self.world, pose) < END_CLEARANCE:
            return False
        g = to_shapely(obj.geom, pose)
        if zones and any(g.distance(z) < ZONE_GAP for z in self.zones):
            return False
        return all(g.distance(p) >= OBJECT_GAP for p in self._geoms)

    def add(self, obj: FleetObject, pose: np.ndarray) -> np.ndarray:
        self.footprints.append((obj.geom, pose))
        self._geoms.append(to_shapely(obj.geom, pose))
        return pose

    def forget(self, n: int) -> None:
        """Take back the last ``n`` poses added."""
        del self.footprints[len(self.footprints) - n:], self._geoms[len(self._geoms) - n:]

    def place(self, obj: FleetObject, pose: np.ndarray, zones: bool = True) -> np.ndarray | None:
        """``pose`` (rounded) added when it fits, else None."""
        pose = np.array([rnd(pose[0]), rnd(pose[1]), rnd(pose[2], 4)])
        return self.add(obj, pose) if self.fits(obj, pose, zones) else None

    def sample(self, rng: np.random.Generator, obj: FleetObject, box: Box,
               near: tuple[float, float, float, float] | None = None,
               tries: int = 60) -> np.ndarray | None:
        """A pose in ``box`` (the centre keeps ``obj.reach`` inside it), added when found;
        ``near = (x, y, dmin, dmax)`` keeps the centre dmin..dmax from (x, y)."""
        x0, y0, x1, y1 = box
        m = obj.reach + 0.5 * END_CLEARANCE
        if x1 - x0 <= 2 * m or y1 - y0 <= 2 * m:
            return None
        for _ in range(tries):
            if near is None:
                x, y = rng.uniform(x0 + m, x1 - m), rng.uniform(y0 + m, y1 - m)
            else:
                a, d = rng.uniform(-math.pi, math.pi), rng.uniform(near[2], near[3])
                x, y = near[0] + d * math.cos(a), near[1] + d * math.sin(a)
                if not (x0 + m <= x <= x1 - m and y0 + m <= y <= y1 - m):
                    continue
            th = heading(rng, obj)
            pose = self.place(obj, np.array([x, y, th]))
            if pose is not None:
                return pose
        return None


def heading(rng: np.random.Generator, obj: FleetObject) -> float:
    """0 for circles; else axis-aligned half the time, any heading otherwise."""
    if obj.kind == "circle":
        return 0.0
    if rng.random() < 0.5:
        return 0.5 * math.pi * int(rng.integers(-1, 3))
    return rng.uniform(-math.pi, math.pi)


def place_team(rng: np.random.Generator, placer: Placer, anchors: list[np.ndarray],
               reaches: list[float], n: int) -> list[list[float]] | None:
    """``n`` robot starts (module docstring), robot ``i`` near anchor ``i % len(anchors)``
    (``ROBOT_RING`` beyond its bounding circle), else anywhere in the workspace."""
    W, H = placer.workspace
    foot = C.build_world(placer.workspace, [Obstacle(s, tuple(float(v) for v in p))
                                            for s, p in placer.footprints])
    need = ROBOT_RADIUS + ROBOT_MARGIN
    out: list[np.ndarray] = []

    def ok(p: np.ndarray) -> bool:
        if not (need <= p[0] <= W - need and need <= p[1] <= H - need):
            return False
        if min(C.point_clearance(placer.world, p), C.point_clearance(foot, p)) < need:
            return False
        if any(math.dist(p, q) < 2 * ROBOT_RADIUS + ROBOT_SPACING for q in out):
            return False
        pt = shapely.Point(p)
        return all(pt.distance(z) >= ROBOT_RADIUS for z in placer.zones)

    for i in range(n):
        a = anchors[i % len(anchors)]
        for t in range(200):
            if t < 120:
                ang = rng.uniform(-math.pi, math.pi)
                d = reaches[i % len(anchors)] + ROBOT_RADIUS + rng.uniform(*ROBOT_RING)
                p = np.array([rnd(a[0] + d * math.cos(ang)), rnd(a[1] + d * math.sin(ang))])
            else:
                p = np.array([rnd(rng.uniform(0, W)), rnd(rng.uniform(0, H))])
            if ok(p):
                out.append(p)
                break
        else:
            return None
    return [[float(v) for v in q] for q in out]


# --------------------------------------------------------------------------- layouts
@dataclass
class FleetLayout:
    """A map with its objects placed: workspace, obstacle dicts, objects in scene order
    with starts, goals and ``after`` lists, the placer (its keep-out zones keep robots
    out of doors and slots) and a summary for the manifest."""

    workspace: tuple[float, float]
    obstacles: list[dict[str, Any]]
    objects: list[FleetObject]
    starts: list[np.ndarray]
    goals: list[np.ndarray]
    placer: Placer
    info: dict[str, Any]
    after: list[tuple[int, ...]] = field(default_factory=list)


def door_width(rng: np.random.Generator, objects: list[FleetObject]) -> float:
    """The widest object across + two robot diameters + ``DOOR_EXTRA``."""
    return max(o.across for o in objects) + DOOR_MIN_EXTRA + rng.uniform(*DOOR_EXTRA)


def _splits(rng: np.random.Generator, length: float, n: int) -> list[float]:
    """n + 1 cell boundaries from 0 to ``length``, inner ones jittered by +-15 %."""
    cell = length / n
    return [0.0, *(cell * (i + rng.uniform(-0.15, 0.15)) for i in range(1, n)), length]


def _door_graph(rng: np.random.Generator, nc: int, nr: int) -> set[tuple[int, int]]:
    """Doors between grid rooms (room id = row * nc + col): a random spanning tree plus
    each other neighbour pair with probability 0.35."""
    pairs = [(r * nc + c, r * nc + c + 1) for r in range(nr) for c in range(nc - 1)]
    pairs += [(r * nc + c, (r + 1) * nc + c) for r in range(nr - 1) for c in range(nc)]
    order = [pairs[i] for i in rng.permutation(len(pairs))]
    root = list(range(nc * nr))

    def find(a: int) -> int:
        while root[a] != a:
            a = root[a]
        return a

    doors = set()
    for a, b in order:
        if find(a) != find(b):
            root[find(a)] = find(b)
            doors.add((a, b))
        elif rng.random() < 0.35:
            doors.add((a, b))
    return doors


def _hops(doors: set[tuple[int, int]], n: int, src: int) -> list[int]:
    adj: list[list[int]] = [[] for _ in range(n)]
    for a, b in doors:
        adj[a].append(b)
        adj[b].append(a)
    dist = [-1] * n
    dist[src] = 0
    queue = deque([src])
    while queue:
        u = queue.popleft()
        for v in adj[u]:
            if dist[v] < 0:
                dist[v] = dist[u] + 1
                queue.append(v)
    return dist


def wall(lo: float, hi: float, at: float, t: float, vertical: bool,
          door: tuple[float, float] | None) -> list[dict[str, Any]]:
    """A wall of thickness t on the line x = at (vertical) or y = at from lo to hi, with a
    door gap (c, width) when given."""
    spans = [(lo, hi)] if door is None else [(lo, door[0] - 0.5 * door[1]),
                                             (door[0] + 0.5 * door[1], hi)]
    out = []
    for a, b in spans:
        if b - a > 1e-3:
            out.append(rect(at, 0.5 * (a + b), t, b - a) if vertical
                       else rect(0.5 * (a + b), at, b - a, t))
    return out


def layout_rooms(rng: np.random.Generator, ws: tuple[float, float],
                 objects: list[FleetObject]) -> FleetLayout | None:
    """A grid of rooms (3-6 m each on a small map, up to 6-12 m on a 50 m one) behind walls, a door in the wall between
    each pair of rooms on a random spanning tree (and some others); every object goes from
    one room to a room one or two doors away, away from the door mouths."""
    W, H = ws
    grow = 1.0 + max(W, H) / 50.0
    nc = max(1, round(W / (grow * rng.uniform(3.0, 6.0))))
    nr = max(1 if nc > 1 else 2, round(H / (grow * rng.uniform(3.0, 6.0))))
    xs, ys = _splits(rng, W, nc), _splits(rng, H, nr)
    t = rng.uniform(0.1, 0.2)
    dw = door_width(rng, objects)
    doors = _door_graph(rng, nc, nr)
    obstacles: list[dict[str, Any]] = []
    zones: list[Box] = []
    for r in range(nr):
        for c in range(nc):
            me = r * nc + c
            if c + 1 < nc:  # wall to the right: x = xs[c + 1], y in row r
                lo, hi = ys[r], ys[r + 1]
                door = None
                if (me, me + 1) in doors:
                    d = rng.uniform(lo + 0.4 + 0.5 * dw, hi - 0.4 - 0.5 * dw)
                    door = (d, dw)
                    zones.append((xs[c + 1] - 0.5 * t - DOOR_APPROACH, d - 0.5 * dw,
                                  xs[c + 1] + 0.5 * t + DOOR_APPROACH, d + 0.5 * dw))
                obstacles += wall(lo, hi, xs[c + 1], t, True, door)
            if r + 1 < nr:  # wall above: y = ys[r + 1], x in column c
                lo, hi = xs[c], xs[c + 1]
                door = None
                if (me, me + nc) in doors:
                    d = rng.uniform(lo + 0.4 + 0.5 * dw, hi - 0.4 - 0.5 * dw)
                    door = (d, dw)
                    zones.append((d - 0.5 * dw, ys[r + 1] - 0.5 * t - DOOR_APPROACH,
                                  d + 0.5 * dw, ys[r + 1] + 0.5 * t + DOOR_APPROACH))
                obstacles += wall(lo, hi, ys[r + 1], t, False, door)
    rooms = [(xs[c] + 0.5 * t, ys[r] + 0.5 * t, xs[c + 1] - 0.5 * t, ys[r + 1] - 0.5 * t)
             for r in range(nr) for c in range(nc)]
    _furnish(rng, rooms, zones, obstacles)
    placer = Placer(ws, obstacles)
    for z in zones:
        placer.add_zone(z)
    starts, goals = [], []
    n = nc * nr
    for obj in objects:
        a = int(rng.integers(n))
        hops = _hops(doors, n, a)
        far = [b for b in range(n) if hops[b] == (2 if rng.random() < 0.3 else 1)]
        far = far or [b for b in range(n) if hops[b] == 1]
        b = far[int(rng.integers(len(far)))]
        s = placer.sample(rng, obj, rooms[a])
        g = placer.sample(rng, obj, rooms[b]) if s is not None else None
        if g is None:
            return None
        starts.append(s)
        goals.append(g)
    info = {"rooms": [nc, nr], "doors": len(doors), "door_width": round(dw, 3),
            "wall_thickness": round(t, 3)}
    return FleetLayout(ws, obstacles, objects, starts, goals, placer, info)


def _furnish(rng: np.random.Generator, rooms: list[Box], zones: list[Box],
             obstacles: list[dict[str, Any]]) -> None:
    """Up to two pieces of furniture (boxes 0.4-1.2 x 0.3-0.7 m) against the walls of
    each room of at least 2.5 m a side, >= 0.5 m from the door zones and each other."""
    placed = [box_geom(z) for z in zones]
    for x0, y0, x1, y1 in rooms:
        if min(x1 - x0, y1 - y0) < 2.5:
            continue
        for _ in range(int(rng.integers(0, 3))):
            a, b = rng.uniform(0.4, 1.2), rng.uniform(0.3, 0.7)
            side = int(rng.integers(4))
            if side < 2:  # against the bottom / top wall
                cx = rng.uniform(x0 + 0.5 * a, x1 - 0.5 * a)
                cy = y0 + 0.5 * b if side == 0 else y1 - 0.5 * b
                sx, sy = a, b
            else:
                cy = rng.uniform(y0 + 0.5 * a, y1 - 0.5 * a)
                cx = x0 + 0.5 * b if side == 2 else x1 - 0.5 * b
                sx, sy = b, a
            g = shapely.box(cx - 0.5 * sx, cy - 0.5 * sy, cx + 0.5 * sx, cy + 0.5 * sy)
            if all(g.distance(p) >= 0.5 for p in placed):
                placed.append(g)
                obstacles.append(rect(cx, cy, sx, sy))
