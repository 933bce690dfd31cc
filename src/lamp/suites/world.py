"""The exact clearance world of the scene checks: obstacles and object footprints as
padded convex pieces for the compiled kernels (``lamp.suites.kernels``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from numpy.typing import ArrayLike

from lamp.geometry.shapes import local_outline, obstacle_geometry
from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, Shape
from lamp.suites import kernels as K


# --------------------------------------------------------------------------- world
@dataclass(frozen=True)
class World:
    """Static obstacles as convex pieces for the kernels (see ``kernels`` docstring)."""

    width: float
    height: float
    circ: np.ndarray
    pv: np.ndarray
    pn: np.ndarray
    pb: np.ndarray

    @property
    def args(self) -> tuple[Any, ...]:
        return (self.circ, self.pv, self.pn, self.pb, self.width, self.height)


@dataclass(frozen=True)
class Footprint:
    """A movable shape for the kernels: a disk (``radius > 0``) or convex pieces."""

    radius: float
    ov: np.ndarray
    on: np.ndarray
    reach: float
    #: symmetry period of the footprint under rotation (0 for rotation-invariant disks)
    period: float

    @property
    def args(self) -> tuple[Any, ...]:
        return (self.radius, self.ov, self.on, self.reach)


def _ccw(pts: np.ndarray) -> np.ndarray:
    area2 = np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
    return pts if area2 > 0 else pts[::-1].copy()


def _convex_pieces(pts: np.ndarray) -> list[np.ndarray]:
    """Split a simple polygon into convex CCW pieces (itself when already convex)."""
    pts = _ccw(np.asarray(pts, dtype=float))
    poly = shapely.Polygon(pts)
    if abs(poly.convex_hull.area - poly.area) <= 1e-12 * max(1.0, poly.area):
        return [pts]
    tris = shapely.constrained_delaunay_triangles(poly)
    return [_ccw(np.asarray(t.exterior.coords, dtype=float)[:-1]) for t in tris.geoms]


def _pad(pieces: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    if not pieces:
        return np.zeros((0, 3, 2)), np.zeros(0, dtype=np.int64)
    vmax = max(len(p) for p in pieces)
    out = np.empty((len(pieces), vmax, 2))
    for i, p in enumerate(pieces):
        out[i, : len(p)] = p
        out[i, len(p) :] = p[-1]
    return np.ascontiguousarray(out), np.array([len(p) for p in pieces], dtype=np.int64)


def footprint_of(shape: Shape) -> Footprint:
    """Kernel footprint of an object shape (its own frame)."""
    if isinstance(shape, Circle):
        return Footprint(
            float(shape.radius),
            np.zeros((0, 3, 2)),
            np.zeros(0, np.int64),
            float(shape.radius),
            0.0,
        )
    pts = local_outline(shape)
    pieces = _convex_pieces(pts)
    ov, on = _pad(pieces)
    reach = float(np.max(np.hypot(pts[:, 0], pts[:, 1])))
    period = math.pi if isinstance(shape, Rectangle) else 2.0 * math.pi
    return Footprint(0.0, ov, on, reach, period)


def build_world(workspace: tuple[float, float], obstacles: Sequence[Obstacle]) -> World:
    """Kernel world of static ``obstacles`` in the workspace ``[0, W] x [0, H]``."""
    circles = []
    pieces: list[np.ndarray] = []
    for ob in obstacles:
        if isinstance(ob.shape, Circle):
            circles.append((ob.pose[0], ob.pose[1], ob.shape.radius))
            continue
        if isinstance(ob.shape, Rectangle):
            pts = local_outline(ob.shape)
            c, s = math.cos(ob.pose[2]), math.sin(ob.pose[2])
            world = np.stack(
                [
                    ob.pose[0] + c * pts[:, 0] - s * pts[:, 1],
                    ob.pose[1] + s * pts[:, 0] + c * pts[:, 1],
                ],
                axis=1,
            )
            pieces.append(_ccw(world))
        else:
            geom = obstacle_geometry(ob)
            pieces.extend(_convex_pieces(np.asarray(geom.exterior.coords, dtype=float)[:-1]))
    pv, pn = _pad(pieces)
    pb = np.zeros((len(pieces), 3))
    for i, p in enumerate(pieces):
        cx, cy = p.mean(axis=0)
        pb[i] = (cx, cy, float(np.max(np.hypot(p[:, 0] - cx, p[:, 1] - cy))))
    circ = np.asarray(circles, dtype=float).reshape(-1, 3)
    return World(float(workspace[0]), float(workspace[1]), np.ascontiguousarray(circ), pv, pn, pb)


def object_obstacles(
    scene: Scene, object_index: int | None, object_poses: ArrayLike | None = None
) -> list[Obstacle]:
    """The scene's obstacles plus every object except ``object_index`` at ``object_poses``
    (default: the objects' start poses)."""
    poses = scene.object_starts() if object_poses is None else np.asarray(object_poses, float)
    if poses.shape != (len(scene.objects), 3):
        raise ValueError(
            f"object_poses must have shape ({len(scene.objects)}, 3), got {poses.shape}"
        )
    out = list(scene.obstacles)
    for i, (obj, p) in enumerate(zip(scene.objects, poses, strict=True)):
        if i != object_index:
            out.append(Obstacle(obj.shape, (float(p[0]), float(p[1]), float(p[2]))))
    return out


def object_world(scene: Scene, object_index: int, object_poses: ArrayLike | None = None) -> World:
    return build_world(scene.workspace, object_obstacles(scene, object_index, object_poses))


def clearance(shape: Shape, world: World, poses: ArrayLike) -> np.ndarray:
    """Exact clearance (m) of ``shape`` at (..., 3) ``poses`` in ``world`` (negative: overlap)."""
    arr = np.asarray(poses, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ValueError(f"poses must have shape (..., 3), got {arr.shape}")
    fp = footprint_of(shape)
    flat = np.ascontiguousarray(arr.reshape(-1, 3))
    return K.batch_clearance(flat, *fp.args, *world.args).reshape(arr.shape[:-1])


def point_clearance(world: World, points: ArrayLike) -> np.ndarray:
    """Exact distance (m) from (..., 2) points to the obstacles and border of ``world``."""
    arr = np.asarray(points, dtype=float)
    flat = np.ascontiguousarray(arr.reshape(-1, 2))
    return K.point_clearance(flat, *world.args).reshape(arr.shape[:-1])
