"""Validation of Gspi's starts and goals: shape and finiteness (``InputError``), then
placement: inside the workspace, clear of obstacles, clear of each other (a reason)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from lamp.errors import InputError
from lamp.geometry.robot_space import RobotSpace

__all__ = ["as_points", "check_points"]


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
    clr = space.clearance(pts, exact=True)
    bad = clr < space.threshold - tol
    if bad.any():
        k = int(np.nonzero(bad)[0][0])
        where = "inside an obstacle" if clr[k] < 0 else "overlapping an obstacle or the border"
        return clr, (f"{name}[{k}] = {pts[k].tolist()} is {where}: clearance {clr[k]:.4f} m "
                     f"< required {space.threshold:.4f} m - tolerance {tol:g} m")
    if len(pts) > 1:
        d = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        np.fill_diagonal(d, np.inf)
        close = d < 2 * space.radius - tol
        if close.any():
            a, b = (int(v) for v in np.argwhere(close)[0])
            return clr, (f"{name}[{a}] and {name}[{b}] overlap: distance {d[a, b]:.4f} m < "
                         f"2r = {2 * space.radius:.4f} m - tolerance {tol:g} m")
    return clr, ""
