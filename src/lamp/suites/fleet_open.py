"""The open kinds of the ``fleet`` family (``lamp.suites.fleet``): yards with scattered
posts, containers and rubble, and the door swap (two halls joined by a single door).
Starts and goals are placed by ``fleet_layout.Placer`` (its guarantees hold)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import shapely

from lamp.geometry.shapes import to_shapely
from lamp.scene.model import Shape
from lamp.suites.fleet_layout import (
    DOOR_APPROACH,
    FleetLayout,
    FleetObject,
    Placer,
    box_geom,
    door_width,
    wall,
)
from lamp.suites.layout import circle, obstacles_of, rect, rnd

#: ``layout_on``'s route test: (object, start, goal, footprints placed before it) -> ok
RouteTest = Callable[[FleetObject, np.ndarray, np.ndarray, list[tuple[Shape, np.ndarray]]], bool]


def scatter(rng: np.random.Generator, ws: tuple[float, float], count: int, gap: float,
            avoid: list[shapely.Geometry], big: float = 3.0) -> list[dict[str, Any]]:
    """Up to ``count`` yard obstacles: posts (circles r 0.1-0.35 m), containers and crates
    (rectangles 0.5-``big`` x 0.4-1.5 m, any angle) and rubble (convex polygons 0.4-1.5
    m), each >= ``gap`` from the border, the others and ``avoid``."""
    W, H = ws
    out: list[dict[str, Any]] = []
    geoms = list(avoid)
    for _ in range(4 * count):
        if len(out) >= count:
            break
        x, y, u = rng.uniform(0, W), rng.uniform(0, H), rng.random()
        if u < 0.4:
            d = circle(x, y, rng.uniform(0.1, 0.35))
        elif u < 0.8:
            d = rect(x, y, rng.uniform(0.5, big), rng.uniform(0.4, 1.5),
                     rng.uniform(-math.pi, math.pi))
        else:
            r = rng.uniform(0.2, 0.75)
            ang = np.sort(rng.uniform(0, 2 * math.pi, int(rng.integers(3, 7))))
            if np.max(np.diff(np.r_[ang, ang[0] + 2 * math.pi])) > 0.9 * math.pi:
                continue
            d = {"type": "polygon", "points": [[rnd(x + r * math.cos(a)), rnd(y + r * math.sin(a))]
                                               for a in ang]}
        (ob,) = obstacles_of([d])
        g = to_shapely(ob.shape, ob.pose)
        x0, y0, x1, y1 = g.bounds
        if x0 < gap or y0 < gap or x1 > W - gap or y1 > H - gap:
            continue
        if all(g.distance(o) >= gap for o in geoms):
            geoms.append(g)
            out.append(d)
    return out


def layout_yard(rng: np.random.Generator, ws: tuple[float, float],
                objects: list[FleetObject]) -> FleetLayout | None:
    """An open yard: posts, containers and rubble (0.02-0.05 per square metre) at least
    1.2 m from each other and the fence; every object goes 1.5-12 m in any direction."""
    W, H = ws
    count = min(150, int(W * H * rng.uniform(0.02, 0.05)))
    obstacles = scatter(rng, ws, count, 1.2, [])
    return layout_on(rng, ws, objects, obstacles, {"yard_obstacles": len(obstacles)})


def layout_on(rng: np.random.Generator, ws: tuple[float, float], objects: list[FleetObject],
              obstacles: list[dict[str, Any]], info: dict[str, Any],
              route_ok: RouteTest | None = None, tries: int = 1) -> FleetLayout | None:
    """The objects on a map with these ``obstacles`` (a yard's, or a user's map): each
    starts anywhere and goes 1.5 m to min(12 m, 0.7 x the longer side) in any direction;
    with ``route_ok(obj, start, goal, placed)`` (``placed``: the footprints of the objects
    before it) an object is drawn again, up to ``tries`` times in all, until it passes.
    None when one does not fit."""
    W, H = ws
    placer = Placer(ws, obstacles)
    starts, goals = [], []
    reach = min(12.0, 0.7 * max(W, H))
    for obj in objects:
        for _ in range(tries):
            s = placer.sample(rng, obj, (0.0, 0.0, W, H))
            if s is None:
                return None
            g = placer.sample(rng, obj, (0.0, 0.0, W, H), near=(s[0], s[1], 1.5, reach))
            if g is not None and (route_ok is None
                                  or route_ok(obj, s, g, placer.footprints[:-2])):
                break
            placer.forget(1 if g is None else 2)
        else:
            return None
        starts.append(s)
        goals.append(g)
    return FleetLayout(ws, obstacles, objects, starts, goals, placer, info)


def layout_swap(rng: np.random.Generator, ws: tuple[float, float],
                objects: list[FleetObject]) -> FleetLayout | None:
    """Two halls split by a wall (x = 40-60 % of the width) with one door. Objects 0, 1
    (and 2, 3 and 4, 5 when there are 4 / 8+ objects) swap sides through the door: each
    pair's starts and goals 0.8-3.5 m beyond the door's keep-out zone on either side; the
    others cross with probability 0.3 or stay in their hall, 1.5-10 m away. Some sparse
    clutter (>= 1 m apart) stays >= 1.5 m from the door."""
    W, H = ws
    xs, t = W * rng.uniform(0.4, 0.6), rng.uniform(0.15, 0.3)
    dw = door_width(rng, objects)
    yc = rng.uniform(max(0.2 * H, 0.6 + 0.5 * dw), min(0.8 * H, H - 0.6 - 0.5 * dw))
    obstacles = wall(0.0, H, xs, t, True, (yc, dw))
    zone = (xs - 0.5 * t - DOOR_APPROACH, yc - 0.5 * dw, xs + 0.5 * t + DOOR_APPROACH,
            yc + 0.5 * dw)
    walls = [box_geom((xs - 0.5 * t, 0.0, xs + 0.5 * t, H)), box_geom(zone).buffer(1.5)]
    obstacles += scatter(rng, ws, int(W * H * rng.uniform(0.005, 0.02)), 1.0, walls, 1.5)
    placer = Placer(ws, obstacles)
    placer.add_zone(zone)
    halls = [(0.0, 0.0, xs - 0.5 * t, H), (xs + 0.5 * t, 0.0, W, H)]
    n_pairs = 1 + (len(objects) >= 4) + (len(objects) >= 8)
    mouths = [(xs - 0.5 * t - DOOR_APPROACH, yc), (xs + 0.5 * t + DOOR_APPROACH, yc)]
    starts, goals = [], []
    for k, obj in enumerate(objects):
        side = k % 2 if k < 2 * n_pairs else int(rng.integers(2))
        if k < 2 * n_pairs:
            got = []
            for e in (side, 1 - side):
                lo = obj.reach + 0.8
                got.append(placer.sample(rng, obj, halls[e], near=(*mouths[e], lo, lo + 2.7)))
                if got[-1] is None:
                    return None
            s, g = got
        else:
            other = 1 - side if rng.random() < 0.3 else side
            s = placer.sample(rng, obj, halls[side])
            cx = None if s is None else (s[0], s[1], 1.5, 10.0)
            g = None if s is None else placer.sample(
                rng, obj, halls[other], near=cx if other == side else None)
            if g is None:
                return None
        starts.append(s)
        goals.append(g)
    info = {"wall_x": round(xs, 3), "door_y": round(yc, 3), "door_width": round(dw, 3),
            "wall_thickness": round(t, 3), "swap_pairs": n_pairs,
            "clutter": len(obstacles) - 2}
    return FleetLayout(ws, obstacles, objects, starts, goals, placer, info)
