"""Geometry of the ``corridor`` family's maps: one narrow corridor with turning bays
between a start room and a goal room, and the walls that fill the rest of the workspace.

The free region is the union of

* a *start room* and a *goal room*: rectangles aligned with the first / last leg, the
  corridor's mouth on one of their walls;
* the *legs*: strips of width ``width`` along straight segments of the centreline;
* a *bay* at every turn: a regular ``BAY_SIDES``-gon centred on the turn vertex whose
  inscribed circle has the bay's radius.

Walls are the workspace minus that region, cut into simple polygons (no holes) along a
grid of cells (``wall_polygons``): a piece of a cell can only have a hole when the whole
free region lies inside that cell (the free region is connected), and such a cell is cut
again into quarters. Wall points are snapped to the millimetre grid of the scene files;
the free region is grown by ``SNAP_PAD`` first, so snapping never moves a wall into it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from shapely.geometry.polygon import orient

#: sides of the regular polygon of a turning bay
BAY_SIDES = 24
#: wall cells are at most this large (m) before pieces with holes are cut again
WALL_CELL = 3.0
#: the free region is grown by this much (m) before the walls are snapped to 1 mm
SNAP_PAD = 0.0008
#: scene files hold positions to the millimetre
SNAP_GRID = 0.001


def unit(angle: float) -> np.ndarray:
    return np.array([math.cos(angle), math.sin(angle)])


def strip(a: np.ndarray, b: np.ndarray, width: float) -> shapely.Polygon:
    """The rectangle of ``width`` around the segment a -> b."""
    d = b - a
    n = np.array([-d[1], d[0]]) / math.hypot(*d) * 0.5 * width
    return shapely.Polygon([a - n, b - n, b + n, a + n])


def bay(center: np.ndarray, radius: float, phase: float) -> shapely.Polygon:
    """Regular ``BAY_SIDES``-gon centred on ``center`` whose inscribed circle has ``radius``
    (so it contains the disk of that radius)."""
    circum = radius / math.cos(math.pi / BAY_SIDES)
    a = phase + 2.0 * math.pi * np.arange(BAY_SIDES) / BAY_SIDES
    return shapely.Polygon(np.stack([center[0] + circum * np.cos(a),
                                     center[1] + circum * np.sin(a)], axis=1))


def room(mouth: np.ndarray, angle: float, u: tuple[float, float],
         v: tuple[float, float]) -> shapely.Polygon:
    """The rectangle ``u0 <= u <= u1, v0 <= v <= v1`` in the frame at ``mouth`` whose u
    axis points along ``angle``."""
    eu, ev = unit(angle), unit(angle + 0.5 * math.pi)
    corners = [(u[0], v[0]), (u[1], v[0]), (u[1], v[1]), (u[0], v[1])]
    return shapely.Polygon([mouth + cu * eu + cv * ev for cu, cv in corners])


def bay_radius(rotate_radius: float, width: float, turn: float, wall: float) -> float:
    """Radius of a bay: room to rotate (``rotate_radius``), and at least ``wall`` of wall
    between the two legs where they leave the bay.

    The legs' inner edges leave a bay of radius R at the angle ``asin(width / 2R)`` from
    their axes; the two exit corners are the closest points of the legs' narrow parts, a
    chord ``2 R sin(a / 2 - asin(width / 2R))`` apart (``a = pi - |turn|`` the angle
    between the legs). It is >= ``wall`` when ``asin(width / 2R) + asin(wall / 2R) <=
    a / 2``; the left side decreases with R, so bisection finds the least such R (to
    0.1 mm, rounded up)."""
    half = 0.5 * (math.pi - abs(turn))

    def ok(r: float) -> bool:
        return math.asin(min(1.0, 0.5 * width / r)) + math.asin(min(1.0, 0.5 * wall / r)) \
            <= half

    lo, hi = 0.5 * max(width, wall), 100.0
    if ok(lo):
        return max(rotate_radius, lo)
    while hi - lo > 1e-4:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return max(rotate_radius, hi)


@dataclass(frozen=True)
class Chain:
    """The corridor's centreline: ``vertices`` (start mouth, turn vertices, goal mouth),
    the absolute angle of each leg, the narrow length of each leg (between the ends of
    its rooms / bays) and the radius of each bay (one per turn)."""

    vertices: np.ndarray
    angles: tuple[float, ...]
    lengths: tuple[float, ...]
    radii: tuple[float, ...]

    def __post_init__(self) -> None:
        n = len(self.angles)
        if n < 1 or len(self.lengths) != n or len(self.radii) != n - 1:
            raise ValueError(
                f"need n >= 1 angles, n lengths and n - 1 radii, got {n}, "
                f"{len(self.lengths)}, {len(self.radii)}"
            )
        if self.vertices.shape != (n + 1, 2):
            raise ValueError(f"vertices must have shape ({n + 1}, 2), got {self.vertices.shape}")
        if min(self.lengths) <= 0 or (self.radii and min(self.radii) <= 0):
            raise ValueError("leg lengths and bay radii must be > 0")

    @property
    def turns(self) -> tuple[float, ...]:
        return tuple(b - a for a, b in zip(self.angles[:-1], self.angles[1:], strict=True))

    def shifted(self, d: np.ndarray) -> Chain:
        return Chain(self.vertices + d, self.angles, self.lengths, self.radii)


def chain_from(angles: list[float], lengths: list[float], radii: list[float]) -> Chain:
    """Vertices of the centreline from the start mouth at the origin: a leg reaches from
    the end of one piece (mouth or bay edge) over its narrow length to the next."""
    pts = [np.zeros(2)]
    ends = [0.0, *radii, 0.0]
    for k, (a, ln) in enumerate(zip(angles, lengths, strict=True)):
        pts.append(pts[-1] + (ends[k] + ln + ends[k + 1]) * unit(a))
    return Chain(np.array(pts), tuple(angles), tuple(lengths), tuple(radii))


@dataclass(frozen=True)
class Rooms:
    """Start and goal room extents in their mouth frames (u along the first / last leg,
    pointing into the corridor for the start room and out of it for the goal room)."""

    start_u: tuple[float, float]
    start_v: tuple[float, float]
    goal_u: tuple[float, float]
    goal_v: tuple[float, float]


def free_pieces(chain: Chain, width: float, rooms: Rooms) -> list[shapely.Polygon]:
    """The free region as a sequence of pieces: start room, narrow part of leg 0, bay 1,
    narrow part of leg 1, ..., goal room (consecutive pieces touch; the legs' strips
    reach into the bays and rooms, their narrow parts do not)."""
    v = chain.vertices
    a0, a1 = chain.angles[0], chain.angles[-1]
    start = room(v[0], a0, rooms.start_u, rooms.start_v)
    goal = room(v[-1], a1, rooms.goal_u, rooms.goal_v)
    bays = [bay(v[k + 1], r, chain.angles[k]) for k, r in enumerate(chain.radii)]
    ends = [start, *bays, goal]
    out: list[shapely.Polygon] = [start]
    for k in range(len(chain.angles)):
        a = v[k] - 0.02 * unit(a0) if k == 0 else v[k]
        b = v[k + 1] + 0.02 * unit(a1) if k == len(chain.angles) - 1 else v[k + 1]
        s = strip(a, b, width)
        out.append(s.difference(ends[k]).difference(ends[k + 1]))
        out.append(ends[k + 1])
    return out


def free_region(chain: Chain, width: float, rooms: Rooms) -> shapely.Geometry:
    """Union of rooms, full leg strips and bays."""
    v = chain.vertices
    a0, a1 = chain.angles[0], chain.angles[-1]
    parts = [room(v[0], a0, rooms.start_u, rooms.start_v),
             room(v[-1], a1, rooms.goal_u, rooms.goal_v)]
    parts += [bay(v[k + 1], r, chain.angles[k]) for k, r in enumerate(chain.radii)]
    for k in range(len(chain.angles)):
        a = v[k] - 0.02 * unit(a0) if k == 0 else v[k]
        b = v[k + 1] + 0.02 * unit(a1) if k == len(chain.angles) - 1 else v[k + 1]
        parts.append(strip(a, b, width))
    return shapely.union_all(parts)


def separated(pieces: list[shapely.Polygon], near: float, far: float) -> bool:
    """Pieces two apart in the sequence (the legs on either side of a bay) keep at least
    ``near`` of wall between them, pieces further apart at least ``far``: the corridor
    never runs into itself."""
    for i in range(len(pieces)):
        for j in range(i + 2, len(pieces)):
            if pieces[i].distance(pieces[j]) < (near if j == i + 2 else far):
                return False
    return True


def _cut(region: shapely.Geometry, box: tuple[float, float, float, float],
         out: list[shapely.Polygon]) -> None:
    x0, y0, x1, y1 = box
    part = region.intersection(shapely.box(x0, y0, x1, y1))
    polys = [g for g in shapely.get_parts(part) if isinstance(g, shapely.Polygon)]
    if any(len(p.interiors) for p in polys):
        xm, ym = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        for sub in ((x0, y0, xm, ym), (xm, y0, x1, ym), (x0, ym, xm, y1), (xm, ym, x1, y1)):
            _cut(region, sub, out)
        return
    out.extend(p for p in polys if not p.is_empty)


def wall_polygons(workspace: tuple[float, float], free: shapely.Geometry) -> list[np.ndarray]:
    """Simple polygons (CCW point arrays on the 1 mm grid) covering the workspace minus
    ``free`` grown by ``SNAP_PAD``, cut along cells of at most ``WALL_CELL``."""
    W, H = workspace
    region = shapely.box(0.0, 0.0, W, H).difference(free.buffer(SNAP_PAD, join_style="mitre"))
    nx, ny = math.ceil(W / WALL_CELL), math.ceil(H / WALL_CELL)
    xs, ys = np.linspace(0.0, W, nx + 1), np.linspace(0.0, H, ny + 1)
    pieces: list[shapely.Polygon] = []
    for i in range(nx):
        for j in range(ny):
            _cut(region, (xs[i], ys[j], xs[i + 1], ys[j + 1]), pieces)
    out = []
    for p in pieces:
        snapped = shapely.set_precision(p, SNAP_GRID)
        for g in shapely.get_parts(snapped):
            if not isinstance(g, shapely.Polygon) or g.is_empty or g.area < 1e-6:
                continue
            if g.interiors or not g.is_valid:  # cannot happen after _cut; refuse loudly
                raise ValueError("a wall piece is not a simple polygon")
            g = orient(g, sign=1.0)
            out.append(np.asarray(g.exterior.coords, dtype=float)[:-1])
    return out


def angle_bin_offset(angle: float, bin_width: float) -> float:
    """Distance (rad) from ``angle`` to the nearest multiple of ``bin_width``."""
    r = angle % bin_width
    return min(r, bin_width - r)


def grid_offset(v: float, grid: float) -> float:
    """Distance from ``v`` to the nearest multiple of ``grid``."""
    r = v % grid
    return min(r, grid - r)


def layout_summary(chain: Chain, width: float, rooms: Rooms) -> dict[str, Any]:
    """The manifest's record of the geometry (rounded to 0.1 mm / 1e-4 rad)."""
    v = chain.vertices
    return {
        "legs": [
            {"from": [round(float(x), 4) for x in v[k]],
             "to": [round(float(x), 4) for x in v[k + 1]],
             "angle": round(float(math.remainder(a, 2.0 * math.pi)), 4),
             "length": round(float(ln), 4)}
            for k, (a, ln) in enumerate(zip(chain.angles, chain.lengths, strict=True))
        ],
        "bays": [
            {"center": [round(float(x), 4) for x in v[k + 1]], "radius": round(float(r), 4),
             "turn": round(float(t), 4)}
            for k, (r, t) in enumerate(zip(chain.radii, chain.turns, strict=True))
        ],
        "corridor_width": round(float(width), 4),
        "rooms": {
            "start": {"u": [round(x, 4) for x in rooms.start_u],
                      "v": [round(x, 4) for x in rooms.start_v]},
            "goal": {"u": [round(x, 4) for x in rooms.goal_u],
                     "v": [round(x, 4) for x in rooms.goal_v]},
        },
    }
