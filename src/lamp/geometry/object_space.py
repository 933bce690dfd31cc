"""Collision and clearance queries for one movable object in a static world.

``ObjectSpace`` answers, for ONE object shape, whether poses and straight SE(2) motions
(``lamp.geometry.se2.interpolate``) are free of the obstacles and inside the workspace,
and how much clearance they have. It is the validity checker of the object-level search
(``lamp.search``): a D* Lite or A* search checks thousands of edges, so every query is a
compiled (Numba) loop over a precomputed obstacle distance grid.

How it works
------------
* **Obstacle distance grid.** Obstacles are rasterised on cells of side ``resolution``
  (default 4 mm) covering the workspace (held in tiles, filled on demand on large maps
  with distances capped at ``DEFAULT_GRID_CAP``: :mod:`lamp.geometry.distance_tiles`). A cell is *occupied* when its centre lies within
  ``h = resolution / sqrt(2)`` (half the cell diagonal) of an obstacle, so every obstacle
  point lies in an occupied cell and every occupied centre lies within ``h`` of an
  obstacle. ``scipy.ndimage.distance_transform_edt`` gives, at every free cell centre g,
  the distance ``D(g)`` to the nearest occupied centre, so ``|D - d| <= h`` for the true
  distance ``d`` to the obstacles. For any point p whose nearest cell centre is g
  (``|p - g| <= h``) and since ``D`` is 1-Lipschitz, ``D(g) - 2h <= d(p) <= D(g) + 2h``:
  the grid stores the lower bound ``D(g) - 2h`` (occupied cells store ``-2h``: inside
  obstacles the value only says "not free", it is not a penetration depth).
* **Footprint as disks.** The (inflated) footprint is represented by disks ``(p_j, r_j)``
  in the object frame whose union covers its boundary: a circle is one disk (its centre,
  radius ``R + inflation``), a polygon is sampled along its boundary every
  ``<= sample_spacing`` metres with ``r_j`` = half the local spacing. A disk is clear when
  ``lowerbound(p_j) > r_j``; the footprint clearance lower bound is
  ``min_j (lowerbound(p_j) - r_j)``.
* **Obstacles inside the footprint.** Boundary disks only see obstacles that reach the
  boundary. An obstacle (a connected set) that meets a polygonal footprint without
  touching its boundary lies entirely inside it, so one representative point per obstacle
  is tested for containment in the footprint polygon (exact, no sampling).
* **Border.** The workspace is convex, so the distance of a polygon to the border is
  attained at a vertex: the border part is exact (vertices; circle: centre minus radius).
* **Coarse first.** Boolean queries of polygonal footprints first try a handful of disks
  covering the whole footprint (one per ``cover_cell`` cell of its bounding box): when
  they are all clear, that looser bound already decides; only otherwise are the boundary
  disks and representative points consulted. ``clearance`` always uses the tight bound.
* **Motions** use conservative advancement: at a checked pose with clearance lower bound
  ``c > margin``, the next pose checked is one where no point of the object has moved by
  more than ``c + margin / 2``; with both ends having clearance ``> margin`` every pose in
  between has true clearance ``>= margin / 4 > 0``. Near obstacles this samples every
  ``>= 1.5 * margin`` (7.5 mm for the default 5 mm margin) of point displacement; in the
  open it takes large steps. A motion is free when every checked pose (both ends
  included) has clearance lower bound ``> motion_margin``.

Guarantees (tested against Shapely in ``tests/test_object_space.py``)
---------------------------------------------------------------------
* ``pose_free`` never answers True for a pose whose inflated footprint intersects an
  obstacle or leaves the workspace; ``motion_free`` never answers True for a motion that
  passes through such a pose.
* ``clearance`` is a lower bound of the true clearance and at most ``band`` below it,
  where ``band = 4 * h + sample_spacing / 2`` (13.3 mm at the defaults) for the obstacle
  part (the border part is exact); on a tiled grid filled on demand (large maps) the
  obstacle part is moreover capped near the grid's ``cap`` (at least ``min_grid_cap``,
  so the two statements below hold unchanged). So a pose whose true clearance exceeds ``band`` is
  reported free, and a motion whose every pose has true clearance above
  ``band + motion_margin`` is reported free.

Inflation semantics (as GCo): circles grow in radius by ``inflation``; rectangles grow by
``inflation`` on every side (size + 2 * inflation, sharp corners); polygons are offset by
``inflation`` per edge with mitred corners (Shapely ``buffer(join_style="mitre")``, whose
mitre limit of 5 bevels only very sharp spikes). A negative inflation shrinks the footprint
the same way; it is meant for tolerating a small penetration when leaving a drifted pose
(``ObjectLattice.start_connections(tolerance=...)``), and must leave a non-empty footprint.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import shapely
from numpy.typing import ArrayLike

from lamp.geometry.distance_tiles import (
    DEFAULT_GRID_CAP,
    FULL_GRID_CELLS,
    TILE,
    DistanceTiles,
    grid_shape,
    shared_tiles,
)
from lamp.geometry.object_kernels import (
    batch_clearance,
    batch_motions_free,
)
from lamp.geometry.primitives import Circle, Obstacle, Rectangle, Shape
from lamp.geometry.shapes import local_outline, obstacle_geometry

if TYPE_CHECKING:  # the scene layer builds on geometry, not the other way round
    from lamp.scene.model import Scene

DEFAULT_RESOLUTION = 0.004
DEFAULT_MOTION_MARGIN = 0.005
DEFAULT_COVER_CELL = 0.08
#: A shared grid of static obstacles is used where its store (allocated at once, its
#: pages taken as tiles are filled) would be at most this many bytes.
SHARED_STORE_BYTES = 2**32
#: Spacing (m) of the positions along a motion around which the grid is prepared.
_PREPARE_STEP = 0.1


def inflated_outline(shape: Shape, inflation: float) -> np.ndarray | None:
    """(V, 2) counter-clockwise vertices of the inflated polygon footprint (object frame).

    Returns None for circles (their inflated footprint is the disk of radius
    ``radius + inflation``).
    """
    if isinstance(shape, Circle):
        if shape.radius + inflation <= 0:
            raise ValueError(
                f"inflation {inflation} makes the circle of radius {shape.radius} vanish"
            )
        return None
    if isinstance(shape, Rectangle):
        hx = 0.5 * shape.size[0] + inflation
        hy = 0.5 * shape.size[1] + inflation
        if min(hx, hy) <= 0:
            raise ValueError(f"inflation {inflation} makes the rectangle {shape.size} vanish")
        return np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]], dtype=float)
    pts = local_outline(shape)
    if inflation == 0.0:
        return pts
    poly = shapely.Polygon(pts).buffer(inflation, join_style="mitre")
    if poly.is_empty or poly.geom_type != "Polygon":
        raise ValueError(f"inflation {inflation} does not leave a single polygon footprint")
    out = np.asarray(poly.exterior.coords, dtype=float)[:-1]
    area2 = np.sum(out[:, 0] * np.roll(out[:, 1], -1) - np.roll(out[:, 0], -1) * out[:, 1])
    return out if area2 > 0 else out[::-1].copy()


def inflated_geometry(shape: Shape, pose: ArrayLike, inflation: float) -> shapely.Geometry:
    """Shapely geometry of the inflated footprint at ``pose`` (reference for tests/drawing)."""
    pose = np.asarray(pose, dtype=float)
    if isinstance(shape, Circle):
        return shapely.Point(pose[0], pose[1]).buffer(shape.radius + inflation, quad_segs=64)
    pts = inflated_outline(shape, inflation)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    world = np.stack(
        [pose[0] + c * pts[:, 0] - s * pts[:, 1], pose[1] + s * pts[:, 0] + c * pts[:, 1]], 1
    )
    return shapely.Polygon(world)


def _footprint_disks(
    shape: Shape, inflation: float, spacing: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Object-frame sampling of the inflated footprint.

    Returns (disk centres (S, 2), disk radii (S,), border points (B, 2), border radii (B,),
    polygon (V, 2) or an empty (0, 2) array for circles).
    """
    if isinstance(shape, Circle):
        inflated_outline(shape, inflation)  # validates that the disk does not vanish
        c = np.zeros((1, 2))
        r = np.array([shape.radius + inflation])
        return c, r, c.copy(), r.copy(), np.zeros((0, 2))
    poly = inflated_outline(shape, inflation)
    pts, rad = [], []
    nxt = np.roll(poly, -1, axis=0)
    for a, b in zip(poly, nxt, strict=True):
        length = float(np.hypot(*(b - a)))
        n = max(1, math.ceil(length / spacing))
        t = np.arange(n) / n
        pts.append(a + t[:, None] * (b - a))
        rad.append(np.full(n, 0.5 * length / n))
    return (
        np.concatenate(pts),
        np.concatenate(rad),
        poly.copy(),
        np.zeros(len(poly)),
        poly.copy(),
    )


def _cover_disks(poly: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Disks covering a polygon: one per cell (side <= ``cell``) of its bounding box that
    meets the polygon, centred on the cell with the half diagonal as radius."""
    x0, y0 = poly.min(axis=0)
    x1, y1 = poly.max(axis=0)
    nx = max(1, math.ceil((x1 - x0) / cell))
    ny = max(1, math.ceil((y1 - y0) / cell))
    sx, sy = (x1 - x0) / nx, (y1 - y0) / ny
    xs = x0 + sx * (np.arange(nx) + 0.5)
    ys = y0 + sy * (np.arange(ny) + 0.5)
    gx, gy = (a.ravel() for a in np.meshgrid(xs, ys))
    boxes = shapely.box(gx - sx / 2, gy - sy / 2, gx + sx / 2, gy + sy / 2)
    keep = shapely.intersects(shapely.Polygon(poly), boxes)
    centres = np.stack([gx[keep], gy[keep]], axis=1)
    return centres, np.full(len(centres), 0.5 * math.hypot(sx, sy))


def _new_grid(workspace: tuple[float, float], obstacles: tuple[Obstacle, ...],
              resolution: float, cap: float, static: tuple[Obstacle, ...]) -> DistanceTiles:
    """The distance grid of ``obstacles``: over the shared grid of their leading ``static``
    part where the map is large enough to be tiled on demand and that grid's store stays
    within ``SHARED_STORE_BYTES``; else one of its own."""
    n = len(static)
    ny, nx = grid_shape(workspace, resolution)
    tiles = -(-ny // TILE) * -(-nx // TILE)
    if (n and ny * nx > FULL_GRID_CELLS and tiles * TILE * TILE * 4 <= SHARED_STORE_BYTES
            and obstacles[:n] == static):
        base = shared_tiles(workspace, static, resolution, cap)
        return DistanceTiles(workspace, obstacles[n:], resolution, cap, base=base)
    return DistanceTiles(workspace, obstacles, resolution, cap=cap)


class ObjectSpace:
    """Collision/clearance queries for one movable object among static obstacles.

    Args:
        shape: the object's shape (object frame).
        workspace: (W, H); the workspace is [0, W] x [0, H] and its border is a wall.
        obstacles: static obstacles (world frame), e.g. the scene's obstacles plus the other
            objects at their current poses.
        inflation: grow the object's footprint by this much (see module docstring).
        resolution: obstacle grid cell side in metres.
        sample_spacing: maximal spacing of boundary samples (default: ``resolution``).
        motion_margin: clearance a motion must keep at its checked poses.
        cover_cell: cell size of the coarse covering disks (a fast first test for
            polygonal footprints in boolean queries; does not change any answer's guarantee).
        grid: the distance grid to use (it depends on the obstacles, workspace and
            resolution only, so spaces of the same obstacles with other inflations share
            it); default: a new one.
        static: the map's static obstacles when they lead ``obstacles`` (the same tuple
            object for every space of the map, e.g. ``Scene.obstacles``): on large maps the
            new grid then lies over their shared grid (``distance_tiles.shared_tiles``) and
            holds only the tiles the other obstacles change. The same values either way.

    See the module docstring for the conservativeness guarantee and the error ``band``.
    """

    def __init__(
        self,
        shape: Shape,
        workspace: tuple[float, float],
        obstacles: Sequence[Obstacle] = (),
        inflation: float = 0.0,
        *,
        resolution: float = DEFAULT_RESOLUTION,
        sample_spacing: float | None = None,
        motion_margin: float = DEFAULT_MOTION_MARGIN,
        cover_cell: float = DEFAULT_COVER_CELL,
        grid: DistanceTiles | None = None,
        static: tuple[Obstacle, ...] = (),
    ) -> None:
        w, h = (float(v) for v in workspace)
        if not (w > 0 and h > 0 and math.isfinite(w) and math.isfinite(h)):
            raise ValueError(f"workspace must be two positive finite numbers, got {workspace!r}")
        if not math.isfinite(inflation):
            raise ValueError(f"inflation must be finite, got {inflation!r}")
        if not (resolution > 0 and math.isfinite(resolution)):
            raise ValueError(f"resolution must be finite and > 0, got {resolution!r}")
        spacing = resolution if sample_spacing is None else float(sample_spacing)
        if not (spacing > 0 and math.isfinite(spacing)):
            raise ValueError(f"sample_spacing must be finite and > 0, got {sample_spacing!r}")
        if not (motion_margin > 0 and math.isfinite(motion_margin)):
            raise ValueError(f"motion_margin must be finite and > 0, got {motion_margin!r}")
        if not (cover_cell > 0 and math.isfinite(cover_cell)):
            raise ValueError(f"cover_cell must be finite and > 0, got {cover_cell!r}")
        self.shape = shape
        self.workspace = (w, h)
        self.obstacles = tuple(obstacles)
        self.static = static
        self.inflation = float(inflation)
        self.resolution = float(resolution)
        self.sample_spacing = spacing
        self.motion_margin = float(motion_margin)
        self.cover_cell = float(cover_cell)
        #: width of the band (m) within which clearance may under-estimate the truth
        self.band = 4.0 * self.resolution / math.sqrt(2.0) + 0.5 * spacing

        dpts, drad, bpts, brad, poly = _footprint_disks(shape, self.inflation, spacing)
        if len(poly):
            cpts, crad = _cover_disks(poly, cover_cell)
            self._reach2 = float(np.max(np.sum(poly**2, axis=1))) + 1e-12
            rep_pts = [obstacle_geometry(o).representative_point() for o in self.obstacles]
            reps = np.array([[p.x, p.y] for p in rep_pts], dtype=float).reshape(-1, 2)
        else:  # a circle is its own single disk
            cpts, crad = np.zeros((0, 2)), np.zeros(0)
            self._reach2 = 0.0
            reps = np.zeros((0, 2))
        self._fp = tuple(
            np.ascontiguousarray(a, dtype=float)
            for a in (dpts, drad, bpts, brad, poly, reps, cpts, crad)
        )
        #: max distance of any footprint disk centre / vertex from the object origin
        self.reach = float(
            max(np.max(np.hypot(p[:, 0], p[:, 1]), initial=0.0) for p in (dpts, bpts, cpts))
        )
        #: smallest distance cap of a tiled grid that keeps every guarantee: beyond it a
        #: footprint disk still reads clearance above ``band + motion_margin``
        self.min_grid_cap = float(max(np.max(drad, initial=0.0), np.max(crad, initial=0.0))
                                  + self.band + self.motion_margin)
        if grid is None:
            grid = _new_grid(self.workspace, self.obstacles, self.resolution,
                             max(DEFAULT_GRID_CAP, self.min_grid_cap), static)
        elif (grid.workspace, grid.resolution) != (self.workspace, self.resolution):
            raise ValueError("grid must have this space's workspace and resolution")
        elif grid.capped and grid.cap < self.min_grid_cap:
            raise ValueError(f"grid cap {grid.cap:g} m is below this footprint's "
                             f"min_grid_cap {self.min_grid_cap:g} m")
        self.grid = grid

    @classmethod
    def from_scene(
        cls,
        scene: Scene,
        object_index: int,
        object_poses: ArrayLike | None = None,
        inflation: float = 0.0,
        **kwargs: float,
    ) -> ObjectSpace:
        """The space of ``scene.objects[object_index]``: the scene's obstacles plus every
        other object at ``object_poses`` (K, 3) (default: their start poses) are obstacles."""
        k = len(scene.objects)
        if not (isinstance(object_index, (int, np.integer)) and 0 <= object_index < k):
            raise ValueError(f"object_index must be in [0, {k}), got {object_index!r}")
        poses = scene.object_starts() if object_poses is None else np.asarray(object_poses, float)
        if poses.shape != (k, 3):
            raise ValueError(f"object_poses must have shape ({k}, 3), got {poses.shape}")
        others = [
            Obstacle(o.shape, (float(p[0]), float(p[1]), float(p[2])))
            for i, (o, p) in enumerate(zip(scene.objects, poses, strict=True))
            if i != object_index
        ]
        return cls(
            scene.objects[object_index].shape,
            scene.workspace,
            tuple(scene.obstacles) + tuple(others),
            inflation,
            static=scene.fixed_obstacles,
            **kwargs,
        )

    def with_inflation(self, inflation: float) -> ObjectSpace:
        """The same object, obstacles and query settings with another ``inflation`` (a new
        space sharing this one's distance grid)."""
        return ObjectSpace(
            self.shape,
            self.workspace,
            self.obstacles,
            inflation,
            resolution=self.resolution,
            sample_spacing=self.sample_spacing,
            motion_margin=self.motion_margin,
            cover_cell=self.cover_cell,
            grid=self.grid if not self.grid.capped or self.grid.cap >= self.min_grid_cap
            + abs(inflation - self.inflation) else None,
            static=self.static,
        )

    # ------------------------------------------------------------------ grid
    def prepare(self, points: ArrayLike, extra: float = 0.0) -> None:
        """Make the distance grid ready for footprints at the (..., 2) positions ``points``
        moved by up to ``extra`` metres: compiled callers (``kernel_args``) read -inf,
        i.e. "not free", where the grid was not prepared. The query methods of this
        class prepare what they read themselves."""
        self.grid.ensure(points, self.reach + extra + 2.0 * self.resolution)

    def prepare_point(self, x: float, y: float, extra: float = 0.0) -> None:
        """:meth:`prepare` for one position (x, y)."""
        self.grid.ensure_point(x, y, self.reach + extra + 2.0 * self.resolution)

    # --------------------------------------------------------------- queries
    def _clearance_flat(self, poses: np.ndarray, stop_below: float, quick: bool) -> np.ndarray:
        self.prepare(poses[:, :2])
        return batch_clearance(
            poses, self.grid.args, self.resolution, self.workspace[0], self.workspace[1],
            self._fp, self._reach2, stop_below, quick,
        )  # fmt: skip

    @staticmethod
    def _as_poses(poses: ArrayLike, name: str = "poses") -> np.ndarray:
        arr = np.asarray(poses, dtype=float)
        if arr.ndim == 0 or arr.shape[-1] != 3:
            raise ValueError(f"{name} must have shape (..., 3), got {arr.shape}")
        return arr

    def clearance(self, poses: ArrayLike) -> np.ndarray:
        """Lower bound of the distance from the inflated footprint to the nearest obstacle
        or the border, for (..., 3) poses; <= 0 when colliding or outside the workspace.
        At most ``self.band`` below the truth (obstacles) and exact for the border."""
        arr = self._as_poses(poses)
        flat = np.ascontiguousarray(arr.reshape(-1, 3))
        out = self._clearance_flat(flat, -np.inf, False)
        return out.reshape(arr.shape[:-1])

    def pose_free(self, poses: ArrayLike) -> np.ndarray:
        """(...) bool: the inflated footprint at each pose is inside the workspace and
        overlaps no obstacle (conservative: never True for a colliding pose)."""
        arr = self._as_poses(poses)
        flat = np.ascontiguousarray(arr.reshape(-1, 3))
        out = self._clearance_flat(flat, 0.0, True) > 0.0
        return out.reshape(arr.shape[:-1])

    def motions_free(self, starts: ArrayLike, ends: ArrayLike) -> np.ndarray:
        """(M,) bool: the swept motion from ``starts[m]`` to ``ends[m]`` along
        ``se2.interpolate`` (shortest rotation) stays free with ``motion_margin``."""
        a = self._as_poses(starts, "starts").reshape(-1, 3)
        b = self._as_poses(ends, "ends").reshape(-1, 3)
        if a.shape != b.shape:
            raise ValueError(
                f"starts and ends must have the same shape, got {a.shape} and {b.shape}"
            )
        if self.grid.capped and len(a):
            # positions along every motion, no farther apart than the prepared radius
            n = int(np.ceil(np.max(np.hypot(*(b[:, :2] - a[:, :2]).T)) / _PREPARE_STEP)) + 1
            u = np.linspace(0.0, 1.0, max(n, 2))[:, None, None]
            self.prepare((a[None, :, :2] + u * (b[None, :, :2] - a[None, :, :2])),
                         0.5 * _PREPARE_STEP)
        return batch_motions_free(
            np.ascontiguousarray(a), np.ascontiguousarray(b), self.motion_margin, self.reach,
            self.grid.args, self.resolution, self.workspace[0], self.workspace[1],
            self._fp, self._reach2,
        )  # fmt: skip

    @property
    def kernel_args(self) -> tuple:
        """``(margin, reach, sd, res, width, height, fp, reach2)``: the arguments that
        :func:`motion_free_kernel` takes after the two poses (``pose_free_kernel`` takes
        ``sd`` to ``reach2``), for compiled callers; call :meth:`prepare` for the places
        they will query first."""
        return (
            self.motion_margin, self.reach, self.grid.args, self.resolution,
            self.workspace[0], self.workspace[1], self._fp, self._reach2,
        )  # fmt: skip

    def motion_free(self, a: ArrayLike, b: ArrayLike) -> bool:
        """Whether the straight SE(2) motion from pose ``a`` to pose ``b`` is free."""
        return bool(self.motions_free(np.reshape(a, (1, 3)), np.reshape(b, (1, 3)))[0])

    def point_clearance(self, points: ArrayLike) -> np.ndarray:
        """Lower bound of the distance from (..., 2) world points to the nearest obstacle or
        the border (<= 0 inside obstacles / outside); useful for heuristics and drawing."""
        p = np.asarray(points, dtype=float)
        res = self.resolution
        self.grid.ensure(p, 2.0 * res)
        ny, nx = self.grid.shape
        ci = np.clip(np.floor(p[..., 0] / res).astype(int), 0, nx - 1)
        ri = np.clip(np.floor(p[..., 1] / res).astype(int), 0, ny - 1)
        border = np.minimum(
            np.minimum(p[..., 0], self.workspace[0] - p[..., 0]),
            np.minimum(p[..., 1], self.workspace[1] - p[..., 1]),
        )
        return np.minimum(self.grid.values(ri, ci), border)
