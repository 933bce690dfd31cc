"""Whether two segments on the shared clock can run at the same time: robots checked row
by row, objects by the space they may take.

Both segments' rows are on the common grid (``segments.on_grid``) and aligned from now
(row ``cursor`` of a running segment and row 0 of a new one run together); a segment's
robots hold their last row once it ends. The object a segment pushes may be anywhere
along its planned motion (grown by ``OBJECT_MARGIN``) until the segment ends, and at its
last planned pose after.

Guarantee (``tests/test_fleet_regions.py``): when :func:`compatible` holds, at every row of
the shared clock each robot of one segment is at least ``2 * ROBOT_MARGIN`` farther than a
robot diameter from each robot of the other, each robot at least ``ROBOT_MARGIN`` clear
of the other's object space, and the two object spaces do not meet.
"""

from __future__ import annotations

import numpy as np
import shapely

from lamp.fleet.regions import OBJECT_MARGIN, ROBOT_MARGIN, footprints
from lamp.fleet.segments import Segment

__all__ = ["compatible", "object_space"]


def object_space(seg: Segment, final: bool = False) -> shapely.Geometry:
    """Where ``seg``'s object may be while it runs (``final``: once it has ended)."""
    poses = seg.poses[-1:] if final else seg.poses
    return footprints(seg.shape, poses, OBJECT_MARGIN)


def _rows(seg: Segment, n: int) -> np.ndarray:
    """(robots, n, 2): its rows from the cursor, holding the last one."""
    rows = seg.rows[:, seg.cursor:]
    if rows.shape[1] >= n:
        return rows[:, :n]
    return np.concatenate([rows, np.repeat(rows[:, -1:], n - rows.shape[1], axis=1)], axis=1)


def _robots_clear(rows: np.ndarray, moving_until: int, during: shapely.Geometry,
                  after: shapely.Geometry, clearance: float) -> bool:
    """Robots along ``rows`` stay ``clearance`` from ``during`` for rows before
    ``moving_until`` and from ``after`` from then on."""
    for region, part in ((during, rows[:, :moving_until]), (after, rows[:, moving_until:])):
        if part.size == 0:
            continue
        pts = shapely.points(part.reshape(-1, 2))
        if np.min(shapely.distance(region, pts)) < clearance:
            return False
    return True


def compatible(a: Segment, b: Segment) -> bool:
    """Whether ``a`` and ``b`` may run together from now (see the module docstring)."""
    r = a.robot_radius
    n = max(a.remaining, b.remaining)
    ra, rb = _rows(a, n), _rows(b, n)
    gap = np.hypot(*np.moveaxis(ra[:, None] - rb[None], -1, 0))  # (na, nb, n)
    if gap.size and gap.min() < 2.0 * r + 2.0 * ROBOT_MARGIN:
        return False
    space_a, space_b = object_space(a), object_space(b)
    if space_a.intersects(space_b):
        return False
    clear = r + ROBOT_MARGIN
    return (_robots_clear(rb, a.remaining, space_a, object_space(a, final=True), clear)
            and _robots_clear(ra, b.remaining, space_b, object_space(b, final=True), clear))
