"""Compiled clearance kernels of :class:`~lamp.geometry.robot_space.RobotSpace` (Numba).

Exact signed distances of points and straight segments to circles, polygons and the
workspace border (a :class:`~lamp.geometry.geometry_set.GeometrySet` in array form), the
clearance grid fill, its conservative lower bound and bilinear reading, and the
breadth-first search for free grid nodes. Conventions as in :mod:`lamp.geometry.robot_space`.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.geometry.kernels import point_segment_distance

__all__ = ["bfs_collect", "bilinear", "fill_field", "lower_bound", "point_clearance",
           "points_clearance", "segment_clearance", "segments_clearance"]


@nb.njit(cache=True)
def _poly_signed_dist(px: float, py: float, verts: np.ndarray, s: int, e: int) -> float:
    """Signed distance from a point to the polygon verts[s:e] (negative inside)."""
    best = np.inf
    inside = False
    n = e - s
    for k in range(n):
        ax = verts[s + k, 0]
        ay = verts[s + k, 1]
        b = s + (k + 1) % n
        bx = verts[b, 0]
        by = verts[b, 1]
        d = point_segment_distance(px, py, ax, ay, bx, by)
        if d < best:
            best = d
        if (ay > py) != (by > py):
            xc = ax + (py - ay) * (bx - ax) / (by - ay)
            if px < xc:
                inside = not inside
    return -best if inside else best


@nb.njit(cache=True)
def point_clearance(
    px: float, py: float, circles: np.ndarray, verts: np.ndarray, ptr: np.ndarray,
    W: float, H: float,
) -> float:
    """Exact signed clearance of a point: obstacles and the workspace border."""
    best = min(px, W - px, py, H - py)
    for c in range(circles.shape[0]):
        dx = px - circles[c, 0]
        dy = py - circles[c, 1]
        d = math.sqrt(dx * dx + dy * dy) - circles[c, 2]
        if d < best:
            best = d
    for q in range(ptr.shape[0] - 1):
        d = _poly_signed_dist(px, py, verts, ptr[q], ptr[q + 1])
        if d < best:
            best = d
    return best


@nb.njit(cache=True)
def points_clearance(
    pts: np.ndarray, circles: np.ndarray, verts: np.ndarray, ptr: np.ndarray, W: float, H: float
) -> np.ndarray:
    out = np.empty(pts.shape[0])
    for k in range(pts.shape[0]):
        out[k] = point_clearance(pts[k, 0], pts[k, 1], circles, verts, ptr, W, H)
    return out


@nb.njit(cache=True, inline="always")
def _orient(ax: float, ay: float, bx: float, by: float, cx: float, cy: float) -> float:
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@nb.njit(cache=True)
def _segs_intersect(
    ax: float, ay: float, bx: float, by: float, cx: float, cy: float, dx: float, dy: float
) -> bool:
    d1 = _orient(cx, cy, dx, dy, ax, ay)
    d2 = _orient(cx, cy, dx, dy, bx, by)
    d3 = _orient(ax, ay, bx, by, cx, cy)
    d4 = _orient(ax, ay, bx, by, dx, dy)
    # proper crossings only: touching / collinear cases are caught by the zero distance
    # of the end-point tests in the caller
    return ((d1 > 0.0 and d2 < 0.0) or (d1 < 0.0 and d2 > 0.0)) and (
        (d3 > 0.0 and d4 < 0.0) or (d3 < 0.0 and d4 > 0.0)
    )


@nb.njit(cache=True)
def segment_clearance(
    ax: float, ay: float, bx: float, by: float,
    circles: np.ndarray, verts: np.ndarray, ptr: np.ndarray, W: float, H: float,
) -> float:
    """Minimum clearance along the segment a-b (exact when positive).

    A value <= 0 means that the segment touches or enters an obstacle or leaves the
    workspace (its magnitude is then not the penetration depth).
    """
    # border: min(x, W-x, y, H-y) is concave along a segment -> minimum at an end point
    best = min(ax, W - ax, ay, H - ay, bx, W - bx, by, H - by)
    for c in range(circles.shape[0]):
        d = point_segment_distance(circles[c, 0], circles[c, 1], ax, ay, bx, by) - circles[c, 2]
        if d < best:
            best = d
    for q in range(ptr.shape[0] - 1):
        s = ptr[q]
        e = ptr[q + 1]
        da = _poly_signed_dist(ax, ay, verts, s, e)
        if da <= 0.0:
            return min(best, da)
        db = _poly_signed_dist(bx, by, verts, s, e)
        if db <= 0.0:
            return min(best, db)
        n = e - s
        dmin = min(da, db)
        for k in range(n):
            cx = verts[s + k, 0]
            cy = verts[s + k, 1]
            m = s + (k + 1) % n
            dx = verts[m, 0]
            dy = verts[m, 1]
            if _segs_intersect(ax, ay, bx, by, cx, cy, dx, dy):
                return min(best, 0.0)
            d = point_segment_distance(cx, cy, ax, ay, bx, by)
            if d < dmin:
                dmin = d
        if dmin < best:
            best = dmin
    return best


@nb.njit(cache=True)
def segments_clearance(
    a: np.ndarray, b: np.ndarray, circles: np.ndarray, verts: np.ndarray, ptr: np.ndarray,
    W: float, H: float,
) -> np.ndarray:
    out = np.empty(a.shape[0])
    for k in range(a.shape[0]):
        out[k] = segment_clearance(
            a[k, 0], a[k, 1], b[k, 0], b[k, 1], circles, verts, ptr, W, H
        )
    return out


@nb.njit(cache=True)
def fill_field(
    field: np.ndarray, h: float, cap: float,
    circles: np.ndarray, verts: np.ndarray, ptr: np.ndarray, i_off: int, j_off: int,
) -> None:
    """field = min(field, exact signed distance to each obstacle) inside a window of
    ``cap`` around the obstacle (outside it the obstacle is at least ``cap`` away).

    ``field[j, i]`` holds grid node ``(i + i_off, j + j_off)`` at ``((i + i_off) * h,
    (j + j_off) * h)``: a window of the workspace grid gets, bit for bit, the values the
    same nodes of the whole grid get."""
    ny, nx = field.shape
    for c in range(circles.shape[0]):
        cx = circles[c, 0]
        cy = circles[c, 1]
        ext = circles[c, 2] + cap
        i0 = max(0, int(math.floor((cx - ext) / h)) - i_off)
        i1 = min(nx - 1, int(math.ceil((cx + ext) / h)) - i_off)
        j0 = max(0, int(math.floor((cy - ext) / h)) - j_off)
        j1 = min(ny - 1, int(math.ceil((cy + ext) / h)) - j_off)
        for j in range(j0, j1 + 1):
            dy = (j + j_off) * h - cy
            for i in range(i0, i1 + 1):
                dx = (i + i_off) * h - cx
                d = math.sqrt(dx * dx + dy * dy) - circles[c, 2]
                if d < field[j, i]:
                    field[j, i] = d
    for q in range(ptr.shape[0] - 1):
        s = ptr[q]
        e = ptr[q + 1]
        xmin = verts[s, 0]
        xmax = xmin
        ymin = verts[s, 1]
        ymax = ymin
        for k in range(s, e):
            xmin = min(xmin, verts[k, 0])
            xmax = max(xmax, verts[k, 0])
            ymin = min(ymin, verts[k, 1])
            ymax = max(ymax, verts[k, 1])
        i0 = max(0, int(math.floor((xmin - cap) / h)) - i_off)
        i1 = min(nx - 1, int(math.ceil((xmax + cap) / h)) - i_off)
        j0 = max(0, int(math.floor((ymin - cap) / h)) - j_off)
        j1 = min(ny - 1, int(math.ceil((ymax + cap) / h)) - j_off)
        for j in range(j0, j1 + 1):
            for i in range(i0, i1 + 1):
                d = _poly_signed_dist((i + i_off) * h, (j + j_off) * h, verts, s, e)
                if d < field[j, i]:
                    field[j, i] = d


@nb.njit(cache=True)
def lower_bound(pts: np.ndarray, field: np.ndarray, h: float, i_off: int, j_off: int,
                NX: int, NY: int) -> np.ndarray:
    """Lipschitz lower bound on clearance: max over the cell's 4 nodes of f(c) - |p - c|.

    The workspace grid has NX x NY nodes; ``field`` holds its window of nodes from
    ``(i_off, j_off)`` on. Each node term is a lower bound by itself, so nodes outside the
    window are left out; points outside the workspace, or whose cell has no node in the
    window, get -inf. With the whole grid (offsets 0) this is the plain bound."""
    ny, nx = field.shape
    out = np.empty(pts.shape[0])
    for k in range(pts.shape[0]):
        x = pts[k, 0] / h
        y = pts[k, 1] / h
        if not (x >= 0.0 and y >= 0.0 and x <= NX - 1 and y <= NY - 1):
            out[k] = -np.inf
            continue
        i = min(int(x), NX - 2) if NX > 1 else 0
        j = min(int(y), NY - 2) if NY > 1 else 0
        best = -np.inf
        for dj in range(2):
            for di in range(2):
                ii = min(i + di, NX - 1)
                jj = min(j + dj, NY - 1)
                li = ii - i_off
                lj = jj - j_off
                if li < 0 or lj < 0 or li >= nx or lj >= ny:
                    continue
                ex = (x - ii) * h
                ey = (y - jj) * h
                v = field[lj, li] - math.sqrt(ex * ex + ey * ey)
                if v > best:
                    best = v
        out[k] = best
    return out


@nb.njit(cache=True)
def bilinear(pts: np.ndarray, field: np.ndarray, h: float, i_off: int, j_off: int,
             NX: int, NY: int) -> np.ndarray:
    """Bilinear reading of the grid (window convention of :func:`lower_bound`); -inf
    outside the workspace or where a node of the cell lies outside the window."""
    ny, nx = field.shape
    out = np.empty(pts.shape[0])
    for k in range(pts.shape[0]):
        x = pts[k, 0] / h
        y = pts[k, 1] / h
        if not (x >= 0.0 and y >= 0.0 and x <= NX - 1 and y <= NY - 1):
            out[k] = -np.inf
            continue
        i = min(int(x), NX - 2)
        j = min(int(y), NY - 2)
        li = i - i_off
        lj = j - j_off
        if li < 0 or lj < 0 or li + 1 >= nx or lj + 1 >= ny:
            out[k] = -np.inf
            continue
        fx = x - i
        fy = y - j
        out[k] = (
            (1 - fx) * (1 - fy) * field[lj, li]
            + fx * (1 - fy) * field[lj, li + 1]
            + (1 - fx) * fy * field[lj + 1, li]
            + fx * fy * field[lj + 1, li + 1]
        )
    return out


@nb.njit(cache=True)
def bfs_collect(
    ok: np.ndarray, reach: np.ndarray, si: int, sj: int, max_depth: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """8-connected BFS over grid nodes from (si, sj) through ``reach`` nodes (the start
    node always counts as reached), up to ``max_depth`` hops. Returns the ``ok`` nodes met,
    in BFS order, as (i, j, depth) arrays."""
    ny, nx = ok.shape
    r0 = max(0, sj - max_depth)
    r1 = min(ny - 1, sj + max_depth)
    c0 = max(0, si - max_depth)
    c1 = min(nx - 1, si + max_depth)
    h_ = r1 - r0 + 1
    w_ = c1 - c0 + 1
    depth = np.full((h_, w_), -1, dtype=np.int32)
    qi = np.empty(h_ * w_, dtype=np.int32)
    qj = np.empty(h_ * w_, dtype=np.int32)
    oi = np.empty(h_ * w_, dtype=np.int32)
    oj = np.empty(h_ * w_, dtype=np.int32)
    od = np.empty(h_ * w_, dtype=np.int32)
    n_ok = 0
    head = 0
    tail = 1
    qi[0] = si
    qj[0] = sj
    depth[sj - r0, si - c0] = 0
    while head < tail:
        i = qi[head]
        j = qj[head]
        head += 1
        dep = depth[j - r0, i - c0]
        if ok[j, i]:
            oi[n_ok] = i
            oj[n_ok] = j
            od[n_ok] = dep
            n_ok += 1
        if dep >= max_depth:
            continue
        for dj in range(-1, 2):
            for di in range(-1, 2):
                if di == 0 and dj == 0:
                    continue
                ii = i + di
                jj = j + dj
                if ii < c0 or jj < r0 or ii > c1 or jj > r1:
                    continue
                if depth[jj - r0, ii - c0] >= 0 or not reach[jj, ii]:
                    continue
                depth[jj - r0, ii - c0] = dep + 1
                qi[tail] = ii
                qj[tail] = jj
                tail += 1
    return oi[:n_ok], oj[:n_ok], od[:n_ok]
