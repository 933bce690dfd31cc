"""Compiled (Numba) kernels of :class:`~lamp.geometry.object_space.ObjectSpace`.

Conservative clearance of an object footprint (boundary disks plus the polygon) against the
distance grid (tiles of ``lamp.geometry.distance_tiles``), for single poses, batches and
straight SE(2) motions. The guarantees are stated and tested on ``ObjectSpace``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["batch_clearance", "batch_motions_free", "motion_free_kernel", "pose_clearance",
           "pose_free_kernel"]


@numba.njit(cache=True, inline="always")
def _point_in_polygon(px: float, py: float, poly: np.ndarray) -> bool:
    """Crossing-number test (points on the boundary may go either way)."""
    inside = False
    n = poly.shape[0]
    j = n - 1
    for i in range(n):
        xi, yi = poly[i, 0], poly[i, 1]
        xj, yj = poly[j, 0], poly[j, 1]
        if (yi > py) != (yj > py):
            xc = xi + (py - yi) * (xj - xi) / (yj - yi)
            if px < xc:
                inside = not inside
        j = i
    return inside


@numba.njit(cache=True, inline="always")
def _grid_bound(sd: tuple, res: float, px: float, py: float) -> float:
    """The distance grid's clearance lower bound at world point p: the value of the cell
    containing p (points outside the workspace take the nearest border cell); -inf in a
    tile not filled yet. ``sd`` is :attr:`DistanceTiles.args` (a table entry ``t <= -2``
    is the base's tile ``-2 - t``)."""
    tiles, base, table, ny, nx = sd
    ci = min(max(int(math.floor(px / res)), 0), nx - 1)
    ri = min(max(int(math.floor(py / res)), 0), ny - 1)
    T = tiles.shape[1]
    tr = ri // T
    tc = ci // T
    t = table[tr, tc]
    if t >= 0:
        return tiles[t, ri - tr * T, ci - tc * T]
    if t == -1:
        return -np.inf
    return base[-2 - t, ri - tr * T, ci - tc * T]


@numba.njit(cache=True)
def pose_clearance(
    x: float,
    y: float,
    th: float,
    sd: tuple,
    res: float,
    width: float,
    height: float,
    fp: tuple,
    reach2: float,
    stop_below: float,
    quick: bool,
) -> float:
    """Clearance lower bound of the footprint ``fp`` at (x, y, th).

    Returns early once the bound is <= ``stop_below``. With ``quick``, a coarse bound from
    the covering disks that is already > ``stop_below`` is returned as is (it is a valid,
    looser lower bound: boolean queries do not need the tight value).
    """
    dpts, drad, bpts, brad, poly, reps, cpts, crad = fp
    c = math.cos(th)
    s = math.sin(th)
    best = np.inf
    # border (exact: polygon vertices or circle centre)
    for j in range(bpts.shape[0]):
        px = x + c * bpts[j, 0] - s * bpts[j, 1]
        py = y + s * bpts[j, 0] + c * bpts[j, 1]
        d = min(px, width - px, py, height - py) - brad[j]
        if d < best:
            best = d
            if best <= stop_below:
                return best
    if quick and cpts.shape[0] > 0:
        # coarse: disks covering the whole footprint (interior included)
        coarse = best
        for j in range(cpts.shape[0]):
            px = x + c * cpts[j, 0] - s * cpts[j, 1]
            py = y + s * cpts[j, 0] + c * cpts[j, 1]
            d = _grid_bound(sd, res, px, py) - crad[j]
            if d < coarse:
                coarse = d
                if coarse <= stop_below:
                    break
        if coarse > stop_below:
            return coarse
    # obstacles: boundary disks against the distance grid
    for j in range(dpts.shape[0]):
        px = x + c * dpts[j, 0] - s * dpts[j, 1]
        py = y + s * dpts[j, 0] + c * dpts[j, 1]
        d = _grid_bound(sd, res, px, py) - drad[j]
        if d < best:
            best = d
            if best <= stop_below:
                return best
    # obstacles entirely inside a polygonal footprint: one representative point each
    if best > 0.0 and poly.shape[0] > 0:
        for k in range(reps.shape[0]):
            dx = reps[k, 0] - x
            dy = reps[k, 1] - y
            if dx * dx + dy * dy > reach2:
                continue
            lx = c * dx + s * dy
            ly = -s * dx + c * dy
            if _point_in_polygon(lx, ly, poly):
                return 0.0
    return best


@numba.njit(cache=True)
def batch_clearance(
    poses: np.ndarray,
    sd: tuple,
    res: float,
    width: float,
    height: float,
    fp: tuple,
    reach2: float,
    stop_below: float,
    quick: bool,
) -> np.ndarray:
    out = np.empty(poses.shape[0])
    for i in range(poses.shape[0]):
        out[i] = pose_clearance(
            poses[i, 0], poses[i, 1], poses[i, 2], sd, res, width, height,
            fp, reach2, stop_below, quick,
        )  # fmt: skip
    return out


@numba.njit(cache=True)
def motion_free_kernel(
    x0: float,
    y0: float,
    t0: float,
    x1: float,
    y1: float,
    t1: float,
    margin: float,
    reach: float,
    sd: tuple,
    res: float,
    width: float,
    height: float,
    fp: tuple,
    reach2: float,
) -> bool:
    """Conservative advancement along ``se2.interpolate`` from (x0, y0, t0) to (x1, y1, t1)
    (for compiled callers such as the lattice; see ``ObjectSpace.kernel_args``)."""
    dx = x1 - x0
    dy = y1 - y0
    dth = (t1 - t0 + math.pi) % (2.0 * math.pi) - math.pi
    # upper bound of any footprint disk centre's displacement over the whole motion
    length = math.hypot(dx, dy) + reach * abs(dth)
    t = 0.0
    while True:
        c = pose_clearance(
            x0 + t * dx, y0 + t * dy, t0 + t * dth, sd, res, width, height,
            fp, reach2, margin, True,
        )  # fmt: skip
        if c <= margin:
            return False
        if t >= 1.0 or length <= 0.0:
            return True
        # next check where no disk centre moved more than c + margin / 2 (see module doc)
        t = min(1.0, t + (c + 0.5 * margin) / length)


@numba.njit(cache=True)
def pose_free_kernel(
    x: float, y: float, th: float, sd: tuple, res: float, width: float, height: float,
    fp: tuple, reach2: float,
) -> bool:  # fmt: skip
    """``ObjectSpace.pose_free`` for one pose (for compiled callers)."""
    return pose_clearance(x, y, th, sd, res, width, height, fp, reach2, 0.0, True) > 0.0


@numba.njit(cache=True)
def batch_motions_free(
    starts: np.ndarray,
    ends: np.ndarray,
    margin: float,
    reach: float,
    sd: tuple,
    res: float,
    width: float,
    height: float,
    fp: tuple,
    reach2: float,
) -> np.ndarray:
    out = np.empty(starts.shape[0], dtype=np.bool_)
    for m in range(starts.shape[0]):
        out[m] = motion_free_kernel(
            starts[m, 0], starts[m, 1], starts[m, 2], ends[m, 0], ends[m, 1], ends[m, 2],
            margin, reach, sd, res, width, height, fp, reach2,
        )  # fmt: skip
    return out
