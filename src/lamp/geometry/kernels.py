"""Compiled (Numba) planar primitives shared by the compiled clearance checkers.

``lamp.geometry.robot_space`` (robot disks) and ``lamp.suites.kernels`` (the suites' exact
object checker) measure distances to polygon edges, and Gspi's robot-robot conflict test
(``lamp.mrmp.gspi``) the closest approach of two linear motions; the point-to-segment
distance they all need lives here once. Functions are inlined into their callers (``inline="always"``),
so sharing them costs nothing in the hot loops.
"""

from __future__ import annotations

import math

import numba as nb


@nb.njit(cache=True, inline="always")
def point_segment_distance(
    px: float, py: float, ax: float, ay: float, bx: float, by: float
) -> float:
    """Euclidean distance from point p to the segment ab (a point when a == b)."""
    dx = bx - ax
    dy = by - ay
    L2 = dx * dx + dy * dy
    t = 0.0
    if L2 > 0.0:
        t = ((px - ax) * dx + (py - ay) * dy) / L2
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
    qx = ax + t * dx - px
    qy = ay + t * dy - py
    return math.sqrt(qx * qx + qy * qy)
