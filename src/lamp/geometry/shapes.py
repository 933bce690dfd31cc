"""Shape footprints: outlines as vertex arrays and Shapely geometries, in local or world frame.

Circles are exact in Shapely (buffered points) wherever exactness matters; outlines used
for drawing and image rasterisation approximate them with ``CIRCLE_SEGMENTS`` vertices.
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import ArrayLike

from lamp.geometry.primitives import Circle, Obstacle, Polygon, Rectangle, Shape
from lamp.geometry.se2 import transform_points

CIRCLE_SEGMENTS = 64


def local_outline(shape: Shape, segments: int = CIRCLE_SEGMENTS) -> np.ndarray:
    """(V, 2) counter-clockwise boundary vertices in the shape's own frame."""
    if isinstance(shape, Circle):
        a = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
        return shape.radius * np.stack([np.cos(a), np.sin(a)], axis=1)
    if isinstance(shape, Rectangle):
        hx, hy = 0.5 * shape.size[0], 0.5 * shape.size[1]
        return np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]], dtype=float)
    pts = np.asarray(shape.points, dtype=float)
    # shoelace: make counter-clockwise
    area2 = np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
    return pts if area2 > 0 else pts[::-1].copy()


def world_outline(shape: Shape, pose: ArrayLike, segments: int = CIRCLE_SEGMENTS) -> np.ndarray:
    """(V, 2) boundary vertices of ``shape`` placed at ``pose``."""
    return transform_points(pose, local_outline(shape, segments))


def to_shapely(shape: Shape, pose: ArrayLike = (0.0, 0.0, 0.0)) -> shapely.Geometry:
    """Shapely geometry of ``shape`` at ``pose`` (circles as exact-ish buffered points)."""
    pose = np.asarray(pose, dtype=float)
    if isinstance(shape, Circle):
        return shapely.Point(pose[0], pose[1]).buffer(shape.radius, quad_segs=32)
    return shapely.Polygon(world_outline(shape, pose))


def to_shapely_many(shape: Shape, poses: ArrayLike) -> np.ndarray:
    """``to_shapely(shape, q)`` for each pose ``q`` of ``poses`` (P, 3), as an array of P
    geometries built in one call; each is the very geometry ``to_shapely`` builds (the
    same vertices to the last bit: each pose's cosine and sine are taken as there, and
    the vertices by the same operations in the same order)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    if isinstance(shape, Circle):
        return shapely.buffer(shapely.points(poses[:, :2]), shape.radius, quad_segs=32)
    local = local_outline(shape)
    c = np.array([np.cos(a) for a in poses[:, 2]])[:, None]
    s = np.array([np.sin(a) for a in poses[:, 2]])[:, None]
    out = np.empty((len(poses), *local.shape), dtype=float)
    out[..., 0] = poses[:, 0, None] + c * local[None, :, 0] - s * local[None, :, 1]
    out[..., 1] = poses[:, 1, None] + s * local[None, :, 0] + c * local[None, :, 1]
    return shapely.polygons(out)


def obstacle_geometry(obstacle: Obstacle) -> shapely.Geometry:
    return to_shapely(obstacle.shape, obstacle.pose)


def half_extents(shape: Shape) -> tuple[float, float]:
    """Half extents of the shape's bounding box in its own frame."""
    if isinstance(shape, Circle):
        return float(shape.radius), float(shape.radius)
    if isinstance(shape, Rectangle):
        return 0.5 * float(shape.size[0]), 0.5 * float(shape.size[1])
    pts = np.abs(np.asarray(shape.points, dtype=float))
    return float(pts[:, 0].max()), float(pts[:, 1].max())


def narrowest_width(shape: Shape) -> float:
    """The shape's width in its narrowest direction (the least distance between two
    parallel lines enclosing it): a circle's diameter, a rectangle's shorter side, and for a
    polygon the least, over the edges of its convex hull, of the farthest vertex's distance
    from the edge's line (a minimum is always attained along a hull edge)."""
    if isinstance(shape, Circle):
        return 2.0 * float(shape.radius)
    if isinstance(shape, Rectangle):
        return float(min(shape.size))
    hull = np.asarray(shapely.MultiPoint(np.asarray(shape.points, float)).convex_hull
                      .exterior.coords)[:-1]
    edges = np.roll(hull, -1, axis=0) - hull
    normals = np.column_stack([-edges[:, 1], edges[:, 0]]) / np.hypot(*edges.T)[:, None]
    heights = np.abs(np.einsum("ek,evk->ev", normals, hull[None, :, :] - hull[:, None, :]))
    return float(heights.max(axis=1).min())


def is_polygon(shape: Shape) -> bool:
    return isinstance(shape, (Rectangle, Polygon))


def signed_distance(shape: Shape, local_points: ArrayLike) -> np.ndarray:
    """Signed distance from (..., 2) points in the shape's frame to its boundary.

    Negative inside, positive outside. Exact for circles and rectangles; polygons use the
    minimum distance to their edges with an even-odd inside test.
    """
    p = np.asarray(local_points, dtype=float)
    if isinstance(shape, Circle):
        return np.hypot(p[..., 0], p[..., 1]) - shape.radius
    if isinstance(shape, Rectangle):
        hx, hy = 0.5 * shape.size[0], 0.5 * shape.size[1]
        qx = np.abs(p[..., 0]) - hx
        qy = np.abs(p[..., 1]) - hy
        outside = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
        inside = np.minimum(np.maximum(qx, qy), 0.0)
        return outside + inside
    verts = local_outline(shape)
    a = verts
    b = np.roll(verts, -1, axis=0)
    flat = p.reshape(-1, 2)
    ab = b - a  # (V, 2)
    ap = flat[:, None, :] - a[None, :, :]  # (P, V, 2)
    t = np.clip(np.sum(ap * ab, axis=-1) / np.maximum(np.sum(ab * ab, axis=-1), 1e-18), 0.0, 1.0)
    closest = a[None] + t[..., None] * ab[None]
    dist = np.min(np.hypot(*(flat[:, None, :] - closest).transpose(2, 0, 1)), axis=1)
    # even-odd rule
    ya, yb = a[None, :, 1], b[None, :, 1]
    py = flat[:, 1:2]
    crosses = (ya > py) != (yb > py)
    xint = a[None, :, 0] + (py - ya) / np.where(yb - ya == 0, 1e-18, yb - ya) * ab[None, :, 0]
    inside = np.sum(crosses & (flat[:, 0:1] < xint), axis=1) % 2 == 1
    return np.where(inside, -dist, dist).reshape(p.shape[:-1])
