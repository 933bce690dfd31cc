"""Whether two segments on the shared clock can run at the same time: robots checked row
by row, objects by the space they may take.

Both segments' rows are on the common grid (``segments.on_grid``) and aligned from now
(row ``cursor`` of a running segment and row 0 of a new one run together); a segment's
robots hold their last row once it ends. The object a segment pushes stands at its first
planned pose until a robot may touch it (``Segment.touch``), may then be anywhere along
its planned motion until the segment ends, and is at its last planned pose after (each
grown by ``OBJECT_MARGIN``: :func:`object_phases`). Objects and robots are checked against
the other's object phase by phase.

Guarantee (``tests/test_fleet_parts.py``, against a row-by-row brute force): when
:func:`compatible` holds, at every row of the shared clock each robot of one segment is at
least ``2 * ROBOT_MARGIN`` farther than a robot diameter from each robot of the other, each
robot at least ``ROBOT_MARGIN`` clear of the other's object space at that row (its phase),
and the two objects' spaces do not meet while both hold them.

Segments whose reach (:func:`reach_box`: every row left and every object phase) lie
farther apart than the largest of those clearances are compatible without a row being
compared: the same answer, found from two boxes (tested against the full test).
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from lamp.fleet.regions import OBJECT_MARGIN, ROBOT_MARGIN, footprints
from lamp.fleet.segments import Segment

__all__ = ["compatible", "object_phases", "object_space", "reach_box"]


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


def _rows(seg: Segment, n: int) -> np.ndarray:
    """(robots, n, 2): its rows from the cursor, holding the last one."""
    rows = seg.rows[:, seg.cursor:]
    if rows.shape[1] >= n:
        return rows[:, :n]
    return np.concatenate([rows, np.repeat(rows[:, -1:], n - rows.shape[1], axis=1)], axis=1)


def _robots_clear(rows: np.ndarray, phases: list[tuple[float, shapely.Geometry]],
                  clearance: float) -> bool:
    """Robots along ``rows`` stay ``clearance`` from each phase's space in its rows."""
    begin = 0
    for until, region in phases:
        end = int(min(until, rows.shape[1]))
        part = rows[:, begin:end]
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
        if near.any() and np.min(shapely.distance(region, pts[near])) < clearance:
            return False
    return True


def _objects_clear(pa: list[tuple[float, shapely.Geometry]],
                   pb: list[tuple[float, shapely.Geometry]]) -> bool:
    """No two phases of the two objects that overlap in time meet in space."""
    start_a = 0.0
    for until_a, space_a in pa:
        start_b = 0.0
        for until_b, space_b in pb:
            if start_a < until_b and start_b < until_a and space_a.intersects(space_b):
                return False
            start_b = until_b
        start_a = until_a
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


def compatible(a: Segment, b: Segment) -> bool:
    """Whether ``a`` and ``b`` may run together from now (see the module docstring)."""
    r = a.robot_radius
    if apart(reach_box(a), reach_box(b), 2.0 * r + 2.0 * ROBOT_MARGIN):
        return True  # every test below holds: robots and spaces all farther apart
    n = max(a.remaining, b.remaining)
    ra, rb = _rows(a, n), _rows(b, n)
    gap = np.hypot(*np.moveaxis(ra[:, None] - rb[None], -1, 0))  # (na, nb, n)
    if gap.size and gap.min() < 2.0 * r + 2.0 * ROBOT_MARGIN:
        return False
    phases_a, phases_b = object_phases(a), object_phases(b)
    if not _objects_clear(phases_a, phases_b):
        return False
    clear = r + ROBOT_MARGIN
    return _robots_clear(rb, phases_a, clear) and _robots_clear(ra, phases_b, clear)
