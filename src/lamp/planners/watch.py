"""Watched pushes: stop a push in a tight place as soon as the object leaves its planned path.

The closed loop checks drift after a segment (``closed_loop.drift_limits``). In a passage a
few centimetres wider than the object that is too late: a box pushed straight into a
corridor's mouth that catches a corner turns about it while the robots keep pushing, and
ends wedged across the mouth (corridor-20: planned heading 0.86 rad, reached 1.20 rad),
where only pushes further into the wedge can be reached. ``PushWatch`` is the simulator's
``stop`` condition for such a push (a straight one, through a tight place: ``watched``):
the planned object path is the polyline of the transitions' poses, and the push stops
(the robots hold where they are) as soon as the object's pose is explained by no piece of
it, so the loop replans from a pose that is still nearly aligned.

Deviation from a piece ``a -> b`` (``deviation``): the distance of the object's position
from the segment ``a.xy -> b.xy``, and the angle from its heading to the nearest heading
of the piece's rotation (the arc from ``a.theta`` to ``b.theta``, the short way round).
Lenient on purpose: the object may lag behind its plan, and may already have turned as
far as the piece turns, without counting as off the path.

Guarantee (``tests/test_watch.py``): ``deviation`` is zero at every pose of every piece
(interpolated in SE(2)) and matches a brute-force reference; ``PushWatch`` fires exactly
when no piece has both deviations within the limits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lamp.geometry.se2 import wrap_angle

#: Only pushes whose planned poses come closer than this (m) to an obstacle are watched.
WATCH_CLEARANCE = 0.03
#: ... and only straight ones: planned headings within this (rad) of the first. A push that
#: turns the object lets it lag and swing on the way (corridor-04 lost its way when such
#: pushes were stopped); one along a passage must not turn at all.
WATCH_MAX_TURN = 0.05
#: A watched push stops when the object is off its path by this multiple of the position
#: drift limit of its tightest pose (the loop's end-of-segment check keeps the limits
#: themselves: the watch catches a push that is going wrong, not the wobble of one pushed
#: along a passage) ...
WATCH_FACTOR = 1.5
#: ... or turned by more than this (rad) from it, whatever its length: a box turning
#: about a caught corner turns fast and far (corridor-20: 0.34 rad in one push), while a
#: long bar pushed along a passage wobbles by a few hundredths (1.36 m bars were stopped
#: over and over at 1.5 times their drift limit, 0.02 rad).
WATCH_ROTATION = 0.1


def deviation(path: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(position, heading) deviation (each (M - 1,)) of pose ``q`` from each piece
    ``path[i] -> path[i + 1]`` of the (M, 3) planned path, M >= 2 (module docstring)."""
    path = np.asarray(path, dtype=float)
    q = np.asarray(q, dtype=float)
    a, b = path[:-1], path[1:]
    ab = b[:, :2] - a[:, :2]
    length2 = np.einsum("ij,ij->i", ab, ab)
    t = np.where(length2 > 1e-18,
                 np.einsum("ij,ij->i", q[None, :2] - a[:, :2], ab) / np.maximum(length2, 1e-18),
                 0.0)
    t = np.clip(t, 0.0, 1.0)
    dpos = np.hypot(*(a[:, :2] + t[:, None] * ab - q[None, :2]).T)
    turn = wrap_angle(b[:, 2] - a[:, 2])  # the piece's rotation, the short way
    off = wrap_angle(q[2] - a[:, 2])  # the object's heading from the piece's start
    # the nearest heading on the arc [0, turn] (or [turn, 0]) from the start heading
    lo, hi = np.minimum(turn, 0.0), np.maximum(turn, 0.0)
    inside = (off >= lo) & (off <= hi)
    drot = np.where(inside, 0.0, np.minimum(np.abs(wrap_angle(off - lo)),
                                            np.abs(wrap_angle(off - hi))))
    return dpos, drot


def watched(path: np.ndarray, clearance: float) -> bool:
    """Whether a push along the (M, 3) planned ``path``, whose tightest pose has
    ``clearance`` (m), is watched: closer than ``WATCH_CLEARANCE`` and straight (every
    heading within ``WATCH_MAX_TURN`` of the first)."""
    path = np.asarray(path, dtype=float)
    turn = np.abs(wrap_angle(path[:, 2] - path[0, 2]))
    return bool(clearance < WATCH_CLEARANCE and turn.max() <= WATCH_MAX_TURN)


@dataclass(frozen=True, eq=False)
class PushWatch:
    """``stop`` for ``Simulator.execute``: True when object ``index``'s pose is off every
    piece of ``path`` by more than ``max_position`` (m) or ``max_rotation`` (rad)."""

    path: np.ndarray  # (M, 3) planned object poses, M >= 2
    index: int
    max_position: float
    max_rotation: float

    def __post_init__(self) -> None:
        p = np.asarray(self.path, dtype=float)
        if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 2 or not np.all(np.isfinite(p)):
            raise ValueError(f"PushWatch.path must be a finite (M >= 2, 3) array, got {p.shape}")
        for name in ("max_position", "max_rotation"):
            v = getattr(self, name)
            if not (v > 0 and math.isfinite(v)):
                raise ValueError(f"PushWatch.{name} must be finite and > 0, got {v!r}")
        object.__setattr__(self, "path", p)

    def __call__(self, object_poses: np.ndarray) -> bool:
        dpos, drot = deviation(self.path, np.asarray(object_poses, float)[self.index])
        return not bool(np.any((dpos <= self.max_position) & (drot <= self.max_rotation)))
