"""A bucket grid over a map's obstacles, for the clearance checks of large fleets.

Each square cell of :data:`CELL` metres lists the obstacles (circles, then polygons, as
in :class:`~lamp.geometry.geometry_set.GeometrySet`) whose bounding box meets it. A
query for a segment (or a point) and a reach ``t`` measures only the obstacles whose
bounding box comes within ``t`` of the segment's bounding box, each with the exact
per-obstacle kernels of :mod:`lamp.geometry.clearance_kernels`; all of it is compiled,
with no Python work per tile or per point.

Guarantees (``tests/test_mrmp_obstacle_grid.py``): :func:`grid_clear_segments` makes
the decisions ``segments_clearance(...) >= need - 1e-12`` over all obstacles makes (an
obstacle left out is farther than ``need`` from the segment, so it changes no decision),
and :func:`grid_points_clearance` returns ``points_clearance`` over all obstacles bit
for bit (the nearest obstacle of a point whose clearance is below the reach is always
measured; a point with none that near is measured against every obstacle).
"""

from __future__ import annotations

import math
import weakref
from typing import Any, NamedTuple

import numba as nb
import numpy as np

from lamp.geometry.clearance_kernels import point_clearance, segment_clearance

__all__ = ["CELL", "ObstacleGrid", "get_grid", "grid_clear_segments",
           "grid_points_clearance"]

#: Side of a grid cell (m).
CELL = 0.25
#: Reach (m) within which the obstacles of a point are measured exactly; a point with no
#: obstacle that near is measured against all of them.
POINT_REACH = 0.5

_GRIDS: weakref.WeakKeyDictionary[Any, ObstacleGrid] = weakref.WeakKeyDictionary()


class ObstacleGrid(NamedTuple):
    """``ptr``/``idx``: the obstacles of each cell (CSR over ``cy * nx + cx``; index ``c``
    a circle, ``C + q`` polygon q); ``box (C + P, 4)``: their bounding boxes."""

    ptr: np.ndarray
    idx: np.ndarray
    box: np.ndarray
    nx: int
    ny: int
    cell: float


def get_grid(geometry: Any) -> ObstacleGrid:
    """The bucket grid of ``geometry`` (a ``GeometrySet``; built once and kept while the
    geometry lives)."""
    grid = _GRIDS.get(geometry)
    if grid is None:
        box = np.ascontiguousarray(geometry.bounds(), dtype=np.float64).reshape(-1, 4)
        hi = float(box[:, 2:].max()) if len(box) else 0.0
        n = max(1, int(math.ceil(max(hi, 0.0) / CELL)) + 1)
        ptr, idx = _bucket(box, n, n, CELL)
        grid = ObstacleGrid(ptr, idx, box, n, n, CELL)
        _GRIDS[geometry] = grid
    return grid


@nb.njit(cache=True)
def _cells(x0: float, y0: float, x1: float, y1: float, nx: int, ny: int,
           cell: float) -> tuple[int, int, int, int]:
    """The cells (clamped to the grid) that the box meets: (cx0, cy0, cx1, cy1)."""
    cx0 = min(max(int(math.floor(x0 / cell)), 0), nx - 1)
    cy0 = min(max(int(math.floor(y0 / cell)), 0), ny - 1)
    cx1 = min(max(int(math.floor(x1 / cell)), 0), nx - 1)
    cy1 = min(max(int(math.floor(y1 / cell)), 0), ny - 1)
    return cx0, cy0, cx1, cy1


@nb.njit(cache=True)
def _bucket(box: np.ndarray, nx: int, ny: int, cell: float) -> tuple[np.ndarray, np.ndarray]:
    cnt = np.zeros(nx * ny + 1, np.int64)
    for o in range(box.shape[0]):
        cx0, cy0, cx1, cy1 = _cells(box[o, 0], box[o, 1], box[o, 2], box[o, 3], nx, ny, cell)
        for cy in range(cy0, cy1 + 1):
            for cx in range(cx0, cx1 + 1):
                cnt[cy * nx + cx + 1] += 1
    ptr = np.cumsum(cnt)
    fill = ptr[:-1].copy()
    idx = np.empty(ptr[-1], np.int64)
    for o in range(box.shape[0]):
        cx0, cy0, cx1, cy1 = _cells(box[o, 0], box[o, 1], box[o, 2], box[o, 3], nx, ny, cell)
        for cy in range(cy0, cy1 + 1):
            for cx in range(cx0, cx1 + 1):
                idx[fill[cy * nx + cx]] = o
                fill[cy * nx + cx] += 1
    return ptr, idx


@nb.njit(cache=True)
def _gather(x0: float, y0: float, x1: float, y1: float, t: float, gptr: np.ndarray,
            gidx: np.ndarray, box: np.ndarray, nx: int, ny: int, cell: float,
            seen: np.ndarray, stamp: int, out: np.ndarray) -> int:
    """Into ``out``: the obstacles whose bounding box comes within ``t`` of the box
    (x0, y0, x1, y1), each once (``seen``/``stamp``); returns how many."""
    cx0, cy0, cx1, cy1 = _cells(x0 - t, y0 - t, x1 + t, y1 + t, nx, ny, cell)
    n = 0
    for cy in range(cy0, cy1 + 1):
        for cx in range(cx0, cx1 + 1):
            c = cy * nx + cx
            for e in range(gptr[c], gptr[c + 1]):
                o = gidx[e]
                if seen[o] == stamp:
                    continue
                seen[o] = stamp
                if (box[o, 0] <= x1 + t and box[o, 2] >= x0 - t and box[o, 1] <= y1 + t
                        and box[o, 3] >= y0 - t):
                    out[n] = o
                    n += 1
    return n


@nb.njit(cache=True, inline="always")
def _alone(o: int, circles: np.ndarray, vptr: np.ndarray, none_c: np.ndarray,
           one_c: np.ndarray, one_p: np.ndarray, no_p: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """Obstacle ``o`` (circles first, then polygons) alone, as the (circles, polygon
    offsets) arguments of the clearance kernels, written into the scratch arrays."""
    C = circles.shape[0]
    if o < C:
        one_c[0, 0] = circles[o, 0]
        one_c[0, 1] = circles[o, 1]
        one_c[0, 2] = circles[o, 2]
        return one_c, no_p
    one_p[0] = vptr[o - C]
    one_p[1] = vptr[o - C + 1]
    return none_c, one_p


@nb.njit(cache=True)
def grid_clear_segments(a: np.ndarray, b: np.ndarray, need: np.ndarray, circles: np.ndarray,
                        verts: np.ndarray, vptr: np.ndarray, W: float, H: float,
                        gptr: np.ndarray, gidx: np.ndarray, box: np.ndarray, nx: int,
                        ny: int, cell: float) -> np.ndarray:
    """Whether each segment ``a[k] -> b[k]`` keeps an exact clearance of at least
    ``need[k] - 1e-12`` (``need > 0``) from the obstacles and the workspace border."""
    K = a.shape[0]
    ok = np.empty(K, np.bool_)
    seen = np.zeros(box.shape[0], np.int64)
    near = np.empty(box.shape[0], np.int64)
    none_c = np.zeros((0, 3))
    one_c = np.empty((1, 3))
    one_p = np.empty(2, np.int64)
    no_p = np.zeros(1, np.int64)
    for k in range(K):
        ax, ay, bx, by = a[k, 0], a[k, 1], b[k, 0], b[k, 1]
        t = need[k]
        lim = t - 1e-12
        n = _gather(min(ax, bx), min(ay, by), max(ax, bx), max(ay, by), t, gptr, gidx,
                    box, nx, ny, cell, seen, k + 1, near)
        # the border (as segment_clearance measures it)
        good = min(ax, W - ax, ay, H - ay, bx, W - bx, by, H - by) >= lim
        for q in range(n):
            if not good:
                break
            cs, ps = _alone(near[q], circles, vptr, none_c, one_c, one_p, no_p)
            d = segment_clearance(ax, ay, bx, by, cs, verts, ps, W, H)
            good = d >= lim
        ok[k] = good
    return ok


@nb.njit(cache=True)
def grid_points_clearance(pts: np.ndarray, circles: np.ndarray, verts: np.ndarray,
                          vptr: np.ndarray, W: float, H: float, gptr: np.ndarray,
                          gidx: np.ndarray, box: np.ndarray, nx: int, ny: int,
                          cell: float) -> np.ndarray:
    """Exact signed clearance of each point (``points_clearance`` over all obstacles)."""
    K = pts.shape[0]
    out = np.empty(K)
    seen = np.zeros(box.shape[0], np.int64)
    near = np.empty(box.shape[0], np.int64)
    none_c = np.zeros((0, 3))
    one_c = np.empty((1, 3))
    one_p = np.empty(2, np.int64)
    no_p = np.zeros(1, np.int64)
    for k in range(K):
        px, py = pts[k, 0], pts[k, 1]
        n = _gather(px, py, px, py, POINT_REACH, gptr, gidx, box, nx, ny, cell, seen, k + 1,
                    near)
        best = min(px, W - px, py, H - py)
        for q in range(n):
            cs, ps = _alone(near[q], circles, vptr, none_c, one_c, one_p, no_p)
            d = point_clearance(px, py, cs, verts, ps, W, H)
            if d < best:
                best = d
        if best >= POINT_REACH:
            best = point_clearance(px, py, circles, verts, vptr, W, H)
        out[k] = best
    return out
