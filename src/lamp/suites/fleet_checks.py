"""Checks of the ``fleet`` family (``lamp.suites.fleet``): every object can be pushed on
its own while the others stand still, whatever the concurrent schedule has done so far.

For object k, the other objects stand as the ``after`` lists allow: an object k waits for
(its ancestors, transitively) at its goal, an object waiting for k (its descendants) at
its start, and every other object at its start *and* its goal at once (both footprints
are obstacles), which covers every mix of placed and unplaced objects, in particular the
file's order that the sequential schedule follows (ancestors come first in the file).
In that world:

* **route** (``checks.RouteFinder``, certified lattice search as in the other families):
  a route from start to goal keeping clearance >= ``checks.ROBOT_ROOM`` (a robot fits
  between the object and anything else all along; so it keeps ``FREE_CLEARANCE`` too);
* **blocked** (objects with an ``after`` list): with every other object at its start, no
  route keeping even ``checks.FREE_CLEARANCE`` exists, so the wait is real;
* **reach** (the grid of ``checks.robot_free_cells``, judged as ``checks.robot_reach``
  does, with the same world of standing objects except that every object's goal
  footprint is an obstacle and the ancestors' starts are not): every robot's free
  component contains cells of the object's contact ring, and the robots reach at least
  ``MIN_RING`` of the ring.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage

from lamp.scene.model import Obstacle, Scene
from lamp.suites import checks as C
from lamp.suites import kernels as K

#: least fraction of an object's contact ring the robots must reach
MIN_RING = 0.5


def ancestry(after: list[tuple[int, ...]]) -> list[set[int]]:
    """Per object, every object it waits for, directly or through others."""
    out: list[set[int]] = []
    for k in range(len(after)):
        seen: set[int] = set()
        todo = list(after[k])
        while todo:
            j = todo.pop()
            if j not in seen:
                seen.add(j)
                todo.extend(after[j])
        out.append(seen)
    return out


def _pose(p: Any) -> tuple[float, float, float]:
    return (float(p[0]), float(p[1]), float(p[2]))


def standing(scene: Scene, k: int, anc: list[set[int]]) -> list[Obstacle]:
    """The static obstacles and the other objects as they may stand while ``k`` moves."""
    out = list(scene.obstacles)
    for j, o in enumerate(scene.objects):
        if j == k:
            continue
        if j not in anc[k]:
            out.append(Obstacle(o.shape, _pose(o.start)))
        if k not in anc[j]:
            out.append(Obstacle(o.shape, _pose(o.goal)))
    return out


@dataclass(frozen=True)
class FleetObjectReport:
    """Check results of one object (its manifest entry)."""

    index: int
    after: tuple[int, ...]
    start_clearance: float
    goal_clearance: float
    route: C.Route
    blocked: bool | None
    reach: C.RobotReach

    def to_dict(self) -> dict[str, Any]:
        return {
            "index": self.index,
            "after": list(self.after),
            "start_clearance": round(self.start_clearance, 4),
            "goal_clearance": round(self.goal_clearance, 4),
            "robot_route": self.route.to_dict(3),
            "blocked_until_after": self.blocked,
            "robots": self.reach.to_dict(),
        }


def object_route(scene: Scene, k: int, anc: list[set[int]], resolution: float,
                 n_headings: int) -> tuple[C.Route | None, float, float]:
    """(robot-room route or None, start clearance, goal clearance) of object ``k``."""
    obj = scene.objects[k]
    world = C.build_world(scene.workspace, standing(scene, k, anc))
    c0, c1 = C.clearance(obj.shape, world, np.array([obj.start, obj.goal]))
    finder = C.RouteFinder(obj.shape, world, resolution, n_headings)
    return finder.find(obj.start, obj.goal, C.ROBOT_ROOM), float(c0), float(c1)


def is_blocked(scene: Scene, k: int, resolution: float, n_headings: int) -> bool:
    """No route keeping FREE_CLEARANCE for object ``k`` with the others at their starts."""
    obj = scene.objects[k]
    finder = C.RouteFinder(obj.shape, C.object_world(scene, k), resolution, n_headings)
    return finder.find(obj.start, obj.goal, C.FREE_CLEARANCE) is None


def _robot_labels(xs: np.ndarray, ys: np.ndarray, free: np.ndarray, labels: np.ndarray,
                  robots: np.ndarray, clear: np.ndarray, r: float, h: float) -> list[int]:
    """Each robot's component (0: none), as ``checks.robot_reach`` finds it: the nearest
    free cell of the 2 x 2 around it reachable by a straight move keeping clearance r."""
    ny, nx = free.shape
    out = []
    for (px, py), c in zip(robots, clear, strict=True):
        lab, best = 0, np.inf
        i0, j0 = int(math.floor(px / h - 0.5)), int(math.floor(py / h - 0.5))
        for i in (i0, i0 + 1):
            for j in (j0, j0 + 1):
                if 0 <= i < nx and 0 <= j < ny and free[j, i]:
                    d = math.hypot(xs[i] - px, ys[j] - py)
                    if min(c, r + 0.5 * h) - 0.5 * d >= r and d < best:
                        best, lab = d, int(labels[j, i])
        out.append(lab)
    return out


@dataclass(frozen=True)
class ReachGrid:
    """Cell centres (side ``h``), which cells have exact clearance >= r + h / 2 from the
    static obstacles, the border and every object's goal footprint (``free``), and the
    robots' exact clearance from the same."""

    h: float
    xs: np.ndarray
    ys: np.ndarray
    free: np.ndarray
    robots: np.ndarray


def _clear(world: C.World, pts: np.ndarray, border: bool) -> np.ndarray:
    return K.point_clearance(np.ascontiguousarray(pts), *world.args[:4], world.width,
                             world.height, border)


def free_cells(world: C.World, xs: np.ndarray, ys: np.ndarray, h: float, need: float,
               border: bool) -> np.ndarray:
    """(ny, nx): the cells whose centre has exact clearance >= ``need`` in ``world``. Blocks
    of BLOCK x BLOCK cells are decided from their centre when its clearance is farther
    from ``need`` than any of their cells (clearance is 1-Lipschitz); the exact clearance
    of the other cells decides them. The result is the same as testing every cell."""
    nx, ny = len(xs), len(ys)
    bx, by = -(-nx // BLOCK), -(-ny // BLOCK)
    i0, j0 = np.arange(bx) * BLOCK, np.arange(by) * BLOCK
    i1, j1 = np.minimum(i0 + BLOCK, nx) - 1, np.minimum(j0 + BLOCK, ny) - 1
    cx, cy = np.meshgrid(0.5 * (xs[i0] + xs[i1]), 0.5 * (ys[j0] + ys[j1]))
    c = _clear(world, np.stack([cx.ravel(), cy.ravel()], axis=1), border).reshape(by, bx)
    half = (BLOCK - 1) * h / math.sqrt(2.0)
    state = np.where(c - half >= need, 1, np.where(c + half < need, 0, -1))
    cells = np.repeat(np.repeat(state, BLOCK, axis=0), BLOCK, axis=1)[:ny, :nx]
    out = cells == 1
    jj, ii = np.nonzero(cells == -1)
    if len(ii):
        out[jj, ii] = _clear(world, np.stack([xs[ii], ys[jj]], axis=1), border) >= need
    return out


#: cells per side of the blocks ``free_cells`` decides at once
BLOCK = 8


def reach_grid(scene: Scene, h: float) -> ReachGrid:
    goals = [Obstacle(o.shape, _pose(o.goal)) for o in scene.objects]
    world = C.build_world(scene.workspace, [*scene.obstacles, *goals])
    nx, ny = (int(math.floor(v / h)) for v in scene.workspace)
    xs, ys = (np.arange(nx) + 0.5) * h, (np.arange(ny) + 0.5) * h
    need = float(scene.robot_radius) + 0.5 * h
    return ReachGrid(h, xs, ys, free_cells(world, xs, ys, h, need, True),
                     _clear(world, scene.robot_starts_array, True))


def team_reach(scene: Scene, grid: ReachGrid, indices: list[int], ancestors: set[int],
               ring_width: float) -> dict[int, C.RobotReach]:
    """Reach of the objects ``indices`` (all waiting for exactly ``ancestors``) as
    ``checks.robot_reach`` judges it, on the grid ``checks.robot_free_cells`` builds for the
    world of the static obstacles, every goal footprint and the starts of the objects
    other than the ancestors (``grid.free`` and the cells clear of those starts)."""
    h, xs, ys = grid.h, grid.xs, grid.ys
    starts = C.build_world(scene.workspace, [Obstacle(o.shape, _pose(o.start))
                                             for j, o in enumerate(scene.objects)
                                             if j not in ancestors])
    r = float(scene.robot_radius)
    free = grid.free & free_cells(starts, xs, ys, h, r + 0.5 * h, False)
    labels, _ = ndimage.label(free)
    robots = scene.robot_starts_array
    clear = np.minimum(grid.robots, _clear(starts, robots, False))
    comps = _robot_labels(xs, ys, free, labels, robots, clear, r, h)
    out = {}
    for k in indices:
        obj = scene.objects[k]
        pose = obj.start
        pad = C.footprint_of(obj.shape).reach + r + h + ring_width
        i = np.flatnonzero(np.abs(xs - pose[0]) <= pad)
        j = np.flatnonzero(np.abs(ys - pose[1]) <= pad)
        own = C.build_world(scene.workspace, [Obstacle(obj.shape, _pose(pose))])
        sx, sy = np.meshgrid(xs[i], ys[j])
        d = _clear(own, np.stack([sx.ravel(), sy.ravel()], axis=1), False).reshape(sx.shape)
        ring = (d >= r + 0.5 * h) & (d <= r + 0.5 * h + ring_width)
        lab = labels[np.ix_(j, i)]
        reaches = tuple(bool(c) and bool(np.any(ring & (lab == c))) for c in comps)
        mine = np.isin(lab, [c for c in set(comps) if c]) & ring
        fraction = float(mine.sum() / max(1, ring.sum()))
        out[k] = C.RobotReach(reaches, fraction, tuple(float(v) for v in clear))
    return out


def check_objects(scene: Scene, resolution: float, n_headings: int, reach_h: float,
                  ring_width: float) -> list[FleetObjectReport] | str:
    """Every check of the module docstring for every object: the reports, or the reason
    (a short phrase naming the object) of the first failure."""
    after = [o.after for o in scene.objects]
    anc = ancestry(after)
    groups: dict[frozenset[int], list[int]] = {}
    for k in range(len(scene.objects)):
        groups.setdefault(frozenset(anc[k]), []).append(k)
    grid = reach_grid(scene, reach_h)
    reach: dict[int, C.RobotReach] = {}
    for key, members in groups.items():
        reach.update(team_reach(scene, grid, members, set(key), ring_width))
    reports = []
    for k in range(len(scene.objects)):
        if not reach[k].all_reach or reach[k].ring_fraction < MIN_RING:
            return f"robots cannot reach object {k}"
        blocked = None
        if after[k]:
            blocked = is_blocked(scene, k, resolution, n_headings)
            if not blocked:
                return f"object {k} is not blocked"
        route, c0, c1 = object_route(scene, k, anc, resolution, n_headings)
        if route is None:
            return f"no robot-room route for object {k}"
        reports.append(FleetObjectReport(k, after[k], c0, c1, route, blocked, reach[k]))
    return reports
