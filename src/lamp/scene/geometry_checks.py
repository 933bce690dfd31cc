"""The geometric rules of the scene format: everything inside the workspace (within the
format's 1e-6 m rounding), nothing overlapping at the start, objects clear of obstacles at
their starts, their goals and their tasks' goals. Exact footprints (disks and world polygons, Shapely)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely

from lamp.geometry.se2 import transform_points
from lamp.scene.errors import Ctx, fmt_xy
from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, Shape

__all__ = ["EPS", "Footprint", "check_geometry"]

EPS = 1e-6  # metres: rounding allowed in containment and overlap tests (scene-format.md)


# --------------------------------------------------------------------------- geometry


class Footprint:
    """Exact footprint of one scene item: a disk (centre, radius) or a world polygon."""

    def __init__(self, field: str, what: str, shape: Shape, pose: Sequence[float]) -> None:
        self.field = field
        self.what = what
        x, y, th = (float(c) for c in pose)
        if isinstance(shape, Circle):
            self.center: np.ndarray | None = np.array([x, y])
            self.radius = float(shape.radius)
            self.vertices: np.ndarray | None = None
            self.lo = self.center - self.radius
            self.hi = self.center + self.radius
        else:
            if isinstance(shape, Rectangle):
                hx, hy = 0.5 * shape.size[0], 0.5 * shape.size[1]
                local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
            else:
                local = np.asarray(shape.points, dtype=float)
            self.center = None
            self.radius = 0.0
            self.vertices = transform_points((x, y, th), local)
            self.lo = self.vertices.min(axis=0)
            self.hi = self.vertices.max(axis=0)
        self._geom: shapely.Geometry | None = None
        self._shrunk: shapely.Geometry | None = None

    @property
    def geom(self) -> shapely.Geometry:
        if self._geom is None:
            self._geom = shapely.Polygon(self.vertices)
        return self._geom

    @property
    def shrunk(self) -> shapely.Geometry:
        """The polygon shrunk by EPS: intersecting it means penetrating by more than EPS."""
        if self._shrunk is None:
            self._shrunk = shapely.buffer(self.geom, -EPS, join_style="mitre")
        return self._shrunk


def _overlaps(a: Footprint, b: Footprint) -> bool:
    """Positive-area intersection of two footprints (touching within EPS is not overlap)."""
    if np.any(a.lo >= b.hi - EPS) or np.any(b.lo >= a.hi - EPS):
        return False  # bounding boxes at most touch
    if a.center is not None and b.center is not None:
        return math.hypot(*(a.center - b.center)) < a.radius + b.radius - EPS
    if a.center is not None or b.center is not None:
        disk, poly = (a, b) if a.center is not None else (b, a)
        return float(shapely.distance(shapely.Point(disk.center), poly.geom)) < disk.radius - EPS
    return bool(shapely.intersects(a.shrunk, b.geom))


def _check_inside(ctx: Ctx, fp: Footprint, W: float, H: float) -> None:
    if np.any(fp.lo < -EPS) or fp.hi[0] > W + EPS or fp.hi[1] > H + EPS:
        ctx.fail(
            fp.field,
            f"{fp.what} lies outside the workspace [0, {W:g}] x [0, {H:g}]: its footprint spans "
            f"x [{fp.lo[0]:.6g}, {fp.hi[0]:.6g}], y [{fp.lo[1]:.6g}, {fp.hi[1]:.6g}]",
        )


def _describe_obstacle(o: Obstacle) -> str:
    if isinstance(o.shape, Circle):
        return f"circle at {fmt_xy(o.pose[:2])}, radius {o.shape.radius:g}"
    if isinstance(o.shape, Rectangle):
        return f"rectangle at {fmt_xy(o.pose[:2])}, size {fmt_xy(o.shape.size)}"
    return f"polygon with {len(o.shape.points)} vertices"


def check_geometry(ctx: Ctx, scene: Scene) -> None:
    W, H = scene.workspace
    r = scene.robot_radius
    obstacles = [
        Footprint(f"obstacles[{i}]", _describe_obstacle(o), o.shape, o.pose)
        for i, o in enumerate(scene.obstacles)
    ]
    robots = [
        Footprint(
            f"robots.starts[{i}]", f"robot at {fmt_xy(p)} (radius {r:g})", Circle(r), (*p, 0.0)
        )
        for i, p in enumerate(scene.robot_starts)
    ]
    starts = [
        Footprint(
            f"objects[{k}].start", f"object {k} at its start {fmt_xy(o.start)}", o.shape, o.start
        )
        for k, o in enumerate(scene.objects)
    ]
    goals = [
        Footprint(
            f"objects[{k}].goal", f"object {k} at its goal {fmt_xy(o.goal)}", o.shape, o.goal
        )
        for k, o in enumerate(scene.objects)
    ]
    tasks = [
        Footprint(f"tasks[{i}].goal", f"object {t.object} at the goal of tasks[{i}] "
                  f"{fmt_xy(t.goal)}", scene.objects[t.object].shape, t.goal)
        for i, t in enumerate(scene.tasks)
    ]
    for fp in (*obstacles, *robots, *starts, *goals, *tasks):
        _check_inside(ctx, fp, W, H)

    def pairwise(group_a: list[Footprint], group_b: list[Footprint], same: bool) -> None:
        for i, a in enumerate(group_a):
            for b in group_b[i + 1 :] if same else group_b:
                if _overlaps(a, b):
                    ctx.fail(a.field, f"{a.what} overlaps {b.field} ({b.what})")

    # Robots against each other: vectorised, since teams can be large.
    p = scene.robot_starts_array
    dist = np.hypot(*(p[:, None, :] - p[None, :, :]).transpose(2, 0, 1))
    close = np.argwhere(np.triu(dist < 2.0 * r - EPS, k=1))
    if close.size:
        i, j = (int(c) for c in close[np.lexsort((close[:, 0], close[:, 1]))][0])
        ctx.fail(robots[j].field, f"{robots[j].what} overlaps {robots[i].field} ({robots[i].what})")
    pairwise(robots, obstacles, same=False)
    pairwise(robots, starts, same=False)
    pairwise(starts, obstacles, same=False)
    pairwise(goals, obstacles, same=False)
    pairwise(tasks, obstacles, same=False)
    pairwise(starts, starts, same=True)
    pairwise(goals, goals, same=True)
