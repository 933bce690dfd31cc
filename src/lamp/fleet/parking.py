"""Parking: a sub-team whose object is placed moves out of the others' way before its
robots go free (``PlannerConfig.fleet_park_clear`` > 0; off by default).

Robots freed next to a placed object stand where its last push left them: often beside
the goal of the next load, in the door it came through or across another object's
route, where every later plan must treat them as obstacles. When its object is placed
and no object waits for robots (they would be handed to it at once), a team with a
robot within ``fleet_park_clear`` of what the others still need (every unplaced object's
footprint now and at its goal, and the rest of every moving object's plan: its claim)
moves to parking spots first:

- a spot is a free cell of the transit grid (``fleet.transit.free_grid``: obstacles and
  objects grown by the robot radius + 5 cm) that is open (``PARK_OPEN`` of free cells
  around it: not in a door or a corridor) and at least ``fleet_park_clear`` from what the
  others need;
- each robot that stands in the way takes the spot nearest along the grid (Dijkstra up to
  ``PARK_REACH``), spots kept two radii + 5 cm apart; a robot with no spot in reach stays;
- the move is planned by Gspi like a transit hop (``transit.team_moves``) and runs as a
  segment of the placed object (which stays where it is), admitted like any other.

The object counts as placed from the moment it was (``Fleet.mark_placed``): parking never
delays its placement time nor the makespan. Measured on the ``fleet`` family (seed 0,
``fleet_park_clear`` = 1 m): 19 moves in 12 scenes; the makespan got longer in 5 of them
(fleet-00: 90 -> 109 s, fleet-10: 189 -> 205 s), shorter in 2, and the median ratio to the sequential schedule on the scenes with at least
9 robots went from 0.41 to 0.43: a team that moves makes the others' plans stale (they
replan in the world as it is). Hence off by default.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np
import shapely
from scipy.ndimage import distance_transform_edt
from scipy.sparse.csgraph import dijkstra

from lamp.fleet.state import ObjectState
from lamp.fleet.transit import Grid, free_grid, team_moves
from lamp.fleet.view import FleetView
from lamp.geometry.shapes import to_shapely
from lamp.planners.bystanders import BYSTANDER_GAP
from lamp.scene.model import Scene

__all__ = ["in_the_way", "needed_by_others", "park", "parking_targets"]

#: Free space (m) around a parking spot beyond the grid's own margin.
PARK_OPEN = 0.3
#: How far (m, along the grid) a robot looks for a spot.
PARK_REACH = 5.0


def needed_by_others(scene: Scene, objects: Sequence[ObjectState], poses: np.ndarray,
                     k: int) -> shapely.Geometry | None:
    """What the objects other than ``k`` that are not placed still need (objects of
    ``scene`` at ``poses``): their footprints now and at their goals, and the claims (rest
    of the plan) of those moving."""
    poses = np.asarray(poses, float)
    parts = []
    for o in objects:
        if o.index == k or not o.unplaced:
            continue
        shape = scene.objects[o.index].shape
        parts += [to_shapely(shape, poses[o.index]), to_shapely(shape, scene.objects[o.index].goal)]
        if o.claim is not None:
            parts.append(o.claim)
    return shapely.union_all(parts) if parts else None


def in_the_way(keep: shapely.Geometry | None, positions: np.ndarray, clear: float
               ) -> np.ndarray:
    """Mask of the robots within ``clear`` of ``keep``."""
    pos = np.asarray(positions, float).reshape(-1, 2)
    if keep is None or keep.is_empty:
        return np.zeros(len(pos), bool)
    return np.asarray(shapely.dwithin(keep, shapely.points(pos), clear), bool)


def parking_targets(grid: Grid, keep: shapely.Geometry, positions: np.ndarray,
                    movers: np.ndarray, robot_radius: float, clear: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(targets (N, 2), movers with a spot (mask), points of their grid paths): for each
    of the ``movers`` in order, the open cell at least ``clear`` from ``keep``
    nearest along the grid within ``PARK_REACH`` (ties by cell index), apart from the
    spots taken before and from the robots that stay."""
    pos = np.asarray(positions, float).reshape(-1, 2)
    cell = grid.cell
    open_ = distance_transform_edt(grid.free) * cell >= PARK_OPEN + cell
    ok = (open_ & ~np.asarray(shapely.dwithin(keep, shapely.points(grid.X, grid.Y),
                                              clear), bool)).ravel()
    targets, moved, parts = pos.copy(), np.zeros(len(pos), bool), [pos[movers]]
    taken = [pos[i] for i in np.flatnonzero(~np.asarray(movers, bool))]
    for i in np.flatnonzero(movers):
        start = grid.nearest_free_cell(pos[i])
        if start is None:
            continue
        dist, pred = dijkstra(grid.graph, directed=False, indices=start,
                              limit=PARK_REACH, return_predecessors=True)
        cand = np.flatnonzero(ok & np.isfinite(dist))
        if taken and len(cand):
            xy = grid.centres(cand)
            d = np.linalg.norm(xy[:, None] - np.asarray(taken)[None], axis=2).min(axis=1)
            cand = cand[d >= 2 * robot_radius + BYSTANDER_GAP + cell]
        if len(cand) == 0:
            continue
        best = int(cand[np.lexsort((cand, dist[cand]))[0]])
        parts.append(grid.walk(pred, best))
        targets[i] = parts[-1][0]
        moved[i] = True
        taken.append(targets[i])
    return targets, moved, np.vstack(parts)


def park(view: FleetView, world: Callable[[], Scene], k: int, keep: shapely.Geometry | None,
         clear: float, seed: int = 0) -> tuple[int, float]:
    """Move object ``k``'s sub-team (``view``; ``world()``: the world as it plans in it
    now) ``clear`` metres out of ``keep`` (module docstring); returns the moves run (0 or
    1) and the wall-clock seconds spent planning."""
    pos = np.asarray(view.robot_positions, float)
    movers = in_the_way(keep, pos, clear)
    if not movers.any():
        return 0, 0.0
    t0 = time.perf_counter()
    scene = world()
    poses = np.asarray(view.object_poses, float)
    targets, moved, parts = parking_targets(free_grid(scene, poses), keep, pos, movers,
                                            float(scene.robot_radius), clear)
    plan = team_moves(scene, k, poses, pos, targets, moved, parts, seed) if moved.any() \
        else None
    planning = time.perf_counter() - t0
    if plan is None or not plan.success:
        return 0, planning
    reply = view.execute(plan.paths)
    return (0 if reply.declined else 1), planning
