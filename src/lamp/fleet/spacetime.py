"""Whether two segments on the shared clock can run at the same time: robots checked row
by row, objects by the space they may take.

Both segments' rows are on the common grid (``segments.on_grid``) and aligned from now
(row ``cursor`` of a running segment and row 0 of a new one run together); a segment's
robots hold their last row once it ends. The object a segment pushes stands at its first
planned pose until a robot may touch it (``Segment.touch``), may then be anywhere along
its planned motion until the segment ends, and is at its last planned pose after (each
grown by ``OBJECT_MARGIN``: :func:`object_phases`). Objects and robots are checked against
the other's object phase by phase.

When the objects' poses as read now are given (``seen``), a pushed object is also known to
stay near where it was seen: every point of it moves at most ``PUSH_SPEEDUP`` times as
far as the farthest-moving robot of its segment, plus ``PUSH_LEAD`` (:func:`object_reach`;
robots push it, nothing else does; ``lamp.record.push_reach`` measures the bound on
recordings: ``benchmarks/push_reach.py``, and every concurrent run of the tests). A
robot, or the other object, is then in the way of a moving object at a row only if it
is near the object's planned motion *and* within that reach of the object seen: a
segment may cross the far end of another's push long before the object comes (the
fleet's opt-in ``reach_cut``).

Guarantee (``tests/test_fleet_parts.py``, against a row-by-row brute force): when
:func:`compatible` holds, at every row of the shared clock each robot of one segment is at
least ``2 * ROBOT_MARGIN`` farther than a robot diameter from each robot of the other, each
robot at least ``ROBOT_MARGIN`` clear of the other's object space at that row (its phase,
cut to the object's reach from where it was seen when ``seen`` is given), and the two
objects' spaces (so cut) do not meet while both hold them.

Segments whose reach (:func:`reach_box`: every row left and every object phase) lie
farther apart than the largest of those clearances are compatible without a row being
compared: the same answer, found from two boxes (tested against the full test).

A segment that ends with its object outside its last planned pose (grown by
``OBJECT_MARGIN``) breaks what the running segments were admitted on: :func:`halted`
names those that come too near it, to be stopped.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from lamp.fleet.regions import OBJECT_MARGIN, ROBOT_MARGIN, footprints
from lamp.fleet.segments import Segment
from lamp.geometry.shapes import to_shapely

__all__ = ["PUSH_LEAD", "PUSH_SPEEDUP", "compatible", "halted_by", "object_phases",
           "object_reach", "object_space", "reach_box"]

#: A pushed object's points move at most this many times as far as its segment's
#: farthest-moving robot (a point away from the contact swings faster when it turns) ...
PUSH_SPEEDUP = 1.5
#: ... plus this (m): a slide after contact, the sensor's error in where it was seen, a
#: robot off its row by up to ``segments.REJOIN_GAP``.
PUSH_LEAD = 0.1

#: A phase: (until row, space, and when the object is cut to its reach from where it was
#: seen: (its body seen, (n,) reach at each row from now), else None).
Phase = tuple[float, shapely.Geometry, "tuple[shapely.Geometry, np.ndarray] | None"]


def object_space(seg: Segment, final: bool = False, first: bool = False) -> shapely.Geometry:
    """Where ``seg``'s object may be while it runs (``final``: once it has ended;
    ``first``: before a robot may touch it), grown by ``OBJECT_MARGIN``."""
    return _space(seg, "final" if final else "first" if first else "motion")


def _space(seg: Segment, which: str) -> shapely.Geometry:
    """``seg``'s object at its first planned pose (``which`` = "first"), along its planned
    motion ("motion") or at its last pose ("final"), grown by ``OBJECT_MARGIN``; computed
    once per segment (``Segment.spaces``) and prepared for the many tests against it."""
    space = seg.spaces.get(which)
    if space is None:
        poses = {"first": seg.poses[:1], "motion": seg.poses, "final": seg.poses[-1:]}[which]
        space = footprints(seg.shape, poses, OBJECT_MARGIN)
        shapely.prepare(space)
        seg.spaces[which] = space
    return space


def object_phases(seg: Segment) -> list[tuple[float, shapely.Geometry]]:
    """Where ``seg``'s object may be from now on, as (until row, space) in time order, the
    rows counted from now: at its first planned pose until a robot may touch it
    (``Segment.touch``), anywhere along its planned motion until the segment ends, at its
    last planned pose after (until ``inf``); empty phases left out."""
    touch = max(0, seg.touch - seg.cursor)
    out = []
    if touch > 0:
        out.append((float(min(touch, seg.remaining)), _space(seg, "first")))
    if touch < seg.remaining:
        out.append((float(seg.remaining), object_space(seg)))
    out.append((math.inf, object_space(seg, final=True)))
    return out


def object_reach(seg: Segment, n: int) -> np.ndarray:
    """(n,): how far (m) any point of ``seg``'s object may be at each row from now (row 0:
    ``seg.rows[:, cursor]``) from where it was seen now: ``PUSH_SPEEDUP`` times the
    farthest any of its robots moves along its rows since the last row run (the first,
    before a segment has run), plus ``PUSH_LEAD``; the rows past its last hold it."""
    travel = _travel(seg)
    last = travel.size - 1
    rows = np.minimum(seg.cursor + np.arange(n), last)
    return PUSH_SPEEDUP * (travel[rows] - travel[min(max(seg.cursor - 1, 0), last)]) + PUSH_LEAD


def _travel(seg: Segment) -> np.ndarray:
    """(G,): the farthest any robot of ``seg`` moves from row 0 to row g (the largest step
    of each row added up); computed once for its rows (a rejoin replaces them)."""
    cached = seg.bounds.get("travel")
    if cached is not None and cached[0] is seg.rows:
        return cached[1]
    step = np.hypot(*np.moveaxis(np.diff(seg.rows, axis=1), -1, 0)).max(axis=0, initial=0.0)
    travel = np.concatenate([[0.0], np.cumsum(step)])
    seg.bounds["travel"] = (seg.rows, travel)
    return travel


def _phases(seg: Segment, n: int, seen: np.ndarray | None) -> list[Phase]:
    """:func:`object_phases` with its motion phase cut to the object's reach from where
    it was seen (``seen``: every object's pose read now; None: not cut)."""
    phases = object_phases(seg)
    if seen is None:
        return [(until, space, None) for until, space in phases]
    body = to_shapely(seg.shape, np.asarray(seen[seg.index], float))
    shapely.prepare(body)
    cut = (body, object_reach(seg, n))
    motion = object_space(seg)
    return [(until, space, cut if space is motion else None) for until, space in phases]


def _rows(seg: Segment, n: int) -> np.ndarray:
    """(robots, n, 2): its rows from the cursor, holding the last one."""
    rows = seg.rows[:, seg.cursor:]
    if rows.shape[1] >= n:
        return rows[:, :n]
    return np.concatenate([rows, np.repeat(rows[:, -1:], n - rows.shape[1], axis=1)], axis=1)


def _robots_clear(rows: np.ndarray, phases: list[Phase], clearance: float) -> bool:
    """Robots along ``rows`` stay ``clearance`` from each phase's space in its rows (cut to
    the object's reach at each row where the phase is)."""
    begin = 0
    for until, region, cut in phases:
        end = int(min(until, rows.shape[1]))
        part, first = rows[:, begin:end], begin
        begin = max(begin, end)
        if part.size == 0:
            continue
        xy = part.reshape(-1, 2)
        x0, y0, x1, y1 = region.bounds  # a point outside them grown is farther: not near
        inside = ((xy[:, 0] >= x0 - clearance) & (xy[:, 0] <= x1 + clearance)
                  & (xy[:, 1] >= y0 - clearance) & (xy[:, 1] <= y1 + clearance))
        if not inside.any():
            continue
        pts = shapely.points(xy[inside])
        near = shapely.dwithin(region, pts, clearance)  # a prepared test, then the few exactly
        if not near.any():
            continue
        hit = shapely.distance(region, pts[near]) < clearance
        if hit.any() and cut is not None:  # ... and within the object's reach at that row
            body, reach = cut
            at = first + np.flatnonzero(inside)[near][hit] % part.shape[1]  # their rows
            hit = shapely.distance(body, pts[near][hit]) < clearance + reach[at]
        if hit.any():
            return False
    return True


def _objects_clear(pa: list[Phase], pb: list[Phase]) -> bool:
    """No two phases of the two objects that overlap in time meet in space (each cut to
    its object's reach where it is: :func:`_may_meet`)."""
    start_a = 0.0
    for until_a, space_a, cut_a in pa:
        start_b = 0.0
        for until_b, space_b, cut_b in pb:
            if (start_a < until_b and start_b < until_a and space_a.intersects(space_b)
                    and _may_meet(min(until_a, until_b), space_a, cut_a, space_b, cut_b)):
                return False
            start_b = until_b
        start_a = until_a
    return True


def _may_meet(end: float, space_a: shapely.Geometry, cut_a, space_b: shapely.Geometry,
              cut_b) -> bool:
    """Whether two objects, each in its space (and within its reach of where it was seen
    where it is cut) at a row before ``end``, may meet. Reaches only grow, so the last
    row is the one to test: a point of a within ``reach_a`` of body a and in space b, and
    the same for b, and the two bodies seen within both reaches."""
    if cut_a is None and cut_b is None:
        return True
    def reach(cut) -> float:
        row = min(end, cut[1].size) - 1
        return float(cut[1][int(row)])
    if cut_a is not None and shapely.distance(cut_a[0], space_b) > reach(cut_a):
        return False
    if cut_b is not None and shapely.distance(cut_b[0], space_a) > reach(cut_b):
        return False
    if cut_a is not None and cut_b is not None:
        return bool(shapely.distance(cut_a[0], cut_b[0]) <= reach(cut_a) + reach(cut_b))
    return True


def reach_box(seg: Segment) -> np.ndarray:
    """(x0, y0, x1, y1): a box holding the centres of ``seg``'s robots at every row from
    its cursor on (its last row held) and each of its object's spaces (first, along its
    motion, final)."""
    lo, hi, spaces = _bounds(seg)
    row = min(seg.cursor, seg.rows.shape[1] - 1)
    return np.concatenate([np.minimum(lo[row], spaces[:2]), np.maximum(hi[row], spaces[2:])])


def _bounds(seg: Segment) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(G, 2) the least and greatest robot centre over each row on (``lo[g]``, ``hi[g]``:
    rows g, g + 1, ...), and (4,) the box of its object's three spaces; computed once
    for its rows (a rejoin replaces them)."""
    cached = seg.bounds.get("reach")
    if cached is not None and cached[0] is seg.rows:
        return cached[1:]
    lo = np.minimum.accumulate(seg.rows.min(axis=0)[::-1], axis=0)[::-1]
    hi = np.maximum.accumulate(seg.rows.max(axis=0)[::-1], axis=0)[::-1]
    stack = np.array([_space(seg, w).bounds for w in ("first", "motion", "final")], float)
    spaces = np.concatenate([stack[:, :2].min(axis=0), stack[:, 2:].max(axis=0)])
    seg.bounds["reach"] = (seg.rows, lo, hi, spaces)
    return lo, hi, spaces


def apart(a: np.ndarray, b: np.ndarray, gap: float) -> bool:
    """Whether boxes ``a`` and ``b`` (x0, y0, x1, y1) are more than ``gap`` apart along x
    or along y (then every point of one is more than ``gap`` from every point of the
    other)."""
    return bool(a[0] - b[2] > gap or b[0] - a[2] > gap or a[1] - b[3] > gap
                or b[1] - a[3] > gap)


def compatible(a: Segment, b: Segment, seen: np.ndarray | None = None) -> bool:
    """Whether ``a`` and ``b`` may run together from now (see the module docstring;
    ``seen``: every object's pose read now, or None)."""
    r = a.robot_radius
    if apart(reach_box(a), reach_box(b), 2.0 * r + 2.0 * ROBOT_MARGIN):
        return True  # every test below holds: robots and spaces all farther apart
    n = max(a.remaining, b.remaining)
    ra, rb = _rows(a, n), _rows(b, n)
    gap = np.hypot(*np.moveaxis(ra[:, None] - rb[None], -1, 0))  # (na, nb, n)
    if gap.size and gap.min() < 2.0 * r + 2.0 * ROBOT_MARGIN:
        return False
    phases_a, phases_b = _phases(a, n, seen), _phases(b, n, seen)
    if not _objects_clear(phases_a, phases_b):
        return False
    clear = r + ROBOT_MARGIN
    return _robots_clear(rb, phases_a, clear) and _robots_clear(ra, phases_b, clear)


def halted(running: list[Segment], poses: np.ndarray) -> list[Segment]:
    """The ``running`` segments to stop now (every segment that runs on after the shared
    clock stopped, ``poses`` every object's pose read now), in the order found: those an
    ended segment's object stands in the way of (:func:`halted_by`), then those a halted
    one's object stands in the way of, and so on."""
    out: list[Segment] = []
    todo = [s for s in running if s.done]
    while todo:
        ended = todo.pop(0)
        for seg in halted_by(ended, [s for s in running if s not in out], poses[ended.index]):
            out.append(seg)
            todo.append(seg)
    return out


def halted_by(ended: Segment, running: list[Segment], pose: np.ndarray) -> list[Segment]:
    """The ``running`` segments (not done) that must stop now because ``ended``'s object
    stands (``pose``, read now) outside the space its segment was taken to leave it in
    (its last planned pose grown by ``OBJECT_MARGIN``: a push that drifted further, or
    stopped short) and in their way: a robot row they have left comes nearer than
    ``ROBOT_MARGIN`` to it, or one of their object's spaces (:func:`object_phases`)
    meets it. They were admitted against that space, not against the body where it
    stands; stopped, their loops plan anew around it. None while the object stands
    inside that space (tested against a brute force, ``tests/test_fleet_parts.py``)."""
    body = to_shapely(ended.shape, np.asarray(pose, float))
    if object_space(ended, final=True).contains(body):
        return []
    box = np.asarray(body.bounds, float)
    out = []
    for seg in running:
        clear = seg.robot_radius + ROBOT_MARGIN
        if seg is ended or seg.done or apart(reach_box(seg), box, clear):
            continue
        if (not _robots_clear(seg.rows[:, seg.cursor:], [(math.inf, body, None)], clear)
                or any(space.intersects(body) for _, space in object_phases(seg))):
            out.append(seg)
    return out
