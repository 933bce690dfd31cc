"""Exact clearance of one object among obstacles, for certifying motions in tight places.

:class:`~lamp.geometry.object_space.ObjectSpace` answers from a distance grid: it is fast
and conservative, but its clearance may be up to ``band`` (13 mm at the defaults) below the
truth, and a motion needs ``motion_margin`` (5 mm) on top. A corridor only 2 cm wider than
the object leaves 1 cm a side, which the grid cannot certify. ``ExactSpace`` computes the
clearance exactly instead (Shapely distances between the footprint and the obstacles,
circles as true disks), which is slower and meant for the few poses and motions where the
grid's answer is "not free" but the truth may be "free" (``lamp.search.narrow``).

Guarantees (asserted by ``tests/test_exact_space.py``):

* ``clearance(pose)`` is the exact distance from the (inflated) footprint at ``pose`` to
  the nearest obstacle or the workspace border, capped at ``cap``; ``<= 0`` when they
  overlap (it is then ``0`` or the negative border penetration, not a depth).
  Footprints of polygons are exact; circle obstacles and circular objects are exact disks.
* ``pose_free(pose)`` is ``clearance(pose) > margin``.
* ``motion_free(a, b)`` never answers True for a motion (along ``se2.interpolate``) that
  passes through a pose with clearance ``<= margin / 2``, and answers True for every
  motion whose poses all have clearance ``> margin``. It uses conservative advancement: at
  a checked pose with clearance ``c > margin``, no footprint point moves by more than
  ``c - margin / 2`` before the next checked pose (a point at distance ``r`` from the
  object's origin moves at most ``|dt| + r |dtheta|`` along the blend).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely
from numpy.typing import ArrayLike

from lamp.geometry import se2
from lamp.geometry.object_space import inflated_outline
from lamp.geometry.primitives import Circle, Obstacle
from lamp.geometry.shapes import obstacle_geometry

#: Clearance (m) a pose must keep to be free (motions keep half of it between checks).
DEFAULT_EXACT_MARGIN = 0.002
#: Clearances above this (m) are reported as this: only small ones matter here.
DEFAULT_EXACT_CAP = 0.25


class ExactSpace:
    """Exact footprint clearance of ``shape`` (inflated by ``inflation``) in a workspace.

    Args:
        shape: the object's shape (object frame).
        workspace: (W, H); the border of [0, W] x [0, H] is a wall.
        obstacles: static obstacles (world frame).
        inflation: footprint growth, as in ``ObjectSpace`` (>= 0 for circles' sake too).
        margin: clearance a free pose must have (m).
        cap: clearances are exact up to this (m) and reported as ``cap`` beyond it.
    """

    def __init__(
        self,
        shape: object,
        workspace: tuple[float, float],
        obstacles: Sequence[Obstacle] = (),
        inflation: float = 0.0,
        margin: float = DEFAULT_EXACT_MARGIN,
        cap: float = DEFAULT_EXACT_CAP,
    ) -> None:
        if not (margin > 0 and math.isfinite(margin)):
            raise ValueError(f"margin must be finite and > 0, got {margin!r}")
        if not (cap > margin and math.isfinite(cap)):
            raise ValueError(f"cap must be finite and > margin, got {cap!r}")
        self.shape = shape
        self.workspace = (float(workspace[0]), float(workspace[1]))
        self.margin = float(margin)
        self.cap = float(cap)
        self.inflation = float(inflation)
        if isinstance(shape, Circle):
            self._radius: float | None = float(shape.radius) + self.inflation
            if self._radius <= 0:
                raise ValueError(f"inflation {inflation} makes the circle vanish")
            self._outline = np.zeros((0, 2))
            self.reach = self._radius
        else:
            self._radius = None
            self._outline = inflated_outline(shape, self.inflation)  # (V, 2) object frame
            self.reach = float(np.max(np.hypot(self._outline[:, 0], self._outline[:, 1])))
        disks = [o for o in obstacles if isinstance(o.shape, Circle)]
        others = [o for o in obstacles if not isinstance(o.shape, Circle)]
        self._disk_xy = np.array([o.pose[:2] for o in disks], dtype=float).reshape(-1, 2)
        self._disk_r = np.array([o.shape.radius for o in disks], dtype=float)
        self._disk_pad = float(np.max(self._disk_r, initial=0.0))
        self._disk_geoms = shapely.points(self._disk_xy) if len(disks) else np.zeros(0, object)
        self._polys = np.array([obstacle_geometry(o) for o in others], dtype=object)
        self._disk_tree = shapely.STRtree(self._disk_geoms) if len(disks) else None
        self._poly_tree = shapely.STRtree(self._polys) if len(others) else None
        for g in self._polys:
            shapely.prepare(g)
        self.n_queries = 0

    @classmethod
    def from_space(cls, space: object, **kwargs: float) -> ExactSpace:
        """The exact twin of an ``ObjectSpace`` (same shape, workspace, obstacles, inflation)."""
        return cls(space.shape, space.workspace, space.obstacles, space.inflation, **kwargs)

    # ------------------------------------------------------------------ poses
    def _footprint(self, pose: np.ndarray) -> tuple[shapely.Geometry, float]:
        """Footprint geometry at ``pose`` and its exact distance to the border (signed)."""
        w, h = self.workspace
        if self._radius is not None:
            x, y = float(pose[0]), float(pose[1])
            border = min(x, w - x, y, h - y) - self._radius
            return shapely.Point(x, y), border
        pts = se2.transform_points(pose, self._outline)
        border = float(np.min(np.minimum(np.minimum(pts[:, 0], w - pts[:, 0]),
                                         np.minimum(pts[:, 1], h - pts[:, 1]))))
        return shapely.Polygon(pts), border

    def clearance(self, pose: ArrayLike) -> float:
        """Exact clearance of the footprint at ``pose`` (see the module's guarantees)."""
        p = np.asarray(pose, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"pose must be a finite (x, y, theta), got {pose!r}")
        self.n_queries += 1
        geom, best = self._footprint(p)
        if best <= 0:
            return best
        best = min(best, self.cap)
        pad = self.cap + (self._radius or 0.0)
        x0, y0, x1, y1 = geom.bounds
        box = shapely.box(x0 - pad, y0 - pad, x1 + pad, y1 + pad)
        if self._poly_tree is not None:
            idx = self._poly_tree.query(box)
            if len(idx):
                d = shapely.distance(geom, self._polys[idx])
                best = min(best, float(np.min(d)) - (self._radius or 0.0))
        if self._disk_tree is not None and best > 0:
            r = self._disk_pad  # the tree holds centres: reach their disks' edges too
            idx = self._disk_tree.query(shapely.box(x0 - pad - r, y0 - pad - r,
                                                    x1 + pad + r, y1 + pad + r))
            if len(idx):
                d = shapely.distance(geom, self._disk_geoms[idx]) - self._disk_r[idx]
                best = min(best, float(np.min(d)) - (self._radius or 0.0))
        return best

    def pose_free(self, poses: ArrayLike) -> np.ndarray:
        """(...) bool: clearance > ``margin`` at each of the (..., 3) poses."""
        arr = np.asarray(poses, dtype=float)
        flat = arr.reshape(-1, 3)
        out = np.array([self.clearance(p) > self.margin for p in flat], dtype=bool)
        return out.reshape(arr.shape[:-1])

    # ---------------------------------------------------------------- motions
    def motion_free(self, a: ArrayLike, b: ArrayLike) -> bool:
        """Whether the blend from ``a`` to ``b`` keeps clearance (conservative advancement)."""
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        trans = math.hypot(b[0] - a[0], b[1] - a[1])
        rate = trans + self.reach * abs(float(se2.wrap_angle(b[2] - a[2])))  # max point displacement over t in [0, 1]
        t = 0.0
        while True:
            c = self.clearance(se2.interpolate(a, b, t) if t > 0.0 else a)
            if c <= self.margin:
                return False
            if t >= 1.0:
                return True
            if rate <= 0.0:
                return True
            t = min(1.0, t + (c - 0.5 * self.margin) / rate)

    def motions_free(self, starts: ArrayLike, ends: ArrayLike) -> np.ndarray:
        """(M,) :meth:`motion_free` of each pair of (M, 3) poses."""
        a = np.asarray(starts, dtype=float).reshape(-1, 3)
        b = np.asarray(ends, dtype=float).reshape(-1, 3)
        if a.shape != b.shape:
            raise ValueError(f"starts and ends must match, got {a.shape} and {b.shape}")
        return np.array([self.motion_free(p, q) for p, q in zip(a, b, strict=True)], dtype=bool)
