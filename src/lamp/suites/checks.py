"""Route and reachability checks for benchmark scenes.

For one object of a scene (the others standing still as obstacles, as the scene format
prescribes) these checks answer:

* **Does the object fit along an obstacle-free route from start to goal?**
  ``find_route`` runs A* over an SE(2) lattice (``resolution`` m, ``n_headings`` headings
  over the shape's symmetry period: pi for rectangles, none for circles), keeping a
  required clearance ``tau`` between the object and every obstacle, the other objects
  and the border. Clearances are exact (``lamp.suites.kernels``) and every lattice move
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
from numpy.typing import ArrayLike
from scipy import ndimage

from lamp.scene.model import Obstacle, Scene
from lamp.suites import kernels as K
from lamp.suites.routes import (  # noqa: F401 - re-exported: the checks' public API
    CLEARANCE_LADDER,
    FREE_CLEARANCE,
    MAX_DEPTH,
    N_HEADINGS,
    RESOLUTION,
    ROBOT_ROOM,
    ROT_WEIGHT,
    SAMPLE_STEP,
    TIGHT_MIN_EXTRA,
    TIGHT_MIN_RATIO,
    Route,
    RouteFinder,
    find_route,
    verify_route,
)
from lamp.suites.world import (  # noqa: F401 - re-exported
    Footprint,
    World,
    build_world,
    clearance,
    footprint_of,
    object_obstacles,
    object_world,
    point_clearance,
)


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
