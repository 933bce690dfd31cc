"""Configuration space of a disk robot among static shapes: clearance field and exact checks.

A :class:`RobotSpace` answers "where may the centre of a disk robot of radius ``r`` be?"
in a workspace ``[0, W] x [0, H]`` whose border is a wall, with obstacles made of circles
and polygons (scene obstacles, objects at given poses, extra shapes).

Two layers of answers, both conservative (they never call a colliding placement free):

* **Grid** (fast, O(1) per point): ``field[j, i]`` is the *exact* signed distance from the
  grid node ``(i * h, j * h)`` to the nearest obstacle or border (negative inside an
  obstacle), capped at ``cap``. Since distance is 1-Lipschitz, the clearance of any point
  ``p`` is at least ``max_c field[c] - |p - c|`` over the four nodes ``c`` of its cell;
  :meth:`RobotSpace.is_free` tests that lower bound. Points whose exact clearance lies within
  ``h * sqrt(2) / 2`` (7.1 mm for ``h = 1 cm``) above the threshold may be reported not free
  (the documented band); nothing below the threshold is ever reported free.
* **Exact** (analytic, for continuous points and straight motions): point and segment
  clearances against circles, polygons and the border, computed in compiled code. Used for
  the final approach to goals that sit right next to an obstacle (contact points).

Static scene obstacles form a cached base layer; objects and extra shapes are laid over a
copy of it, so building a space for a new object pose costs well under a millisecond of
grid work plus the copy. Whole spaces are cached too (LRU keyed by :attr:`RobotSpace.key`,
bounded in entries and in bytes).

**Windows.** A space may hold only a rectangular *window* of the workspace grid (nodes
``origin`` to ``origin + shape - 1``): its node values are bit for bit those of the whole
grid (every obstacle within ``cap`` of a window node is filled in, wherever it lies), and
every grid answer is the whole grid's where it needs only window nodes. Outside the window
the space knows nothing and says so conservatively: ``is_free`` is False, ``clearance``
(grid) is -inf, the lower bound drops missing nodes (each node's term is a bound by
itself), BFS stays inside. Exact queries see every obstacle and do not depend on the
window. Memory and build time thus grow with the window, not with the map.

Conventions: metres; ``field`` is indexed ``[j, i]`` = ``[y, x]``; points are ``(..., 2)``
arrays of ``(x, y)``.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry.clearance_kernels import (
    bilinear,
    fill_field,
    lower_bound,
    points_clearance,
    segments_clearance,
)
from lamp.geometry.clearance_layers import (
    Derived,
    as_obstacles,
    base_layer,
    base_window,
    clear_base_layers,
    grid_nodes,
    lru_get,
    lru_put,
    static_token,
    window_nodes,
)
from lamp.geometry.geometry_set import GeometrySet, as_obstacle, obstacle_from_dict
from lamp.geometry.primitives import Circle, Obstacle
from lamp.geometry.waiting_spots import nearest_free_spot

if TYPE_CHECKING:  # the scene layer builds on geometry, not the other way round
    from lamp.scene.model import Scene

__all__ = [
    "RobotSpace",
    "GeometrySet",
    "obstacle_from_dict",
    "clear_caches",
]

DEFAULT_RESOLUTION = 0.01
DEFAULT_CAP = 0.3
_SPACE_CACHE_SIZE = 32
#: Byte bound of the space cache (fields and what is derived from them).
_SPACE_CACHE_BYTES = 128 * 2**20


# --------------------------------------------------------------------------------------
# Caches (whole spaces; the base layers live in lamp.geometry.clearance_layers)
# --------------------------------------------------------------------------------------

_SPACE_CACHE: OrderedDict[Any, RobotSpace] = OrderedDict()


def clear_caches(keep_base: bool = False) -> None:
    """Drop cached spaces (and, unless ``keep_base``, the static base layers)."""
    if not keep_base:
        clear_base_layers()
    _SPACE_CACHE.clear()


# --------------------------------------------------------------------------------------
# RobotSpace
# --------------------------------------------------------------------------------------


def _points(points: ArrayLike, name: str = "points") -> tuple[np.ndarray, tuple[int, ...]]:
    p = np.asarray(points, dtype=np.float64)
    if p.shape[-1:] != (2,):
        raise ValueError(f"{name} must have shape (..., 2), got {p.shape}")
    lead = p.shape[:-1]
    return np.ascontiguousarray(p.reshape(-1, 2)), lead


class RobotSpace:
    """Free space of the centre of a disk robot of radius ``radius`` (plus ``margin``).

    Parameters
    ----------
    workspace: (W, H) in metres; the border is a wall.
    obstacles: static obstacles (Obstacle, (Shape, pose) pairs or scene-file dicts); these
        form the cached base layer.
    radius: robot radius r.
    margin: extra distance kept from obstacles: a centre is free when its clearance is at
        least ``radius + margin`` (the *threshold*).
    overlay: further obstacles laid over the base layer (objects, extra shapes).
    resolution: grid spacing h (default 1 cm).
    cap: clearance values are exact up to ``cap`` and reported as ``cap`` beyond it.
    window: (x0, y0, x1, y1) metres: hold only the grid nodes of this rectangle (grown to
        whole nodes, clipped to the workspace; see the module doc). None: the whole grid.

    Use :meth:`from_scene` in planners: it caches whole spaces.
    """

    def __init__(
        self,
        workspace: tuple[float, float],
        obstacles: Iterable[Any] = (),
        radius: float = 0.05,
        margin: float = 0.0,
        overlay: Iterable[Any] = (),
        resolution: float = DEFAULT_RESOLUTION,
        cap: float = DEFAULT_CAP,
        window: Sequence[float] | None = None,
    ) -> None:
        W, H = (float(v) for v in workspace)
        if not (np.isfinite(W) and np.isfinite(H) and W > 0 and H > 0):
            raise ValueError(f"workspace must be two positive finite numbers, got {workspace!r}")
        if not (np.isfinite(radius) and radius > 0):
            raise ValueError(f"radius must be positive and finite, got {radius!r}")
        if not (np.isfinite(margin) and margin >= 0):
            raise ValueError(f"margin must be >= 0, got {margin!r}")
        if not (np.isfinite(resolution) and resolution > 0):
            raise ValueError(f"resolution must be positive, got {resolution!r}")
        self.workspace = (W, H)
        self.radius = float(radius)
        self.margin = float(margin)
        self.resolution = float(resolution)
        self.cap = float(max(cap, radius + margin + 2 * resolution))
        base_obs = as_obstacles(obstacles)
        over_obs = tuple(as_obstacle(o) for o in overlay)
        nodes = window_nodes(self.workspace, self.resolution, window)
        #: (i0, j0): the whole grid's index of node ``field[0, 0]``.
        self.origin: tuple[int, int] = (nodes[0], nodes[1])
        #: (NX, NY): nodes of the whole workspace grid.
        self.grid_nodes: tuple[int, int] = grid_nodes(self.workspace, self.resolution)
        self.window_nodes = nodes
        if over_obs:
            field, base_geo = base_window(self.workspace, base_obs, self.resolution,
                                          self.cap, nodes)
            over_geo = GeometrySet(over_obs)
            fill_field(field, self.resolution, self.cap, over_geo.circles, over_geo.verts,
                       over_geo.ptr, nodes[0], nodes[1])
            field.setflags(write=False)
            self.geometry = GeometrySet.concat(base_geo, over_geo)
        else:
            field, self.geometry = base_layer(self.workspace, base_obs, self.resolution,
                                              self.cap, nodes)
        self.field: np.ndarray = field
        self.base_obstacles = base_obs
        self.overlay_obstacles = over_obs
        self.key: Any = (
            self.workspace, base_obs, over_obs, self.radius, self.margin, self.resolution,
            self.cap, nodes,
        )
        # derived structures (e.g. planning lattices) cached by their users
        self.derived: dict[Any, Any] = Derived()

    # ---- construction -------------------------------------------------------------

    @classmethod
    def from_scene(
        cls,
        scene: Scene,
        object_poses: ArrayLike | None = None,
        extra_obstacles: Sequence[Any] = (),
        exclude_objects: Iterable[int] = (),
        robot_radius: float | None = None,
        margin: float = 0.0,
        resolution: float = DEFAULT_RESOLUTION,
        cap: float = DEFAULT_CAP,
        window: Sequence[float] | None = None,
    ) -> RobotSpace:
        """The space for ``scene``: its obstacles, its objects at ``object_poses`` (default:
        their start poses) except the indices in ``exclude_objects``, plus
        ``extra_obstacles`` (scene-file dicts, Obstacles or (Shape, pose) pairs), over the
        grid nodes of ``window`` (default: the whole workspace).

        Cached: the same arguments return the same (immutable) space object.
        """
        K = len(scene.objects)
        if object_poses is None:
            poses = scene.object_starts()
        else:
            poses = np.asarray(object_poses, dtype=np.float64)
            if poses.shape != (K, 3):
                raise ValueError(f"object_poses must have shape ({K}, 3), got {poses.shape}")
            if not np.all(np.isfinite(poses)):
                raise ValueError("object_poses must be finite")
        excl = {int(k) for k in exclude_objects}
        for k in excl:
            if not 0 <= k < K:
                raise ValueError(f"exclude_objects holds {k}, not an object index in [0, {K})")
        r = float(scene.robot_radius if robot_radius is None else robot_radius)
        fixed = scene.fixed_obstacles  # the map's own: the base; the rest laid over it
        overlay: list[Obstacle] = list(scene.obstacles[len(fixed):]) + [
            Obstacle(o.shape, tuple(float(v) for v in poses[k]))  # type: ignore[arg-type]
            for k, o in enumerate(scene.objects)
            if k not in excl
        ]
        overlay.extend(as_obstacle(o) for o in extra_obstacles)
        ws = tuple(float(v) for v in scene.workspace)
        key = (
            ws, static_token(fixed), tuple(overlay), r, float(margin),
            float(resolution),
            float(cap), window_nodes(ws, float(resolution), window),  # type: ignore[arg-type]
        )
        hit = lru_get(_SPACE_CACHE, key)
        if hit is not None:
            return hit
        space = cls(scene.workspace, fixed, r, margin, overlay, resolution, cap, window)
        lru_put(_SPACE_CACHE, key, space, _SPACE_CACHE_SIZE, _SPACE_CACHE_BYTES,
                 lambda sp: sp.nbytes)
        return space

    def with_obstacle(self, obstacle: Obstacle, at: int) -> RobotSpace:
        """This space with ``obstacle`` laid over it as overlay obstacle ``at``: the space
        ``RobotSpace(workspace, base, radius, margin, overlay[:at] + (obstacle,) +
        overlay[at:], resolution, cap, window)`` is, field value for value, geometry array
        for array and with its key (``tests/test_robot_space_layers.py``), built from a
        copy of this field (a node's value is the least over the obstacles, whatever their
        order) instead of the static tiles and every overlay obstacle again."""
        over = self.overlay_obstacles
        if not 0 <= at <= len(over):
            raise ValueError(f"at must be in [0, {len(over)}], got {at!r}")
        out = object.__new__(RobotSpace)
        out.__dict__.update(self.__dict__)
        own = GeometrySet((obstacle,))
        field = self.field.copy()
        fill_field(field, self.resolution, self.cap, own.circles, own.verts, own.ptr,
                   *self.origin)
        field.setflags(write=False)
        out.field = field
        after = sum(isinstance(o.shape, Circle) for o in over[at:])  # circles after it
        out.geometry = self.geometry.inserted(
            own, len(self.geometry.circles) - after,
            self.geometry.n_polygons - (len(over) - at - after))
        out.overlay_obstacles = over[:at] + (obstacle,) + over[at:]
        out.key = self.key[:2] + (out.overlay_obstacles,) + self.key[3:]
        out.derived = Derived()
        return out

    # ---- properties ---------------------------------------------------------------

    @property
    def threshold(self) -> float:
        """Clearance a centre needs to be free: ``radius + margin``."""
        return self.radius + self.margin

    @property
    def shape(self) -> tuple[int, int]:
        """Shape ``(ny, nx)`` of ``field``; its node (j, i) sits at ``((i0 + i) * h,
        (j0 + j) * h)`` with ``(i0, j0) = origin`` (0, 0 for a whole-workspace space)."""
        return self.field.shape  # type: ignore[return-value]

    @property
    def covers_workspace(self) -> bool:
        """Whether the field holds the whole workspace grid (no window)."""
        NX, NY = self.grid_nodes
        return self.window_nodes == (0, 0, NX - 1, NY - 1)

    @property
    def window(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1): the rectangle (metres) spanned by the field's nodes."""
        h = self.resolution
        i0, j0, i1, j1 = self.window_nodes
        return (i0 * h, j0 * h, i1 * h, j1 * h)

    @property
    def nbytes(self) -> int:
        """Bytes held by the field and the structures derived from it (lattices...)."""
        own = self.field.nbytes if self.overlay_obstacles else 0  # else the base cache's
        return own + self.derived.nbytes  # type: ignore[attr-defined]

    def node_xy(self, i: ArrayLike, j: ArrayLike) -> np.ndarray:
        """World coordinates of field nodes (i, j) (indices into ``field``) as (..., 2)."""
        i = np.asarray(i) + self.origin[0]
        j = np.asarray(j) + self.origin[1]
        return np.stack([i * self.resolution, j * self.resolution], axis=-1).astype(float)

    @property
    def free_grid(self) -> np.ndarray:
        """Boolean (ny, nx): grid nodes whose exact clearance is >= threshold."""
        g = self.derived.get("free_grid")
        if g is None:
            g = self.field >= self.threshold
            g.setflags(write=False)
            self.derived["free_grid"] = g
        return g

    def components(self, points: ArrayLike, snap: float = 0.02) -> np.ndarray:
        """Id of the connected free region each point lies in: the region (8-connected free
        grid nodes, labelled once per space) of the nearest free node within ``snap`` (m)
        of the point, or 0 when there is none (outside the window, deep in an obstacle).

        Two points with the same nonzero id are joined by free grid nodes, each within a
        diagonal cell of the next; points with different ids are not (inside this window:
        a path around through the rest of the map is not seen). A point touching an
        obstacle (a robot on its contact) takes the region it touches from."""
        from scipy import ndimage

        labels = self.derived.get("components")
        if labels is None:
            labels, _ = ndimage.label(self.free_grid, structure=np.ones((3, 3), dtype=bool))
            labels.setflags(write=False)
            self.derived["components"] = labels
        pts, shape = _points(points)
        h = self.resolution
        s = max(1, int(math.ceil(snap / h)))
        ny, nx = labels.shape
        out = np.zeros(len(pts), dtype=np.int64)
        for k, (x, y) in enumerate(pts):
            i = int(round(x / h)) - self.origin[0]
            j = int(round(y / h)) - self.origin[1]
            i0, i1, j0, j1 = max(0, i - s), min(nx, i + s + 1), max(0, j - s), min(ny, j + s + 1)
            if i0 >= i1 or j0 >= j1:
                continue
            block = labels[j0:j1, i0:i1]
            jj, ii = np.nonzero(block)
            if len(jj) == 0:
                continue
            d = (ii + i0 - (x / h - self.origin[0])) ** 2 + (jj + j0 - (y / h - self.origin[1])) ** 2
            best = int(np.argmin(d))
            if d[best] <= (snap / h) ** 2 + 1e-9:
                out[k] = int(block[jj[best], ii[best]])
        return out.reshape(shape)

    # ---- point queries ------------------------------------------------------------

    def clearance(self, points: ArrayLike, exact: bool = False) -> np.ndarray:
        """Distance from each centre to the nearest obstacle or border (negative inside).

        ``exact=False``: bilinear interpolation of the grid (error below ~h, values capped
        at ``cap``; -inf outside the workspace or the window). ``exact=True``: analytic,
        uncapped.
        """
        p, lead = _points(points)
        if exact:
            W, H = self.workspace
            g = self.geometry
            out = points_clearance(p, g.circles, g.verts, g.ptr, W, H)
        else:
            out = bilinear(p, self.field, self.resolution, *self.origin, *self.grid_nodes)
        return out.reshape(lead)

    def clearance_lower(self, points: ArrayLike) -> np.ndarray:
        """A lower bound on the clearance from the grid (1-Lipschitz bound, O(1) per point)."""
        p, lead = _points(points)
        return lower_bound(p, self.field, self.resolution, *self.origin,
                           *self.grid_nodes).reshape(lead)

    def is_free(self, points: ArrayLike, exact: bool = False) -> np.ndarray:
        """Whether a robot centred at each point is collision-free (clearance >= threshold).

        ``exact=False`` is conservative: never True for a colliding point; may be False
        for points with exact clearance in ``[threshold, threshold + h*sqrt(2)/2)``.
        """
        if exact:
            return self.clearance(points, exact=True) >= self.threshold
        return self.clearance_lower(points) >= self.threshold

    # ---- motion queries -----------------------------------------------------------

    def segment_clearance(self, a: ArrayLike, b: ArrayLike) -> np.ndarray:
        """Exact minimum clearance along straight segments a -> b ((..., 2) each).

        Positive values are exact; a value <= 0 means the segment touches or enters an
        obstacle or crosses the border."""
        pa, lead = _points(a, "a")
        pb, lead_b = _points(b, "b")
        if lead != lead_b:
            pa, pb = (np.ascontiguousarray(x.reshape(-1, 2)) for x in np.broadcast_arrays(
                np.asarray(a, float), np.asarray(b, float)))
            lead = np.broadcast_shapes(lead, lead_b)
        W, H = self.workspace
        g = self.geometry
        return segments_clearance(pa, pb, g.circles, g.verts, g.ptr, W, H).reshape(lead)

    def segment_free(self, a: ArrayLike, b: ArrayLike, threshold: float | None = None) -> np.ndarray:
        """Whether the whole straight motion a -> b keeps clearance >= threshold (exact)."""
        thr = self.threshold if threshold is None else float(threshold)
        return self.segment_clearance(a, b) >= thr

    def path_free(self, path: ArrayLike, threshold: float | None = None) -> bool:
        """Whether a polyline (T, 2) keeps clearance >= threshold along all its segments."""
        p, _ = _points(path, "path")
        if len(p) == 1:
            return bool(self.is_free(p, exact=True)[0]) if threshold is None else bool(
                self.clearance(p, exact=True)[0] >= threshold)
        return bool(np.all(self.segment_free(p[:-1], p[1:], threshold)))

    # ---- waiting spots ------------------------------------------------------------

    def nearest_free(
        self,
        point: ArrayLike,
        avoid: np.ndarray | Sequence[Sequence[float]] | None = None,
        min_clearance: float | None = None,
        through_free: bool = True,
        accept: Callable[[np.ndarray], np.ndarray] | None = None,
        max_distance: float | None = None,
    ) -> np.ndarray | None:
        """A collision-free centre close to ``point``, found by breadth-first search over
        the grid from ``point`` (LAMP paper, footnote to ``Reassign`` in Alg. 1 line 22: waiting locations
        by BFS from the robot's current position until a collision-free configuration is
        found).

        avoid: disks ``(K, 3)`` = (x, y, radius) the centre must stay strictly outside of,
            or a boolean grid mask (shape :attr:`shape`) of nodes to avoid.
        min_clearance: clearance the spot needs (default: threshold).
        through_free: search only through free nodes (spots reachable from ``point``);
            when ``point`` itself is not free the search starts through all nodes.
        accept: optional predicate ``(K, 2) points -> (K,) bool`` a spot must satisfy
            (e.g. "clear of the push paths"); called on batches of candidate nodes.
        max_distance: give up beyond this many metres (default: the whole workspace).
        Returns the (2,) spot, exactly a grid node: among the valid nodes met by the BFS,
        the one closest to ``point`` in Euclidean distance; None when there is none. A
        windowed space searches its window only (from the window node nearest ``point``).
        """
        return nearest_free_spot(self, point, avoid, min_clearance, through_free, accept,
                                 max_distance)

    def __repr__(self) -> str:
        W, H = self.workspace
        return (
            f"RobotSpace({W:g} x {H:g} m, r={self.radius:g}, margin={self.margin:g}, "
            f"{len(self.base_obstacles)}+{len(self.overlay_obstacles)} obstacles, "
            f"grid {self.shape[1]}x{self.shape[0]} @ {self.resolution:g} m"
            + ("" if self.covers_workspace else f" from node {self.origin}") + ")"
        )
