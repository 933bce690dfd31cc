"""Obstacles in the array form the compiled clearance kernels read (``GeometrySet``), and
the conversions into :class:`~lamp.geometry.primitives.Obstacle` from the forms callers pass."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from lamp.geometry.primitives import Circle, Obstacle, Polygon, Rectangle
from lamp.geometry.se2 import transform_points
from lamp.geometry.shapes import local_outline

__all__ = ["GeometrySet", "as_obstacle", "obstacle_from_dict"]


def obstacle_from_dict(d: dict[str, Any]) -> Obstacle:
    """An :class:`Obstacle` from the scene-file dict form (world frame).

    ``{"type": "circle", "center": [x, y], "radius": r}``,
    ``{"type": "rectangle", "center": [x, y], "size": [sx, sy], "angle": a}`` or
    ``{"type": "polygon", "points": [[x, y], ...]}``.
    """
    if not isinstance(d, dict):
        raise ValueError(f"extra obstacle must be a dict in scene-file form, got {d!r}")
    kind = d.get("type")
    try:
        if kind == "circle":
            cx, cy = (float(v) for v in d["center"])
            return Obstacle(Circle(float(d["radius"])), (cx, cy, 0.0))
        if kind == "rectangle":
            cx, cy = (float(v) for v in d["center"])
            sx, sy = (float(v) for v in d["size"])
            return Obstacle(Rectangle((sx, sy)), (cx, cy, float(d.get("angle", 0.0))))
        if kind == "polygon":
            pts = tuple((float(x), float(y)) for x, y in d["points"])
            return Obstacle(Polygon(pts))
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"malformed extra obstacle {d!r}: {exc}") from exc
    raise ValueError(f"extra obstacle has unknown type {kind!r}; expected circle, rectangle or polygon")


def as_obstacle(item: Any) -> Obstacle:
    if isinstance(item, Obstacle):
        return item
    if isinstance(item, dict):
        return obstacle_from_dict(item)
    if isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], (Circle, Rectangle, Polygon)):
        shape, pose = item
        return Obstacle(shape, tuple(float(v) for v in pose))  # type: ignore[arg-type]
    raise ValueError(
        f"obstacle must be an Obstacle, a (Shape, pose) pair or a scene-file dict, got {item!r}"
    )


class GeometrySet:
    """Obstacles as flat arrays: circles ``(C, 3)`` = (cx, cy, radius) and polygons as
    concatenated world vertices ``verts (P, 2)`` with ``ptr (n_poly + 1,)`` offsets.

    Rectangles and polygons become polygons (exact); circles stay circles (exact).
    """

    def __init__(self, obstacles: Iterable[Obstacle]) -> None:
        circles: list[tuple[float, float, float]] = []
        verts: list[np.ndarray] = []
        for ob in obstacles:
            x, y, th = (float(v) for v in ob.pose)
            if isinstance(ob.shape, Circle):
                circles.append((x, y, float(ob.shape.radius)))
            else:
                verts.append(transform_points((x, y, th), local_outline(ob.shape)))
        self.circles = np.array(circles, dtype=np.float64).reshape(-1, 3)
        if verts:
            self.verts = np.ascontiguousarray(np.concatenate(verts, axis=0), dtype=np.float64)
            self.ptr = np.cumsum([0] + [len(v) for v in verts]).astype(np.int64)
        else:
            self.verts = np.zeros((0, 2), dtype=np.float64)
            self.ptr = np.zeros(1, dtype=np.int64)
        self._bounds: np.ndarray | None = None  # filled by bounds()

    @staticmethod
    def concat(a: GeometrySet, b: GeometrySet) -> GeometrySet:
        out = GeometrySet(())
        out.circles = np.ascontiguousarray(np.concatenate([a.circles, b.circles]))
        out.verts = np.ascontiguousarray(np.concatenate([a.verts, b.verts]))
        out.ptr = np.concatenate([a.ptr, b.ptr[1:] + a.ptr[-1]]).astype(np.int64)
        return out

    def inserted(self, other: GeometrySet, circles_before: int, polygons_before: int
                 ) -> GeometrySet:
        """This set with ``other``'s circles placed after its first ``circles_before``
        circles and ``other``'s polygons after its first ``polygons_before`` polygons:
        ``GeometrySet(obs[:i] + new + obs[i:])`` from ``GeometrySet(obs)`` and
        ``GeometrySet(new)``, array for array, given the circles and polygons in
        ``obs[:i]``."""
        c, p = circles_before, polygons_before
        v = int(self.ptr[p])
        out = GeometrySet(())
        out.circles = np.ascontiguousarray(np.concatenate(
            [self.circles[:c], other.circles, self.circles[c:]]))
        out.verts = np.ascontiguousarray(np.concatenate(
            [self.verts[:v], other.verts, self.verts[v:]]))
        out.ptr = np.concatenate([self.ptr[:p + 1], other.ptr[1:] + v,
                                  self.ptr[p + 1:] + len(other.verts)]).astype(np.int64)
        return out

    @property
    def n_polygons(self) -> int:
        return len(self.ptr) - 1

    def bounds(self) -> np.ndarray:
        """(C + n_polygons, 4) bounding boxes (x0, y0, x1, y1): the circles', then the
        polygons' (computed once)."""
        out = self._bounds
        if out is None:
            c = self.circles
            circ = np.stack([c[:, 0] - c[:, 2], c[:, 1] - c[:, 2],
                             c[:, 0] + c[:, 2], c[:, 1] + c[:, 2]], axis=1)
            if self.n_polygons:
                lo = np.minimum.reduceat(self.verts, self.ptr[:-1], axis=0)
                hi = np.maximum.reduceat(self.verts, self.ptr[:-1], axis=0)
                poly = np.concatenate([lo, hi], axis=1)
            else:
                poly = np.zeros((0, 4))
            out = self._bounds = np.concatenate([circ, poly])
        return out

    def near(self, box: tuple[float, float, float, float], reach: float) -> GeometrySet:
        """The obstacles whose bounding box comes within ``reach`` of ``box`` (x0, y0,
        x1, y1), or ``self`` when that is all of them.

        Guarantee (``tests/test_robot_space.py``): for a segment inside ``box`` and a
        threshold ``0 < t <= reach``, ``segment_clearance`` over the result is ``>= t``
        exactly when it is over ``self``: an obstacle nearer the segment than ``t`` has
        its bounding box within ``reach`` of ``box``, so it is kept."""
        b = self.bounds()
        x0, y0, x1, y1 = (float(v) for v in box)
        keep = ((b[:, 0] <= x1 + reach) & (b[:, 2] >= x0 - reach)
                & (b[:, 1] <= y1 + reach) & (b[:, 3] >= y0 - reach))
        if keep.all():
            return self
        nc = len(self.circles)
        out = GeometrySet(())
        out.circles = np.ascontiguousarray(self.circles[keep[:nc]])
        polys = np.flatnonzero(keep[nc:])
        if len(polys):
            starts, ends = self.ptr[polys], self.ptr[polys + 1]
            out.verts = np.ascontiguousarray(np.concatenate(
                [self.verts[a:e] for a, e in zip(starts, ends, strict=True)]))
            out.ptr = np.concatenate([[0], np.cumsum(ends - starts)]).astype(np.int64)
        return out
