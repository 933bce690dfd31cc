"""Validation of Gspi's starts and goals: shape and finiteness (``InputError``), then
placement: inside the workspace, clear of obstacles, clear of each other (a reason)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from lamp.errors import InputError
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.obstacle_grid import get_grid, grid_points_clearance

__all__ = ["as_points", "check_points", "exact_clearance"]

#: Up to this many points, all pairs and all obstacles are measured at once.
DENSE_POINTS = 64


def as_points(x: ArrayLike, name: str) -> np.ndarray:
    """``x`` as a finite (n, 2) float array; InputError naming ``name`` otherwise."""
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be an (n, 2) array of numbers: {exc}") from exc
    if a.ndim == 1 and a.size == 0:
        a = a.reshape(0, 2)
    if a.ndim != 2 or a.shape[1] != 2:
        raise InputError(f"{name} must have shape (n, 2), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be finite, got non-finite values")
    return a


def check_points(
    space: RobotSpace, pts: np.ndarray, name: str, tol: float
) -> tuple[np.ndarray, str]:
    """(exact clearance of each point, why the points cannot be used or ""): a point
    outside the workspace, deeper than ``tol`` inside the threshold, or two points
    overlapping by more than ``tol``. The reason names the point (``goals[1]``)."""
    W, H = space.workspace
    outside = (pts[:, 0] < 0) | (pts[:, 0] > W) | (pts[:, 1] < 0) | (pts[:, 1] > H)
    if outside.any():
        k = int(np.nonzero(outside)[0][0])
        return np.zeros(len(pts)), (f"{name}[{k}] = {pts[k].tolist()} lies outside the "
                                    f"workspace {W}x{H}")
    clr = exact_clearance(space, pts)
    bad = clr < space.threshold - tol
    if bad.any():
        k = int(np.nonzero(bad)[0][0])
        where = "inside an obstacle" if clr[k] < 0 else "overlapping an obstacle or the border"
        return clr, (f"{name}[{k}] = {pts[k].tolist()} is {where}: clearance {clr[k]:.4f} m "
                     f"< required {space.threshold:.4f} m - tolerance {tol:g} m")
    pair = _first_overlap(pts, 2 * space.radius - tol)
    if pair is not None:
        a, b = pair
        d = float(np.hypot(*(pts[a] - pts[b])))
        return clr, (f"{name}[{a}] and {name}[{b}] overlap: distance {d:.4f} m < "
                     f"2r = {2 * space.radius:.4f} m - tolerance {tol:g} m")
    return clr, ""


def _first_overlap(pts: np.ndarray, limit: float) -> tuple[int, int] | None:
    """The first pair (a, b), a < b, in row-major order of points closer than ``limit``."""
    if len(pts) < 2:
        return None
    if len(pts) <= DENSE_POINTS:
        d = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        np.fill_diagonal(d, np.inf)
        close = np.argwhere(d < limit)
        return (int(close[0, 0]), int(close[0, 1])) if len(close) else None
    pairs = cKDTree(pts).query_pairs(max(limit, 0.0), output_type="ndarray")
    if len(pairs) == 0:
        return None
    d = np.hypot(*(pts[pairs[:, 0]] - pts[pairs[:, 1]]).T)
    pairs = pairs[d < limit]
    if len(pairs) == 0:
        return None
    pairs = np.sort(pairs, axis=1)
    k = np.lexsort((pairs[:, 1], pairs[:, 0]))[0]
    return int(pairs[k, 0]), int(pairs[k, 1])


def exact_clearance(space: RobotSpace, pts: np.ndarray) -> np.ndarray:
    """``space.clearance(pts, exact=True)``, the same values: a few points against every
    obstacle, more against the obstacles near each one (the bucket grid of
    :mod:`lamp.mrmp.obstacle_grid`; a point with no obstacle within its reach is measured
    against every obstacle)."""
    if len(pts) <= DENSE_POINTS:
        return space.clearance(pts, exact=True)
    W, H = space.workspace
    g = space.geometry
    grid = get_grid(g)
    return grid_points_clearance(np.ascontiguousarray(pts, dtype=np.float64), g.circles,
                                 g.verts, g.ptr, float(W), float(H), grid.ptr, grid.idx,
                                 grid.box, grid.nx, grid.ny, grid.cell)
