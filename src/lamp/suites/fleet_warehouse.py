"""The warehouse kinds of the ``fleet`` family (``lamp.suites.fleet``): shelf rows with
aisles, cross-aisles and a dock band, and slots cut into the shelves for pallets.

A hall is drawn in a frame (u, v) with the rows along u and the dock band at v = 0, then
transposed at random. Aisles, cross-aisles and the dock band are at least as wide as the
widest object's diagonal plus two ``checks.ROBOT_ROOM`` margins plus 0.3-0.7 m (an object
turns anywhere in them with a robot on either side); shelf rows are 0.9-1.4 m deep, or
deeper where a slot or lane needs it (always 0.1 m of shelf behind it). A *slot* is a
recess opening onto an aisle, as wide as its pallet across plus 0.2-0.28 m on either side
and as deep as the pallet plus 0.2-0.26 m behind it. A *lane* (``after`` scenes) holds a
load at its back and a blocker in front, 0.32-0.4 m apart: the lane is the wider of the
two plus 0.2-0.25 m per side, and the blocker is at least as wide as the load, so the
load (at least 0.3 m across) cannot pass it: the blocker must be cleared first.

Slots and lanes, and 0.8 m of aisle in front of each, are keep-out zones: no other
object's start or goal, and no robot start, lies there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lamp.suites import checks as C
from lamp.suites.fleet_layout import (
    Box,
    FleetLayout,
    FleetObject,
    Placer,
    make_object,
    sample_object,
)
from lamp.suites.layout import rect, rnd

#: pallets: rectangles with sides in this range (m); lanes' loads too
PALLET_RANGE = (0.3, 0.6)
#: depth (m) of aisle in front of a slot or lane kept free of other objects and robots
MOUTH = 0.8
#: an end on the open floor lies this far (m, straight line) from the object's other end
NEAR = (1.5, 10.0)


@dataclass(frozen=True)
class Slot:
    """A recess in a shelf row: mouth centre (x, y), unit direction into it, width,
    depth."""

    mouth: tuple[float, float]
    inward: tuple[float, float]
    width: float
    depth: float

    def pose(self, depth: float) -> np.ndarray:
        """The pose ``depth`` m in from the mouth on the slot's axis, heading inward."""
        (mx, my), (dx, dy) = self.mouth, self.inward
        return np.array([mx + depth * dx, my + depth * dy, math.atan2(dy, dx)])

    def box(self, ahead: float = 0.0) -> Box:
        """The slot's interior, extended ``ahead`` m out of the mouth."""
        (mx, my), (dx, dy) = self.mouth, self.inward
        a = (mx - ahead * dx, my - ahead * dy)
        b = (mx + self.depth * dx, my + self.depth * dy)
        hx, hy = 0.5 * self.width * abs(dy), 0.5 * self.width * abs(dx)
        return (min(a[0], b[0]) - hx, min(a[1], b[1]) - hy,
                max(a[0], b[0]) + hx, max(a[1], b[1]) + hy)


@dataclass
class Hall:
    """A warehouse map in world coordinates: obstacle dicts, open boxes (dock band,
    aisles, cross-aisles), the slots in request order, and a summary."""

    obstacles: list[dict[str, Any]]
    open_boxes: list[Box]
    slots: list[Slot]
    info: dict[str, Any]


def aisle_width(rng: np.random.Generator, objects: list[FleetObject]) -> float:
    return 2.0 * max(o.reach for o in objects) + 2 * C.ROBOT_ROOM + rng.uniform(0.3, 0.7)


def _rows(rng: np.random.Generator, Lv: float, aisle: float, depth: float
          ) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """Shelf rows (v0, v1) and the dock band + aisles between them up to the far wall."""
    dock = max(aisle, rng.uniform(1.8, 3.0))
    rows, aisles = [], [(0.0, dock)]
    pos = dock
    while pos + depth + aisle <= Lv:
        rows.append((pos, pos + depth))
        aisles.append((pos + depth, pos + depth + aisle))
        pos += depth + aisle
    aisles[-1] = (aisles[-1][0], Lv)
    return rows, aisles


def _cross(rng: np.random.Generator, Lu: float, aisle: float) -> list[tuple[float, float]]:
    """Cross-aisles (u0, u1): one at each end wall, others 4-9 m apart."""
    out = [(0.0, aisle)]
    pos = aisle
    while True:
        bay = rng.uniform(4.0, 9.0)
        if pos + bay + aisle > Lu - aisle - 2.0:
            break
        out.append((pos + bay, pos + bay + aisle))
        pos += bay + aisle
    out.append((Lu - aisle, Lu))
    return out


def _assign(rng: np.random.Generator, segments: list[tuple[float, float, int]],
            rows: list[tuple[float, float]], requests: list[tuple[float, float, int | None]]
            ) -> list[tuple[int, int, float]] | None:
    """Per request (width, depth, link): (segment, side (0: opens towards v0, 1: towards
    v1), centre u), 0.3 m of shelf at least beside it and between slots of a row (on the
    same side, or on both sides when their depths leave less than 0.1 m between them;
    else their sides are 0.1 m apart at least along the row, so no shelf piece is thinner),
    and within ``NEAR[1]`` m of slot ``link`` when that is not None."""
    taken: dict[int, list[tuple[float, float, int, float]]] = {}
    out: list[tuple[int, int, float]] = []
    centres: list[tuple[float, float]] = []
    for w, d, link in requests:
        lu, lv = (0.0, 0.0) if link is None else centres[link]
        span = (-np.inf, np.inf) if link is None else (lu - NEAR[1], lu + NEAR[1])
        cand = [k for k, (u0, u1, r) in enumerate(segments)
                if min(u1, span[1]) - max(u0, span[0]) >= w + 0.6
                and (link is None or abs(sum(rows[r]) / 2 - lv) < NEAR[1])]
        for _ in range(60 if cand else 0):
            k = cand[int(rng.integers(len(cand)))]
            u0, u1, row = segments[k]
            u0, u1 = max(u0, span[0]), min(u1, span[1])
            uc, side = rng.uniform(u0 + 0.3 + 0.5 * w, u1 - 0.3 - 0.5 * w), int(rng.integers(2))
            v0, v1 = rows[row]
            vc = sum(rows[row]) / 2
            if link is not None and math.hypot(uc - lu, vc - lv) > NEAR[1]:
                continue
            if all(abs(uc - c) >= 0.5 * (w + ow) + 0.3
                   or (side != os and d + od <= v1 - v0 - 0.1
                       and min(abs(uc + a * w - c - b * ow) for a in (-.5, .5)
                               for b in (-.5, .5)) >= 0.1)
                   for c, ow, os, od in taken.get(row, [])):
                taken.setdefault(row, []).append((uc, w, side, d))
                out.append((k, side, uc))
                centres.append((uc, vc))
                break
        else:
            return None
    return out


def build_hall(rng: np.random.Generator, ws: tuple[float, float], objects: list[FleetObject],
               requests: list[tuple[float, float, int | None]]) -> Hall | None:
    """A hall for ``objects`` with one slot per request (width, depth, link: see
    ``_assign``); None when they do not fit."""
    transpose = bool(rng.random() < 0.5)
    Lu, Lv = (ws[1], ws[0]) if transpose else ws
    aisle = aisle_width(rng, objects)
    depth = max([rng.uniform(0.9, 1.4)] + [d + rng.uniform(0.1, 0.3) for _, d, _ in requests])
    rows, aisles = _rows(rng, Lv, aisle, depth)
    cross = _cross(rng, Lu, aisle)
    if not rows or len(cross) < 2:
        return None
    segments = [(cross[i][1], cross[i + 1][0], r) for r in range(len(rows))
                for i in range(len(cross) - 1)]
    where = _assign(rng, segments, rows, requests)
    if where is None:
        return None

    def xy(u0: float, v0: float, u1: float, v1: float) -> Box:
        return (v0, u0, v1, u1) if transpose else (u0, v0, u1, v1)

    def vec(du: float, dv: float) -> tuple[float, float]:
        return (dv, du) if transpose else (du, dv)

    boxes: list[Box] = []  # shelf pieces, uv
    slots: list[Slot] = []
    cuts: dict[int, list[tuple[float, float, int, float]]] = {}
    for (w, d, _), (k, side, uc) in zip(requests, where, strict=True):
        cuts.setdefault(k, []).append((uc, w, side, d))
        v0, v1 = rows[segments[k][2]]
        mv, inward = (v0, 1.0) if side == 0 else (v1, -1.0)
        m = (uc, mv)
        slots.append(Slot((m[1], m[0]) if transpose else m, vec(0.0, inward), w, d))
    for k, (u0, u1, r) in enumerate(segments):
        boxes += _shelf_pieces(u0, u1, rows[r], cuts.get(k, []))
    obstacles = []
    for b in boxes:
        x0, y0, x1, y1 = xy(*b)
        obstacles.append(rect(0.5 * (x0 + x1), 0.5 * (y0 + y1), x1 - x0, y1 - y0))
    open_boxes = [xy(0.0, a0, Lu, a1) for a0, a1 in aisles]
    open_boxes += [xy(c0, 0.0, c1, Lv) for c0, c1 in cross]
    info = {"shelf_rows": len(rows), "cross_aisles": len(cross), "aisle_width": round(aisle, 3),
            "shelf_depth": round(depth, 3), "transposed": transpose}
    return Hall(obstacles, open_boxes, slots, info)


def _shelf_pieces(u0: float, u1: float, row: tuple[float, float],
                  cuts: list[tuple[float, float, int, float]]) -> list[Box]:
    """The shelf between u0 and u1 in ``row`` less the slots (centre u, width, side,
    depth), as (u0, v0, u1, v1) boxes (merged along u where the depth is the same)."""
    v0, v1 = row
    edges = sorted({u0, u1, *(uc + e * 0.5 * w for uc, w, _, _ in cuts for e in (-1, 1))})
    pieces: list[list[float]] = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        m = 0.5 * (a + b)
        cut = [max([d for uc, w, side, d in cuts if side == s and abs(m - uc) < 0.5 * w],
                   default=0.0) for s in (0, 1)]
        lo, hi = v0 + cut[0], v1 - cut[1]
        if pieces and pieces[-1][1] == a and pieces[-1][2:] == [lo, hi]:
            pieces[-1][1] = b
        else:
            pieces.append([a, b, lo, hi])
    return [(a, lo, b, hi) for a, b, lo, hi in pieces]


def pallet(rng: np.random.Generator, lo: float = PALLET_RANGE[0]) -> FleetObject:
    return sample_object(rng, "rectangle", lo, PALLET_RANGE[1])


def _slot_request(rng: np.random.Generator, obj: FleetObject, link: int | None = None
                  ) -> tuple[float, float, int | None]:
    a, b = obj.shape["size"]
    return (b + 2 * rng.uniform(0.2, 0.28), a + rng.uniform(0.2, 0.26) + rng.uniform(0.0, 0.05),
            link)


def _in_slot(obj: FleetObject, slot: Slot, back: float) -> np.ndarray:
    """The pallet's pose ``back`` m short of the slot's back wall, its x axis inward."""
    return slot.pose(slot.depth - back - 0.5 * obj.shape["size"][0])


def _open(rng: np.random.Generator, placer: Placer, hall: Hall, obj: FleetObject,
          near: tuple[float, float] | None = None) -> np.ndarray | None:
    """A pose in one of the hall's open boxes (weighted by area), ``NEAR`` m from
    ``near`` when given."""
    boxes = hall.open_boxes
    if near is not None:
        x, y = near
        boxes = [b for b in boxes if math.hypot(max(b[0] - x, 0, x - b[2]),
                                                max(b[1] - y, 0, y - b[3])) < NEAR[1]]
    area = np.array([(b[2] - b[0]) * (b[3] - b[1]) for b in boxes])
    for _ in range(8):
        box = boxes[int(rng.choice(len(area), p=area / area.sum()))]
        pose = placer.sample(rng, obj, box, tries=15,
                             near=None if near is None else (*near, *NEAR))
        if pose is not None:
            return pose
    return None


def _fill(rng: np.random.Generator, ws: tuple[float, float], hall: Hall,
          fixed: list[tuple[FleetObject, np.ndarray | None, np.ndarray | None]]
          ) -> tuple[Placer, list[np.ndarray], list[np.ndarray]] | None:
    """Place ``fixed`` (object, start or None, goal or None): the given poses first
    (inside their slots and lanes), then the slots' keep-out zones, then the missing
    poses in the open boxes."""
    placer = Placer(ws, hall.obstacles)
    given = []
    for obj, s, g in fixed:
        ends = [None if p is None else placer.place(obj, p, zones=False) for p in (s, g)]
        if any(e is None and p is not None for e, p in zip(ends, (s, g), strict=True)):
            return None
        given.append(ends)
    for slot in hall.slots:
        placer.add_zone(slot.box(MOUTH))
    starts, goals = [], []
    for (obj, _, _), (s, g) in zip(fixed, given, strict=True):
        if s is None and g is None:
            s = _open(rng, placer, hall, obj)
        if s is None:
            s = None if g is None else _open(rng, placer, hall, obj, (g[0], g[1]))
        elif g is None:
            g = _open(rng, placer, hall, obj, (s[0], s[1]))
        if s is None or g is None:
            return None
        starts.append(s)
        goals.append(g)
    return placer, starts, goals


def layout_aisles(rng: np.random.Generator, ws: tuple[float, float],
                  objects: list[FleetObject]) -> FleetLayout | None:
    """Pallets (the objects must be rectangles) put away from the open floor into a slot
    (45 %), picked from a slot to the open floor (35 %) or moved slot to slot."""
    modes = [("open", "slot") if u < 0.45 else ("slot", "open") if u < 0.8 else ("slot", "slot")
             for u in rng.random(len(objects))]
    requests: list[tuple[float, float, int | None]] = []
    owner = []
    for k, (obj, m) in enumerate(zip(objects, modes, strict=True)):
        for end in (0, 1):
            if m[end] == "slot":
                link = len(requests) - 1 if end == 1 and m[0] == "slot" else None
                requests.append(_slot_request(rng, obj, link))
                owner.append((k, end))
    hall = build_hall(rng, ws, objects, requests)
    if hall is None:
        return None
    ends: list[list[np.ndarray | None]] = [[None, None] for _ in objects]
    for (k, end), slot in zip(owner, hall.slots, strict=True):
        ends[k][end] = _in_slot(objects[k], slot, rng.uniform(0.2, 0.26))
    got = _fill(rng, ws, hall, [(o, e[0], e[1]) for o, e in zip(objects, ends, strict=True)])
    if got is None:
        return None
    placer, starts, goals = got
    info = {**hall.info, "slots": len(hall.slots)}
    return FleetLayout(ws, hall.obstacles, objects, starts, goals, placer, info)


def extents(obj: FleetObject) -> tuple[float, float]:
    """(along, across) a slot of a circle or of a rectangle with its x axis inward."""
    return (obj.along, obj.along) if obj.kind == "circle" else tuple(obj.shape["size"])


def blocker_for(rng: np.random.Generator, load: FleetObject) -> FleetObject:
    """A blocker at least as wide as the pallet ``load`` across its lane: a barrel
    (circle) or a pallet."""
    lo = load.shape["size"][1]
    if rng.random() < 0.4:
        return make_object({"type": "circle", "radius": rnd(0.5 * rng.uniform(lo, 0.6))})
    a, b = rnd(rng.uniform(PALLET_RANGE[0], 0.6)), rnd(rng.uniform(lo, 0.6))
    return make_object({"type": "rectangle", "size": [a, max(b, lo)]})


def layout_lanes(rng: np.random.Generator, ws: tuple[float, float],
                 objects: list[FleetObject], pairs: int) -> FleetLayout | None:
    """Objects ``2 i`` (blocker) and ``2 i + 1`` (load, waits for the blocker:
    ``after = (2 i,)``) for i < ``pairs`` start in a lane, the load at its back; the
    blocker goes to the open floor, the load to the open floor or a slot (half of them).
    The other objects are pallets moved from the open floor to a slot, from a slot to
    the floor, or across the floor (a third each)."""
    requests: list[tuple[float, float, int | None]] = []
    plan = []
    for i in range(pairs):
        blk, load = objects[2 * i], objects[2 * i + 1]
        s = rng.uniform(0.2, 0.25)
        back, gap, front = rng.uniform(0.2, 0.25), rng.uniform(0.32, 0.4), rng.uniform(0, 0.05)
        depth = back + load.shape["size"][0] + gap + extents(blk)[0] + front
        requests.append((max(extents(load)[1], extents(blk)[1]) + 2 * s, depth, None))
        to_slot = bool(rng.random() < 0.5)
        if to_slot:
            requests.append(_slot_request(rng, load, len(requests) - 1))
        plan.append((back, front, to_slot))
    others = []
    for k in range(2 * pairs, len(objects)):
        others.append(int(rng.integers(3)))
        if others[-1] < 2:
            requests.append(_slot_request(rng, objects[k]))
    hall = build_hall(rng, ws, objects, requests)
    if hall is None:
        return None
    fixed: list[tuple[FleetObject, np.ndarray | None, np.ndarray | None]] = []
    it = iter(hall.slots)
    for i, (back, front, to_slot) in enumerate(plan):
        blk, load = objects[2 * i], objects[2 * i + 1]
        lane = next(it)
        b_pose = lane.pose(front + 0.5 * extents(blk)[0])
        if blk.kind == "circle":
            b_pose[2] = 0.0
        fixed.append((blk, b_pose, None))
        goal = _in_slot(load, next(it), rng.uniform(0.2, 0.26)) if to_slot else None
        fixed.append((load, _in_slot(load, lane, back), goal))
    for k, end in zip(range(2 * pairs, len(objects)), others, strict=True):
        p = None if end == 2 else _in_slot(objects[k], next(it), rng.uniform(0.2, 0.26))
        fixed.append((objects[k], p if end == 1 else None, p if end == 0 else None))
    got = _fill(rng, ws, hall, fixed)
    if got is None:
        return None
    placer, starts, goals = got
    after = [(k - 1,) if k < 2 * pairs and k % 2 else () for k in range(len(objects))]
    info = {**hall.info, "slots": len(hall.slots) - pairs, "lanes": pairs}
    return FleetLayout(ws, hall.obstacles, objects, starts, goals, placer, info, after)
