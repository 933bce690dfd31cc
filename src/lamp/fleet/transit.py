"""Transit: a sub-team that stands far from its object drives to it before it pushes.

Verify plans the robots' approach in a window around the object and the robots. A team
drawn from across the map (robots freed by an object placed 35 m away) makes that window
the strip between them: every robot space and every Gspi lattice is the strip's size,
and when the way round leaves the strip (a wall in between) no approach exists inside it
and every Verify fails (fleet-20: one object's 337 Verify calls in 300 s, none passed).

Before its closed loop starts, a team with robots whose route to the object is longer
than ``TRANSIT_RADIUS`` therefore drives there in hops:

1. **Route.** Shortest routes for a robot's disk grown by ``TRANSIT_MARGIN`` to the
   object's staging area (the free cells within ``STAGING`` of the object's footprint's
   bounding circle), on a ``TRANSIT_CELL`` grid of the world as the team plans in it
   (obstacles, every object where it stands, every other robot as a disk): one
   multi-source Dijkstra (SciPy) over the 8-connected free cells, no corner cutting.
   The free cells come from Shapely (the workspace shrunk by the grown radius minus the
   obstacles grown by it), so a route is a guide, not a proof: Gspi checks every motion.
2. **Hop.** Each far robot's waypoint is ``HOP_LENGTH`` along its route (or its end); its
   goal is the free spot nearest the waypoint. A waypoint inside the claim of an object
   ranked above (``keep_out``: admission would hold the hop until that object has gone
   by) moves on along the route to the first point clear of every such claim, up to
   ``CROSS_REACH`` further, so the hop crosses the claim; failing that, back to the last
   clear point before it (at least ``MIN_HOP`` along the route). The others keep their
   place. Gspi plans the hop in the robot space over the route parts' bounding box grown by
   ``WINDOW_MARGIN``; robots standing far outside it hold still
   (``lamp.planners.bystanders``). A hop Gspi cannot plan is tried once at half the
   length; then transit ends and the loop starts from where the team stands.
3. **Run.** The hop is submitted as a segment of the object (its object stays where it
   is), admitted beside the other sub-teams' segments like any other; a declined hop
   (the world changed) is planned again. At most ``MAX_HOPS`` hops.

Deterministic: counts bound everything; Gspi's ``TRANSIT_TIME_LIMIT`` is an outer cap.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from lamp.fleet.view import FleetView
from lamp.geometry.robot_space import RobotSpace
from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.mrmp import plan_paths
from lamp.planners.bystanders import BYSTANDER_GAP, bystanders, route_movers, standing_on_goal
from lamp.planners.task import WINDOW_MARGIN, WINDOW_SNAP
from lamp.scene.model import Scene

__all__ = ["CLAIM_CLEARANCE", "CROSS_REACH", "HOP_LENGTH", "MIN_HOP", "TRANSIT_RADIUS",
           "Grid", "Routes", "clear_waypoint", "far_robots", "free_grid", "hop", "routes",
           "team_moves", "transit"]

#: A robot whose route to its object's staging area is longer than this (m) drives there
#: before its team pushes.
TRANSIT_RADIUS = 4.0
#: Route length (m) one hop covers.
HOP_LENGTH = 5.0
#: Grid cell (m) of the routes.
TRANSIT_CELL = 0.1
#: Clearance (m) beyond the robot radius the routes keep from everything.
TRANSIT_MARGIN = 0.05
#: The staging area: free cells within this (m) of the object's bounding circle.
STAGING = 1.0
#: Hops one transit may take (declined ones included).
MAX_HOPS = 40
#: Outer wall-clock cap (s) of one hop's Gspi call.
TRANSIT_TIME_LIMIT = 10.0
#: How far (m) from its waypoint a robot's goal may be.
SPOT_SEARCH = 1.0
#: How much further (m) than ``HOP_LENGTH`` a hop's waypoint may move along its route to
#: end clear of a higher-ranked object's claim (:func:`clear_waypoint`).
CROSS_REACH = HOP_LENGTH
#: The least route length (m) a hop shortened to end before such a claim still covers.
MIN_HOP = 0.5
#: Clearance (m) beyond the robot radius a moved waypoint keeps from such a claim: more
#: than the margin admission grows the robots' disks by (``regions.ROBOT_MARGIN``).
CLAIM_CLEARANCE = 0.05


@dataclass(frozen=True)
class Grid:
    """The free cells of a ``cell``-metre grid of a world for a robot's disk grown by
    ``TRANSIT_MARGIN`` (cell (i, j) centred at ((i + 0.5) * cell, (j + 0.5) * cell):
    ``X``, ``Y``; ``free`` (ny, nx)) and the graph of 8-connected free cells without corner
    cutting (edge lengths in metres). Cells are named by flat index ``j * nx + i``."""

    cell: float
    X: np.ndarray
    Y: np.ndarray
    free: np.ndarray
    graph: Any  # scipy.sparse CSR (ny * nx, ny * nx)

    @property
    def flat(self) -> np.ndarray:
        return np.arange(self.free.size).reshape(self.free.shape)

    def centres(self, idx: np.ndarray) -> np.ndarray:
        """(M, 2) centres of the cells ``idx`` (flat indices)."""
        idx = np.asarray(idx, np.int64)
        return np.c_[self.X.ravel()[idx], self.Y.ravel()[idx]]

    def walk(self, pred: np.ndarray, v: int) -> np.ndarray:
        """(M, 2) centres of the cells from ``v`` along ``pred`` (a Dijkstra predecessor
        array: the next cell, negative at the end)."""
        out = [int(v)]
        while pred[out[-1]] >= 0:
            out.append(int(pred[out[-1]]))
        return self.centres(np.asarray(out))

    def nearest_free_cell(self, xy: np.ndarray, reach: int = 3,
                          allowed: np.ndarray | None = None) -> int | None:
        """The free cell (flat index; also ``allowed``, a flat mask, when given) nearest
        ``xy`` within ``reach`` cells (a robot that touches an object stands inside the
        grid's margin), the lowest index among equals; or None."""
        ny, nx = self.free.shape
        ci, cj = (int(math.floor(v / self.cell)) for v in np.asarray(xy, float)[:2])
        j0, j1 = max(0, cj - reach), min(ny, cj + reach + 1)
        i0, i1 = max(0, ci - reach), min(nx, ci + reach + 1)
        if j0 >= j1 or i0 >= i1:
            return None
        sub = self.free[j0:j1, i0:i1]
        if allowed is not None:
            sub = sub & np.asarray(allowed).reshape(ny, nx)[j0:j1, i0:i1]
        if not sub.any():
            return None
        d = np.hypot(self.X[j0:j1, i0:i1] - xy[0], self.Y[j0:j1, i0:i1] - xy[1])
        d = np.where(sub, d, np.inf)
        j, i = np.unravel_index(int(np.argmin(d)), d.shape)
        return int((j0 + j) * nx + i0 + i)


@dataclass(frozen=True)
class Routes:
    """Shortest routes on ``grid`` from every free cell to the staging area: ``pred`` is
    the flat index of the next cell towards it (-9999 at the area or where none leads),
    ``dist`` the metres to it (inf: none)."""

    grid: Grid
    pred: np.ndarray  # (ny * nx,) int
    dist: np.ndarray  # (ny * nx,) float

    @property
    def cell(self) -> float:
        return self.grid.cell

    @property
    def shape(self) -> tuple[int, int]:
        return self.grid.free.shape

    @property
    def free(self) -> np.ndarray:
        return self.grid.free

    @cached_property
    def reachable(self) -> np.ndarray:
        """Flat mask of the cells a route leads from."""
        return np.isfinite(self.dist)

    def cell_of(self, xy: np.ndarray) -> int | None:
        """The free cell with a route nearest ``xy`` within two cells (flat index), or
        None."""
        return self.grid.nearest_free_cell(xy, 2, self.reachable)

    def length(self, xy: np.ndarray) -> float:
        """Metres from ``xy``'s cell (``cell_of``) to the staging area; inf when no route
        leads there."""
        v = self.cell_of(xy)
        return math.inf if v is None else float(self.dist[v])

    def path(self, xy: np.ndarray) -> np.ndarray | None:
        """(M, 2) cell centres from ``xy``'s cell to the staging area, or None when no
        route leads there."""
        v = self.cell_of(xy)
        return None if v is None else self.grid.walk(self.pred, v)


def free_grid(scene: Scene, object_poses: np.ndarray, cell: float = TRANSIT_CELL) -> Grid:
    """The :class:`Grid` of ``scene`` with its objects at ``object_poses`` (obstacles and
    objects grown by the robot radius + ``TRANSIT_MARGIN`` with Shapely)."""
    W, H = (float(v) for v in scene.workspace)
    grown = float(scene.robot_radius) + TRANSIT_MARGIN
    poses = np.asarray(object_poses, float).reshape(-1, 3)
    bodies = [obstacle_geometry(o) for o in scene.obstacles]
    bodies += [to_shapely(o.shape, q) for o, q in zip(scene.objects, poses, strict=True)]
    free_poly = shapely.box(0.0, 0.0, W, H).buffer(-grown, join_style="mitre")
    if bodies:
        free_poly = free_poly.difference(shapely.union_all(bodies).buffer(grown))
    shapely.prepare(free_poly)
    nx, ny = max(1, int(W / cell)), max(1, int(H / cell))
    X, Y = np.meshgrid((np.arange(nx) + 0.5) * cell, (np.arange(ny) + 0.5) * cell)
    free = shapely.contains_xy(free_poly, X.ravel(), Y.ravel()).reshape(ny, nx)
    flat = np.arange(ny * nx).reshape(ny, nx)
    us, vs, ws = [], [], []
    for dj, di in ((0, 1), (1, 0), (1, 1), (1, -1)):
        here = (slice(0, ny - dj), slice(max(0, -di), nx - max(0, di)))
        there = (slice(dj, ny), slice(max(0, di), nx - max(0, -di)))
        ok = free[here] & free[there]
        if dj and di:  # no corner cutting: both side cells free
            ok &= free[there[0], here[1]] & free[here[0], there[1]]
        us.append(flat[here][ok])
        vs.append(flat[there][ok])
        ws.append(np.full(int(ok.sum()), cell * math.hypot(di, dj)))
    graph = coo_matrix((np.concatenate(ws), (np.concatenate(us), np.concatenate(vs))),
                       shape=(ny * nx, ny * nx)).tocsr()
    return Grid(cell, X, Y, free, graph)


def routes(scene: Scene, k: int, object_poses: np.ndarray, cell: float = TRANSIT_CELL
           ) -> Routes:
    """The :class:`Routes` to object ``k``'s staging area in ``scene`` with its objects at
    ``object_poses``."""
    grid = free_grid(scene, object_poses, cell)
    free, size = grid.free, grid.free.size
    q = np.asarray(object_poses, float).reshape(-1, 3)[k]
    reach = float(scene.objects[k].shape.bounding_radius) + STAGING
    sources = grid.flat[free & (np.hypot(grid.X - q[0], grid.Y - q[1]) <= reach)]
    if len(sources) == 0:
        return Routes(grid, np.full(size, -9999), np.full(size, np.inf))
    dist, pred = dijkstra(grid.graph, directed=False, indices=sources, min_only=True,
                          return_predecessors=True)[:2]
    return Routes(grid, np.asarray(pred), np.asarray(dist))


def _window(points: np.ndarray, scene: Scene) -> tuple[float, float, float, float]:
    """The points' bounding box grown by ``WINDOW_MARGIN``, snapped outward to
    ``WINDOW_SNAP``, inside the map."""
    W, H = (float(v) for v in scene.workspace)
    lo = np.asarray(points, float).min(axis=0) - WINDOW_MARGIN
    hi = np.asarray(points, float).max(axis=0) + WINDOW_MARGIN
    return (max(0.0, WINDOW_SNAP * math.floor(lo[0] / WINDOW_SNAP)),
            max(0.0, WINDOW_SNAP * math.floor(lo[1] / WINDOW_SNAP)),
            min(W, WINDOW_SNAP * math.ceil(hi[0] / WINDOW_SNAP)),
            min(H, WINDOW_SNAP * math.ceil(hi[1] / WINDOW_SNAP)))


def clear_waypoint(route: np.ndarray, along: np.ndarray, n: int,
                   keep_out: Sequence[shapely.Geometry], clear: float) -> int:
    """The number of ``route`` points (``along``: their distances along it) a hop takes
    instead of ``n``: ``n`` when point ``n - 1`` lies farther than ``clear`` from every
    region of ``keep_out``; else the least count whose last point does, within
    ``CROSS_REACH`` beyond point ``n - 1``; else the greatest below ``n`` whose last point
    does and lies at least ``MIN_HOP`` along; else ``n``."""
    if not keep_out:
        return n
    stop = int(np.searchsorted(along, along[n - 1] + CROSS_REACH, side="right"))
    pts = shapely.points(route[:max(stop, n)])
    near = np.zeros(len(pts), bool)
    for region in keep_out:
        near |= shapely.dwithin(region, pts, clear)
    if not near[n - 1]:
        return n
    ahead = np.flatnonzero(~near[n:])
    if len(ahead):
        return n + int(ahead[0]) + 1
    back = np.flatnonzero(~near[:n - 1] & (along[:n - 1] >= MIN_HOP))
    return int(back[-1]) + 1 if len(back) else n


def hop(scene: Scene, k: int, object_poses: np.ndarray, positions: np.ndarray,
        far: np.ndarray, field: Routes, length: float = HOP_LENGTH, seed: int = 0,
        keep_out: Sequence[shapely.Geometry] = ()) -> Any:
    """Gspi's plan (``MRMPPlan``; ``paths`` (N, T, 2)) that takes the ``far`` robots of
    ``scene`` (at ``positions``) ``length`` metres along their routes (each waypoint
    moved clear of ``keep_out`` by :func:`clear_waypoint`), the others keeping their
    place, or None when a far robot has no route or no free goal spot."""
    pos = np.asarray(positions, float).reshape(-1, 2)
    goals = pos.copy()
    parts = [pos[far]]
    clear = float(scene.robot_radius) + CLAIM_CLEARANCE
    for i in np.flatnonzero(far):
        route = field.path(pos[i])
        if route is None:
            return None
        steps = np.hypot(*np.diff(np.vstack([pos[i], route]), axis=0).T)
        along = np.cumsum(steps)
        n = int(np.searchsorted(along, length, side="right"))
        n = clear_waypoint(route, along, min(max(n, 1), len(route)), keep_out, clear)
        goals[i] = route[n - 1]
        parts.append(route[:n])
    return team_moves(scene, k, object_poses, pos, goals, far, np.vstack(parts), seed)


def team_moves(scene: Scene, k: int, object_poses: np.ndarray, positions: np.ndarray,
               targets: np.ndarray, movers: np.ndarray, parts: np.ndarray, seed: int = 0
               ) -> Any:
    """Gspi's plan (``MRMPPlan``) that takes each of the ``movers`` (mask) of ``scene``'s
    robots (at ``positions``) to the free spot nearest its target (within
    ``SPOT_SEARCH``, kept apart from the others' places), the rest keeping their place;
    planned in the robot space over ``parts`` (points the moves pass: routes, targets)
    and the movers, grown by ``WINDOW_MARGIN``; robots far outside hold still
    (``lamp.planners.bystanders``). None when a mover gets no spot."""
    pos = np.asarray(positions, float).reshape(-1, 2)
    movers = np.asarray(movers, bool)
    r = float(scene.robot_radius)
    goals = pos.copy()
    route_parts = np.vstack([np.asarray(parts, float).reshape(-1, 2), pos[movers]])
    space = RobotSpace.from_scene(scene, object_poses=object_poses,
                                  window=_window(route_parts, scene))
    spots: list[np.ndarray] = [pos[i] for i in np.flatnonzero(~movers)]

    def apart(points: np.ndarray) -> np.ndarray:
        if not spots:
            return np.ones(len(points), bool)
        d = np.linalg.norm(points[:, None] - np.asarray(spots)[None], axis=2)
        return d.min(axis=1) >= 2 * r + BYSTANDER_GAP

    for i in np.flatnonzero(movers):
        spot = space.nearest_free(np.asarray(targets, float)[i], accept=apart,
                                  max_distance=SPOT_SEARCH)
        if spot is None:
            return None
        goals[i] = spot
        spots.append(np.asarray(spot, float))
    own = standing_on_goal(pos, goals)

    def window_of(points: np.ndarray) -> tuple[float, float, float, float]:
        return _window(np.vstack([points, route_parts, goals[movers]]), scene)

    held = bystanders(window_of, pos, own < 0, own >= 0, 2 * r + BYSTANDER_GAP)
    space = RobotSpace.from_scene(scene, object_poses=object_poses,
                                  window=window_of(pos[~held]))

    def gspi(q_object, starts, goals_, space_, time_limit):
        return plan_paths(space_, starts, goals_, time_limit=time_limit, seed=seed)

    return route_movers(gspi, object_poses[k], pos, goals, own, held, space,
                        TRANSIT_TIME_LIMIT)


def far_robots(field: Routes, positions: np.ndarray) -> np.ndarray:
    """Mask of the robots whose route to the staging area is longer than
    ``TRANSIT_RADIUS`` (robots without a route are not far: they cannot transit)."""
    lengths = [field.length(p) for p in np.asarray(positions, float).reshape(-1, 2)]
    return np.asarray([math.isfinite(d) and d > TRANSIT_RADIUS for d in lengths], bool)


def transit(view: FleetView, world: Callable[[], Scene], k: int, seed: int = 0,
            keep_out: Callable[[], Sequence[shapely.Geometry]] = tuple
            ) -> tuple[int, float]:
    """Drive object ``k``'s sub-team (``view``: its executor; ``world()``: the world as the
    team plans in it now, its robots where they stand; ``keep_out()``: the claims its
    hops would wait on, now) to the object, hop by hop (module docstring); returns the
    hops run and the wall-clock seconds spent planning them."""
    runs, planning = 0, 0.0
    for _ in range(MAX_HOPS):
        poses = np.asarray(view.object_poses, float)
        pos = np.asarray(view.robot_positions, float)
        if not (np.hypot(*(pos - poses[k][:2]).T) > TRANSIT_RADIUS).any():
            break  # every route is at least as long as the straight line
        t0 = time.perf_counter()
        scene = world()
        field = routes(scene, k, poses)
        far = far_robots(field, pos)
        plan = None
        if far.any():
            claimed = keep_out()
            plan = hop(scene, k, poses, pos, far, field, seed=seed, keep_out=claimed)
            if plan is None or not plan.success:
                plan = hop(scene, k, poses, pos, far, field, HOP_LENGTH / 2, seed=seed,
                           keep_out=claimed)
        planning += time.perf_counter() - t0
        # the routes' grid spans the map (some 10 MB at 60 x 40 m): not held while the
        # hop runs, when every other team may be transiting too
        del field, scene
        if plan is None or not plan.success:
            break
        reply = view.execute(plan.paths)
        if not reply.declined:
            runs += 1
        if view.team_changed:
            break  # a robot failed or joined: the caller drives the new team
    return runs, planning
