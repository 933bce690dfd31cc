"""Route and reachability checks for benchmark scenes.

For one object of a scene (the others standing still as obstacles, as the scene format
prescribes) these checks answer:

* **Does the object fit along an obstacle-free route from start to goal?**
  ``find_route`` runs A* over an SE(2) lattice (``resolution`` m, ``n_headings`` headings
  over the shape's symmetry period: pi for rectangles, none for circles), keeping a
  required clearance ``tau`` between the object and every obstacle, the other objects
  and the border. Clearances are exact (``lamp.suites._kernels``) and every lattice move
  is certified by bisection with a Lipschitz bound, so a returned route is free with
  clearance >= ``tau`` everywhere, not only at its waypoints. The route is then
  shortcut (certified straight SE(2) motions) and its length (path of the object's
  centre) and minimal clearance (sampled every ``SAMPLE_STEP``) are reported.
* **Is there room for robots along the way?** The same search with
  ``tau = ROBOT_ROOM`` (a robot diameter plus 1 cm): along such a route a robot fits
  between the object and any obstacle, so pushers can get behind and beside it. A scene
  has a *too-tight shortest route* (the LAMP paper's Fig. 1 situation) when the route
  with ``tau = FREE_CLEARANCE`` is markedly shorter than the robot-room route
  (``tight_shortest_route``).
* **Can the robots reach the object?** ``robot_reach`` rasterises the robots'
  configuration space (exact point clearances on a grid) and labels its connected
  components; it reports whether each robot's component contains cells of the contact
  ring around the object and which fraction of that ring the robots can reach.

``verify_route`` re-checks a route independently with ``lamp.geometry.object_space``
(a conservative distance-grid checker written separately), so the two implementations
test each other.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from numpy.typing import ArrayLike
from scipy import ndimage

from lamp.geometry.shapes import local_outline, obstacle_geometry
from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, Shape
from lamp.suites import _kernels as K

#: clearance (m) kept by the "obstacle-free" route: small, but large enough that the
#: conservative ObjectSpace checker (error band about 1 cm) can confirm the route.
FREE_CLEARANCE = 0.02
#: clearance (m) kept by the "robot-room" route: a robot diameter (2 x 0.05 m) plus 1 cm.
ROBOT_ROOM = 0.11
#: clearance ladder for ``route_profile`` (lengths of the shortest route keeping each).
CLEARANCE_LADDER = (0.02, 0.05, 0.08, 0.11)
#: default lattice resolution (m) and headings per symmetry period.
RESOLUTION = 0.025
N_HEADINGS = 16
#: cost of turning, in metres per radian, so the search prefers not to spin for nothing.
ROT_WEIGHT = 0.1
#: route sampling step (m of point displacement) when measuring its minimal clearance.
SAMPLE_STEP = 0.005
#: bisection depth for motion certification (2^-12 of a lattice step is far below 1 mm).
MAX_DEPTH = 12
#: a shortest route is "too tight" when the robot-room route is longer by both of these.
TIGHT_MIN_EXTRA = 0.3  # m
TIGHT_MIN_RATIO = 1.15


# --------------------------------------------------------------------------- world
@dataclass(frozen=True)
class World:
    """Static obstacles as convex pieces for the kernels (see ``_kernels`` docstring)."""

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


# --------------------------------------------------------------------------- routes
@dataclass(frozen=True)
class Route:
    """A certified object route: straight SE(2) motions between ``poses`` (theta unwrapped)."""

    poses: np.ndarray
    tau: float
    length: float
    min_clearance: float

    def to_dict(self, decimals: int = 4) -> dict[str, Any]:
        return {
            "required_clearance": self.tau,
            "length": round(float(self.length), 4),
            "min_clearance": round(float(self.min_clearance), 4),
            "poses": np.round(self.poses, decimals).tolist(),
        }


def _path_length(poses: np.ndarray) -> float:
    return float(np.sum(np.hypot(np.diff(poses[:, 0]), np.diff(poses[:, 1]))))


def _unwrap_to(theta: float, ref: float, period: float) -> float:
    """theta + m * period closest to ref."""
    return theta + period * round((ref - theta) / period)


class RouteFinder:
    """SE(2)-lattice route search for one object shape in one world (clearances cached
    across searches with different required clearances)."""

    def __init__(
        self,
        shape: Shape,
        world: World,
        resolution: float = RESOLUTION,
        n_headings: int = N_HEADINGS,
    ) -> None:
        if not (resolution > 0 and math.isfinite(resolution)):
            raise ValueError(f"resolution must be finite and > 0, got {resolution!r}")
        if not (isinstance(n_headings, int) and n_headings >= 1):
            raise ValueError(f"n_headings must be a positive int, got {n_headings!r}")
        self.shape = shape
        self.world = world
        self.fp = footprint_of(shape)
        self.h = float(resolution)
        self.nx = int(math.floor(world.width / self.h - 1e-9))
        self.ny = int(math.floor(world.height / self.h - 1e-9))
        self.nh = 1 if self.fp.period == 0.0 else int(n_headings)
        self.dth = 0.0 if self.nh == 1 else self.fp.period / self.nh
        self.cache = np.full(self.nx * self.ny * self.nh, np.nan)

    # lattice helpers ---------------------------------------------------------
    def _node_pose(self, node: int) -> np.ndarray:
        i = node % self.nx
        j = (node // self.nx) % self.ny
        k = node // (self.nx * self.ny)
        return np.array([(i + 1) * self.h, (j + 1) * self.h, k * self.dth])

    def _clear(self, pose: np.ndarray) -> float:
        return float(
            K.batch_clearance(
                np.ascontiguousarray(pose.reshape(1, 3)), *self.fp.args, *self.world.args
            )[0]
        )

    def _connectors(self, pose: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
        """Lattice nodes next to ``pose`` reachable by a certified straight motion, with the
        motion cost (translation + rotation weight)."""
        c0 = self._clear(pose)
        nodes, costs = [], []
        if c0 < tau:
            return np.zeros(0, np.int64), np.zeros(0)
        fi = pose[0] / self.h - 1.0
        fj = pose[1] / self.h - 1.0
        if self.nh == 1:
            ks: list[int] = [0]
        else:
            fk = (pose[2] % self.fp.period) / self.dth
            ks = [int(math.floor(fk)) % self.nh, int(math.ceil(fk)) % self.nh]
        for i in (int(math.floor(fi)), int(math.floor(fi)) + 1):
            for j in (int(math.floor(fj)), int(math.floor(fj)) + 1):
                if not (0 <= i < self.nx and 0 <= j < self.ny):
                    continue
                for k in ks:
                    node = (k * self.ny + j) * self.nx + i
                    q = self._node_pose(node)
                    if self.nh > 1:
                        q[2] = _unwrap_to(q[2], pose[2], self.fp.period)
                    cq = self._clear(q)
                    if cq < tau:
                        continue
                    if not K.motion_ok(
                        pose, q, c0, cq, tau, MAX_DEPTH, *self.fp.args, *self.world.args
                    ):
                        continue
                    nodes.append(node)
                    costs.append(
                        math.hypot(q[0] - pose[0], q[1] - pose[1])
                        + ROT_WEIGHT * abs(q[2] - pose[2])
                    )
        return np.array(nodes, dtype=np.int64), np.array(costs, dtype=float)

    # search -------------------------------------------------------------------
    def find(self, start: ArrayLike, goal: ArrayLike, tau: float) -> Route | None:
        """Shortest certified route keeping clearance >= ``tau``, or None."""
        start = np.asarray(start, dtype=float)
        goal = np.asarray(goal, dtype=float)
        if not (tau >= 0 and math.isfinite(tau)):
            raise ValueError(f"tau must be finite and >= 0, got {tau!r}")
        src, src_c = self._connectors(start, tau)
        dst, dst_c = self._connectors(goal, tau)
        if len(src) == 0 or len(dst) == 0:
            return None
        parent, end, _total = K.lattice_astar(
            self.nx, self.ny, self.nh, self.h, self.dth, float(tau), ROT_WEIGHT,
            src, src_c, dst, dst_c, float(goal[0]), float(goal[1]), self.cache, MAX_DEPTH,
            *self.fp.args, *self.world.args,
        )  # fmt: skip
        if end < 0:
            return None
        chain = []
        u = int(end)
        while u >= 0:
            chain.append(u)
            u = int(parent[u])
        chain.reverse()
        poses = [start]
        for node in chain:
            q = self._node_pose(node)
            if self.nh > 1:
                q[2] = _unwrap_to(q[2], poses[-1][2], self.fp.period)
            poses.append(q)
        g = goal.copy()
        if self.nh > 1:
            # the goal footprint is the same for theta + m * period: end the route with the
            # equivalent heading closest to the last lattice heading
            g[2] = _unwrap_to(g[2], poses[-1][2], self.fp.period)
        else:
            g[2] = poses[-1][2]
        poses.append(g)
        arr = np.ascontiguousarray(np.array(poses))
        clear = K.batch_clearance(arr, *self.fp.args, *self.world.args)
        keep = K.shortcut(
            arr, clear, float(tau), 0.5 * math.pi, MAX_DEPTH, *self.fp.args, *self.world.args
        )
        arr = np.ascontiguousarray(arr[keep])
        dense = np.ascontiguousarray(_densify(arr, SAMPLE_STEP, self.fp.reach))
        min_c = float(np.min(K.batch_clearance(dense, *self.fp.args, *self.world.args)))
        return Route(arr, float(tau), _path_length(arr), min_c)


def find_route(
    scene: Scene,
    object_index: int = 0,
    tau: float = FREE_CLEARANCE,
    object_poses: ArrayLike | None = None,
    resolution: float = RESOLUTION,
    n_headings: int = N_HEADINGS,
) -> Route | None:
    """Shortest certified route of ``scene.objects[object_index]`` from its start to its
    goal keeping clearance >= ``tau``; the other objects stand at ``object_poses``
    (default: their starts). None when the lattice search finds no route."""
    obj = scene.objects[object_index]
    finder = RouteFinder(
        obj.shape, object_world(scene, object_index, object_poses), resolution, n_headings
    )
    return finder.find(obj.start, obj.goal, tau)


def verify_route(
    scene: Scene,
    object_index: int,
    poses: ArrayLike,
    tau: float,
    object_poses: ArrayLike | None = None,
) -> tuple[bool, float]:
    """Independent check of a route with ``lamp.geometry.object_space.ObjectSpace``.

    Returns (every straight motion between consecutive poses is free and every checked
    pose keeps ObjectSpace clearance >= tau - band, ObjectSpace's minimal clearance along
    the densely sampled route). ObjectSpace under-estimates clearance by at most its
    ``band`` (about 1 cm), so a route certified with clearance >= tau passes.
    """
    from lamp.geometry.object_space import ObjectSpace

    arr = np.asarray(poses, dtype=float)
    space = ObjectSpace.from_scene(scene, object_index, object_poses=object_poses, inflation=0.0)
    ok = bool(np.all(space.motions_free(arr[:-1], arr[1:])))
    dense = _densify(arr, SAMPLE_STEP, footprint_of(scene.objects[object_index].shape).reach)
    c = space.clearance(dense)
    cmin = float(np.min(c))
    return ok and cmin >= tau - space.band - 1e-9, cmin


def _densify(poses: np.ndarray, step: float, reach: float) -> np.ndarray:
    out = [poses[:1]]
    for a, b in zip(poses[:-1], poses[1:], strict=True):
        delta = math.hypot(b[0] - a[0], b[1] - a[1]) + reach * abs(b[2] - a[2])
        n = max(1, math.ceil(delta / step))
        t = (np.arange(1, n + 1) / n)[:, None]
        out.append(a + t * (b - a))
    return np.concatenate(out)


# --------------------------------------------------------------------------- robots
@dataclass(frozen=True)
class RobotReach:
    """Whether the robots can get to the object (see ``robot_reach``)."""

    reaches: tuple[bool, ...]
    ring_fraction: float
    robot_clearance: tuple[float, ...]

    @property
    def all_reach(self) -> bool:
        return all(self.reaches)

    def to_dict(self) -> dict[str, Any]:
        return {
            "all_reach": self.all_reach,
            "reaches": list(self.reaches),
            "ring_reachable_fraction": round(self.ring_fraction, 3),
        }


def robot_free_cells(
    scene: Scene, poses: np.ndarray, h: float
) -> tuple[World, np.ndarray, np.ndarray, np.ndarray]:
    """The grid on which robot reachability is judged (``robot_reach`` and the IROS
    scene's checks): cells of side ``h`` covering the workspace, free when the exact
    clearance of their centre from the obstacles, every object (at ``poses``) and the
    border is >= robot radius + h / 2.

    Returns (world, xs (nx,), ys (ny,) cell-centre coordinates, free (ny, nx) bool).
    """
    world = build_world(scene.workspace, object_obstacles(scene, None, poses))
    nx = int(math.floor(scene.workspace[0] / h))
    ny = int(math.floor(scene.workspace[1] / h))
    xs = (np.arange(nx) + 0.5) * h
    ys = (np.arange(ny) + 0.5) * h
    gx, gy = np.meshgrid(xs, ys)
    r = float(scene.robot_radius)
    free = point_clearance(world, np.stack([gx, gy], axis=-1)) >= r + 0.5 * h
    return world, xs, ys, free


def robot_reach(
    scene: Scene,
    object_index: int = 0,
    object_poses: ArrayLike | None = None,
    robot_positions: ArrayLike | None = None,
    resolution: float = 0.02,
    ring_width: float = 0.04,
) -> RobotReach:
    """Can disk robots (radius ``scene.robot_radius``) starting at ``robot_positions``
    (default: the scene's robot starts) reach the contact ring of the object?

    Grid cells of side ``resolution`` whose centre has exact clearance >= r + resolution/2
    from every obstacle, object (all of them, at ``object_poses``) and the border are free;
    4-neighbour moves between free cells keep clearance >= r (the midpoint bound), so
    connected components (``scipy.ndimage.label``) are exact reachability classes of the
    grid. The contact ring is the free cells within ``ring_width`` of the robot's contact
    distance from the object; a robot reaches the object when its component contains a
    ring cell. ``ring_fraction`` is the fraction of ring cells (free or not) that some robot
    reaches: near 1 when the robots can get all around the object.
    """
    r = float(scene.robot_radius)
    h = float(resolution)
    poses = scene.object_starts() if object_poses is None else np.asarray(object_poses, float)
    robots = (
        scene.robot_starts_array if robot_positions is None else np.asarray(robot_positions, float)
    )
    world, xs, ys, free = robot_free_cells(scene, poses, h)
    ny, nx = free.shape
    obj = scene.objects[object_index]
    own = build_world(
        scene.workspace, [Obstacle(obj.shape, tuple(float(v) for v in poses[object_index]))]
    )
    gx, gy = np.meshgrid(xs, ys)
    pts = np.stack([gx.ravel(), gy.ravel()], axis=1)
    # distance to the object itself only
    d_obj = K.point_clearance(
        np.ascontiguousarray(pts), own.circ, own.pv, own.pn, own.pb, own.width, own.height, False
    ).reshape(ny, nx)
    ring = (d_obj >= r + 0.5 * h) & (d_obj <= r + 0.5 * h + ring_width)
    labels, _ = ndimage.label(free)
    reaches = []
    robot_c = point_clearance(world, robots)
    comps = set()
    for (px, py), c in zip(robots, robot_c, strict=True):
        lab = 0
        i0 = int(math.floor(px / h - 0.5))
        j0 = int(math.floor(py / h - 0.5))
        best = np.inf
        for i in (i0, i0 + 1):
            for j in (j0, j0 + 1):
                if 0 <= i < nx and 0 <= j < ny and free[j, i]:
                    d = math.hypot(xs[i] - px, ys[j] - py)
                    # straight move start -> cell centre keeps clearance >= r by the bound
                    if min(c, r + 0.5 * h) - 0.5 * d >= r and d < best:
                        best = d
                        lab = int(labels[j, i])
        if lab:
            comps.add(lab)
        reaches.append(bool(lab) and bool(np.any(ring & (labels == lab))))
    reach_mask = np.isin(labels, sorted(comps)) & ring if comps else np.zeros_like(ring)
    fraction = float(reach_mask.sum() / max(1, ring.sum()))
    return RobotReach(tuple(reaches), fraction, tuple(float(v) for v in robot_c))


# --------------------------------------------------------------------------- scene report
@dataclass
class ObjectReport:
    """Check results for one object of a scene (its manifest entry)."""

    index: int
    start_clearance: float
    goal_clearance: float
    free_route: Route | None
    robot_route: Route | None
    profile: dict[float, float | None] = field(default_factory=dict)
    reach: RobotReach | None = None

    @property
    def tight_shortest_route(self) -> bool:
        return is_tight(self.free_route, self.robot_route)

    @property
    def ok(self) -> bool:
        return (
            self.free_route is not None
            and self.robot_route is not None
            and self.reach is not None
            and self.reach.all_reach
        )

    def to_dict(self) -> dict[str, Any]:
        lf = None if self.free_route is None else self.free_route.length
        lr = None if self.robot_route is None else self.robot_route.length
        return {
            "index": self.index,
            "start_clearance": round(self.start_clearance, 4),
            "goal_clearance": round(self.goal_clearance, 4),
            "free_route": None if self.free_route is None else self.free_route.to_dict(),
            "robot_route": None if self.robot_route is None else self.robot_route.to_dict(),
            "length_ratio": None if not (lf and lr) else round(lr / lf, 4),
            "tight_shortest_route": self.tight_shortest_route,
            "route_length_by_clearance": {
                f"{t:.2f}": (None if v is None else round(v, 4)) for t, v in self.profile.items()
            },
            "robots": None if self.reach is None else self.reach.to_dict(),
        }


def is_tight(free: Route | None, roomy: Route | None) -> bool:
    """The Fig. 1 situation: the shortest route is markedly shorter than the robot-room
    route (longer by >= TIGHT_MIN_EXTRA m and by a factor >= TIGHT_MIN_RATIO), or only the
    too-tight route exists."""
    if free is None:
        return False
    if roomy is None:
        return True
    return (
        roomy.length - free.length >= TIGHT_MIN_EXTRA
        and roomy.length >= TIGHT_MIN_RATIO * free.length
    )


def check_object(
    scene: Scene,
    object_index: int = 0,
    object_poses: ArrayLike | None = None,
    robot_positions: ArrayLike | None = None,
    ladder: Sequence[float] = CLEARANCE_LADDER,
    finder: RouteFinder | None = None,
    known: dict[float, Route | None] | None = None,
) -> ObjectReport:
    """All checks for one object with the others at ``object_poses`` (default: starts).

    ``finder`` (a RouteFinder for this object and world) and ``known`` (routes already
    found, by required clearance) let a caller reuse work; results are the same.
    """
    obj = scene.objects[object_index]
    if finder is None:
        finder = RouteFinder(obj.shape, object_world(scene, object_index, object_poses))
    known = dict(known or {})

    def route(t: float) -> Route | None:
        for k, v in known.items():
            if math.isclose(k, t):
                return v
        known[t] = finder.find(obj.start, obj.goal, t)
        return known[t]

    c_start, c_goal = clearance(obj.shape, finder.world, np.array([obj.start, obj.goal]))
    free = route(FREE_CLEARANCE)
    roomy = route(ROBOT_ROOM) if free is not None else None
    profile: dict[float, float | None] = {}
    for t in ladder:
        rt = route(t) if free is not None else None
        profile[t] = None if rt is None else rt.length
    poses = scene.object_starts() if object_poses is None else np.asarray(object_poses, float)
    poses = poses.copy()
    poses[object_index] = obj.start
    reach = robot_reach(scene, object_index, poses, robot_positions)
    return ObjectReport(object_index, float(c_start), float(c_goal), free, roomy, profile, reach)
