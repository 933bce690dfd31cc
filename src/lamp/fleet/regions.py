"""Space in the fleet schedule: what a moving sub-team sweeps, what a plan claims, and what
stands still (Shapely geometry).

A segment that may start must keep out of the space every other body needs while it runs:

- **Swept** (:func:`swept`): a segment's robots' remaining path rows, each robot a disk of
  the robot radius plus ``ROBOT_MARGIN``, and its object's footprint at poses along the
  planned motion (``POSE_STEP`` / ``TURN_STEP`` apart), grown by ``OBJECT_MARGIN`` for
  the drift the closed loop tolerates.
- **Claim** (:func:`claim`): the footprints along the rest of an object's plan, grown by a
  robot diameter (its pushers stand around it). A lower-priority segment keeps out of a
  higher-priority object's claim, so that two loads never meet head-on in a door.
- **Standing** (:func:`standing`): an object's or robot's footprint where it is now,
  shrunk by ``STATIC_SLACK``, tested against a segment's bodies exactly as planned
  (``swept(..., margins=False)``): the planner saw them, so only a real overlap (the
  world changed since the plan) counts.

Guarantee (``tests/test_fleet_parts.py``): two segments whose swept regions do not
intersect keep every robot disk and object footprint of one at least ``2 * ROBOT_MARGIN``
(robots) / ``2 * OBJECT_MARGIN`` (objects, as planned) from the other's at all times,
whatever their timing.
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np
import shapely

from lamp.fleet.config import CLAIM_NEAR
from lamp.geometry.clearance_layers import lru_get, lru_put
from lamp.geometry.se2 import interpolate, pose_distance
from lamp.geometry.shapes import to_shapely, to_shapely_many
from lamp.scene.model import Shape

__all__ = ["CLAIM_BLOCK", "OBJECT_MARGIN", "ROBOT_MARGIN", "STATIC_SLACK", "ClaimBlocks",
           "claim", "claims", "footprints", "robot_disks", "standing", "standing_robots", "swept"]

#: Clearance (m) each moving robot keeps from another sub-team's space (half the gap).
ROBOT_MARGIN = 0.01
#: Clearance (m) around a moving object's planned footprints: the drift it may execute
#: with before its loop replans (``LoopConfig.drift_position`` is 0.05).
OBJECT_MARGIN = 0.05
#: A standing body is shrunk by this (m) before it is tested against a planned segment.
STATIC_SLACK = 0.003
#: Planned object motion is sampled this finely (m, rad).
POSE_STEP = 0.05
TURN_STEP = 0.15
#: Robot path rows are thinned to at most this many per robot (the path between two kept
#: rows is a straight line, so nothing is lost: the buffer covers the segments).
_MAX_PATH_POINTS = 400
#: Steps (pose pairs) of a plan per cached block of its claim (:class:`ClaimBlocks`).
CLAIM_BLOCK = 16


def _densified(poses: np.ndarray) -> np.ndarray:
    """``poses`` (P, 3) with interpolated poses no more than the steps apart."""
    poses = np.asarray(poses, float).reshape(-1, 3)
    out = [poses[:1]]
    for a, b in zip(poses[:-1], poses[1:], strict=True):
        dt, dr = pose_distance(a, b)
        n = max(1, int(np.ceil(max(float(dt) / POSE_STEP, float(dr) / TURN_STEP))))
        out.append(interpolate(a, b, np.arange(1, n + 1) / n))
    return np.concatenate(out)


def footprints(shape: Shape, poses: np.ndarray, grow: float = 0.0) -> shapely.Geometry:
    """Union of ``shape``'s footprints at ``poses`` (densified), grown by ``grow`` (m):
    the union of each step's hull (the convex hull of the bodies at its two ends, which
    holds both), the same set as the bodies' and the hulls' union together."""
    q = _densified(poses)
    parts = to_shapely_many(shape, q)
    if len(parts) == 1:
        geom = parts[0]
    else:  # every footprint has the shape's vertex count: each step's hull at once
        ends = shapely.get_coordinates(parts).reshape(len(parts), -1, 2)
        geom = shapely.union_all(shapely.convex_hull(shapely.multipoints(
            np.concatenate([ends[:-1], ends[1:]], axis=1))))
    return geom.buffer(grow) if grow > 0 else geom


def robot_disks(paths: np.ndarray, radius: float) -> shapely.Geometry:
    """The space robots of ``radius`` sweep along ``paths`` (N, T, 2) (straight between
    rows)."""
    paths = np.asarray(paths, float)
    if paths.ndim == 2:
        paths = paths[:, None]
    lines = []
    for p in paths:
        if len(p) > _MAX_PATH_POINTS:
            keep = np.unique(np.linspace(0, len(p) - 1, _MAX_PATH_POINTS).astype(int))
            p = p[keep]
        lines.append(shapely.Point(p[0]) if len(p) == 1 or np.allclose(p, p[0])
                     else shapely.LineString(p))
    return shapely.union_all([g.buffer(radius, quad_segs=8) for g in lines])


def swept(shape: Shape, object_poses: np.ndarray, robot_rows: np.ndarray,
          robot_radius: float, margins: bool = True) -> shapely.Geometry:
    """A segment's space (see the module docstring): its object along ``object_poses`` and
    its robots along ``robot_rows`` (N, T, 2); without ``margins`` the bodies exactly as
    planned (what is tested against standing bodies)."""
    obj = footprints(shape, object_poses, OBJECT_MARGIN if margins else 0.0)
    grow = ROBOT_MARGIN if margins else 0.0
    return shapely.union(obj, robot_disks(robot_rows, robot_radius + grow))


def claim(shape: Shape, poses: np.ndarray, robot_radius: float) -> shapely.Geometry | None:
    """The space an object's remaining plan ``poses`` (P, 3) claims (None: no poses)."""
    poses = np.asarray(poses, float).reshape(-1, 3)
    if len(poses) == 0:
        return None
    return footprints(shape, poses, 2.0 * robot_radius + OBJECT_MARGIN)


class ClaimBlocks:
    """Claims built from cached blocks, for the claims of one plan as it is executed (each
    segment announces the rest of its plan, a suffix of the last): a plan's claim is the
    union of the claims of its runs of ``CLAIM_BLOCK`` steps counted from its last pose
    (each block holds the pose that joins it to the next), and of the few steps before
    them, so the claims of one plan's suffixes build each block once. The same set as
    :func:`claim` (growing distributes over the union) up to the accuracy of GEOS'
    growing (arcs as chords; dents shallower than 1% of the growth filled, which the
    whole plan's union may have where the blocks' do not). Keeps the ``size`` most
    recently used blocks."""

    def __init__(self, size: int = 1024) -> None:
        self.size = size
        self._blocks: OrderedDict[tuple, shapely.Geometry] = OrderedDict()

    def claim(self, shape: Shape, poses: np.ndarray, robot_radius: float
              ) -> shapely.Geometry | None:
        """:func:`claim` of ``poses`` (P, 3), from blocks."""
        poses = np.asarray(poses, float).reshape(-1, 3)
        steps = len(poses) - 1
        if steps <= CLAIM_BLOCK:
            return claim(shape, poses, robot_radius)
        head = steps % CLAIM_BLOCK
        parts = [claim(shape, poses[:head + 1], robot_radius)] if head else []
        for s in range(head, steps, CLAIM_BLOCK):
            block = poses[s:s + CLAIM_BLOCK + 1]
            key = (shape, float(robot_radius), block.tobytes())
            geom = lru_get(self._blocks, key)
            if geom is None:
                geom = claim(shape, block, robot_radius)
                lru_put(self._blocks, key, geom, self.size)
            parts.append(geom)
        return shapely.union_all(parts)


def claims(shape: Shape, poses: np.ndarray, goal: np.ndarray, robot_radius: float,
           near_reach: float = CLAIM_NEAR, blocks: ClaimBlocks | None = None
           ) -> tuple[shapely.Geometry | None, shapely.Geometry | None, shapely.Geometry | None]:
    """What an object's plan ``poses`` (P, 3) claims, prepared: its :func:`claim` (from
    ``blocks`` when given), the near part (the claim of the poses within ``near_reach`` m
    of planned travel from the first; the whole claim when the plan is no longer, or
    ``near_reach`` is 0) and its way (the centre's path through the poses on to ``goal``,
    a line). (None, None, None) without poses."""
    poses = np.asarray(poses, float).reshape(-1, 3)
    if len(poses) == 0:
        return None, None, None
    travel = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(poses[:, :2], axis=0).T))])
    n_near = (max(1, int(np.searchsorted(travel, near_reach, side="right")))
              if near_reach > 0 else len(poses))
    full = (claim(shape, poses, robot_radius) if blocks is None else
            blocks.claim(shape, poses, robot_radius))
    near = full if n_near >= len(poses) else claim(shape, poses[:n_near], robot_radius)
    way = shapely.LineString(np.vstack([poses[:, :2], np.asarray(goal, float)[None, :2]]))
    for g in {id(g): g for g in (full, near, way)}.values():
        shapely.prepare(g)
    return full, near, way


def standing(shape: Shape, pose: np.ndarray) -> shapely.Geometry:
    """An object's body where it stands (``shape`` at ``pose``), shrunk by
    ``STATIC_SLACK``."""
    return to_shapely(shape, pose).buffer(-STATIC_SLACK)


def standing_robots(positions: np.ndarray, robot_radius: float) -> np.ndarray:
    """The bodies of robots standing at ``positions`` ((N, 2) or (N, 3); the x, y used):
    N disks, shrunk by ``STATIC_SLACK``."""
    centres = np.asarray(positions, float).reshape(-1, np.shape(positions)[-1])[:, :2]
    return shapely.buffer(shapely.points(centres), robot_radius - STATIC_SLACK, quad_segs=8)
