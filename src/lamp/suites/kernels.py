"""Compiled (Numba) exact-clearance and motion-certification kernels behind ``lamp.suites.checks``.

The lattice search and path shortcutting built on them are ``lamp.suites.search_kernels``.

These kernels compute *exact* Euclidean clearances between convex pieces (disks and convex
polygons) and certify straight SE(2) motions by bisection with a Lipschitz bound, so the
suite checks do not depend on a rasterisation. They are deliberately independent of
``lamp.geometry.object_space`` (a conservative distance-grid checker): the suite generator
searches with these kernels and ``checks.verify_route`` re-verifies every route with
``ObjectSpace``, so each implementation is an oracle for the other.

World representation (all float64, C-contiguous):
- ``circ``: (n, 3) obstacle disks ``[cx, cy, r]``;
- ``pv``: (m, V, 2) convex obstacle polygons (world frame, counter-clockwise, padded by
  repeating the last vertex), ``pn``: (m,) vertex counts, ``pb``: (m, 3) bounding circles;
- the workspace border ``[0, W] x [0, H]`` is a wall.
An object is either a disk (``obj_r > 0``, no pieces) or a union of convex polygon pieces
``ov`` (k, V, 2) / ``on`` (k,) in its own frame, with ``obj_reach`` the largest distance of
a vertex from the object origin.

Clearance convention: the distance between the footprint and the nearest obstacle or the
border when they are disjoint; a negative number when they overlap (the magnitude is not
meaningful). Motions are certified with the bound used throughout: on a straight SE(2)
motion every point of the object travels at most ``delta = |dxy| + reach * |dtheta|``, so
every intermediate pose has clearance at least ``min(c_a, c_b) - delta / 2``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from lamp.geometry.kernels import point_segment_distance

BIG = 1.0e9


@numba.njit(cache=True)
def _point_poly_dist(px: float, py: float, v: np.ndarray, n: int) -> float:
    """Signed distance from a point to a convex CCW polygon (negative inside)."""
    inside = True
    best = BIG
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        ax, ay = v[i, 0], v[i, 1]
        bx, by = v[j, 0], v[j, 1]
        if (bx - ax) * (py - ay) - (by - ay) * (px - ax) < 0.0:
            inside = False
        d = point_segment_distance(px, py, ax, ay, bx, by)
        if d < best:
            best = d
    return -best if inside else best


@numba.njit(cache=True)
def _separated(a: np.ndarray, na: int, b: np.ndarray, nb: int) -> bool:
    """Separating-axis test over the edge normals of CCW polygon ``a``."""
    for i in range(na):
        j = i + 1 if i + 1 < na else 0
        ex = a[j, 0] - a[i, 0]
        ey = a[j, 1] - a[i, 1]
        # outward normal of a CCW edge is (ey, -ex); b separated if all its vertices are beyond
        sep = True
        for k in range(nb):
            if ey * (b[k, 0] - a[i, 0]) - ex * (b[k, 1] - a[i, 1]) <= 0.0:
                sep = False
                break
        if sep:
            return True
    return False


@numba.njit(cache=True)
def _poly_poly_dist(a: np.ndarray, na: int, b: np.ndarray, nb: int) -> float:
    """Distance between two convex CCW polygons; -1 when they overlap."""
    if not (_separated(a, na, b, nb) or _separated(b, nb, a, na)):
        return -1.0
    best = BIG
    for i in range(na):
        for j in range(nb):
            k = j + 1 if j + 1 < nb else 0
            d = point_segment_distance(a[i, 0], a[i, 1], b[j, 0], b[j, 1], b[k, 0], b[k, 1])
            if d < best:
                best = d
    for i in range(nb):
        for j in range(na):
            k = j + 1 if j + 1 < na else 0
            d = point_segment_distance(b[i, 0], b[i, 1], a[j, 0], a[j, 1], a[k, 0], a[k, 1])
            if d < best:
                best = d
    return best


@numba.njit(cache=True)
def pose_clearance(
    x: float,
    y: float,
    th: float,
    obj_r: float,
    ov: np.ndarray,
    on: np.ndarray,
    obj_reach: float,
    circ: np.ndarray,
    pv: np.ndarray,
    pn: np.ndarray,
    pb: np.ndarray,
    width: float,
    height: float,
    stop_below: float,
) -> float:
    """Exact clearance of the object at pose (x, y, th); may return early once <= stop_below."""
    if obj_r > 0.0:
        best = min(x - obj_r, width - x - obj_r, y - obj_r, height - y - obj_r)
        if best <= stop_below:
            return best
        for i in range(circ.shape[0]):
            d = math.hypot(circ[i, 0] - x, circ[i, 1] - y) - circ[i, 2] - obj_r
            if d < best:
                best = d
                if best <= stop_below:
                    return best
        for i in range(pv.shape[0]):
            if math.hypot(pb[i, 0] - x, pb[i, 1] - y) - pb[i, 2] - obj_r >= best:
                continue
            d = _point_poly_dist(x, y, pv[i], pn[i]) - obj_r
            if d < best:
                best = d
                if best <= stop_below:
                    return best
        return best
    c = math.cos(th)
    s = math.sin(th)
    kmax = ov.shape[1]
    wv = np.empty((ov.shape[0], kmax, 2))
    best = BIG
    for p in range(ov.shape[0]):
        for i in range(on[p]):
            wx = x + c * ov[p, i, 0] - s * ov[p, i, 1]
            wy = y + s * ov[p, i, 0] + c * ov[p, i, 1]
            wv[p, i, 0] = wx
            wv[p, i, 1] = wy
            d = min(wx, width - wx, wy, height - wy)
            if d < best:
                best = d
    if best <= stop_below:
        return best
    for i in range(circ.shape[0]):
        if math.hypot(circ[i, 0] - x, circ[i, 1] - y) - circ[i, 2] - obj_reach >= best:
            continue
        for p in range(ov.shape[0]):
            d = _point_poly_dist(circ[i, 0], circ[i, 1], wv[p], on[p]) - circ[i, 2]
            if d < best:
                best = d
        if best <= stop_below:
            return best
    for i in range(pv.shape[0]):
        if math.hypot(pb[i, 0] - x, pb[i, 1] - y) - pb[i, 2] - obj_reach >= best:
            continue
        for p in range(ov.shape[0]):
            d = _poly_poly_dist(wv[p], on[p], pv[i], pn[i])
            if d < best:
                best = d
        if best <= stop_below:
            return best
    return best


@numba.njit(cache=True)
def batch_clearance(
    poses: np.ndarray,
    obj_r: float,
    ov: np.ndarray,
    on: np.ndarray,
    obj_reach: float,
    circ: np.ndarray,
    pv: np.ndarray,
    pn: np.ndarray,
    pb: np.ndarray,
    width: float,
    height: float,
) -> np.ndarray:
    """Exact clearance for (M, 3) poses."""
    out = np.empty(poses.shape[0])
    for m in range(poses.shape[0]):
        out[m] = pose_clearance(
            poses[m, 0], poses[m, 1], poses[m, 2], obj_r, ov, on, obj_reach,
            circ, pv, pn, pb, width, height, -BIG,
        )  # fmt: skip
    return out


@numba.njit(cache=True)
def point_clearance(
    points: np.ndarray,
    circ: np.ndarray,
    pv: np.ndarray,
    pn: np.ndarray,
    pb: np.ndarray,
    width: float,
    height: float,
    border: bool = True,
) -> np.ndarray:
    """Exact distance from (M, 2) points to the obstacles and (when ``border``) the
    workspace border (negative inside an obstacle)."""
    out = np.empty(points.shape[0])
    for m in range(points.shape[0]):
        x = points[m, 0]
        y = points[m, 1]
        best = min(x, width - x, y, height - y) if border else BIG
        for i in range(circ.shape[0]):
            d = math.hypot(circ[i, 0] - x, circ[i, 1] - y) - circ[i, 2]
            if d < best:
                best = d
        for i in range(pv.shape[0]):
            if math.hypot(pb[i, 0] - x, pb[i, 1] - y) - pb[i, 2] >= best:
                continue
            d = _point_poly_dist(x, y, pv[i], pn[i])
            if d < best:
                best = d
        out[m] = best
    return out


@numba.njit(cache=True)
def motion_ok(
    a: np.ndarray,
    b: np.ndarray,
    ca: float,
    cb: float,
    tau: float,
    max_depth: int,
    obj_r: float,
    ov: np.ndarray,
    on: np.ndarray,
    obj_reach: float,
    circ: np.ndarray,
    pv: np.ndarray,
    pn: np.ndarray,
    pb: np.ndarray,
    width: float,
    height: float,
) -> bool:
    """Certify that the straight SE(2) motion a -> b (linear in x, y and the *unwrapped*
    theta) keeps clearance >= tau, given the end clearances ca, cb (bisection on the
    Lipschitz bound of the module docstring; unresolved after ``max_depth`` halvings
    counts as not certified)."""
    if ca < tau or cb < tau:
        return False
    dx = b[0] - a[0]
    dy = b[1] - a[1]
    dth = b[2] - a[2]
    delta = math.hypot(dx, dy) + obj_reach * abs(dth)
    # explicit stack of intervals (t0, c0, t1, c1, depth)
    st_t0 = np.empty(max_depth + 2)
    st_c0 = np.empty(max_depth + 2)
    st_t1 = np.empty(max_depth + 2)
    st_c1 = np.empty(max_depth + 2)
    st_d = np.empty(max_depth + 2, dtype=np.int64)
    top = 0
    st_t0[0], st_c0[0], st_t1[0], st_c1[0], st_d[0] = 0.0, ca, 1.0, cb, 0
    while top >= 0:
        t0, c0, t1, c1, d = st_t0[top], st_c0[top], st_t1[top], st_c1[top], st_d[top]
        top -= 1
        if min(c0, c1) - 0.5 * delta * (t1 - t0) >= tau:
            continue
        if d >= max_depth:
            return False
        tm = 0.5 * (t0 + t1)
        cm = pose_clearance(
            a[0] + tm * dx, a[1] + tm * dy, a[2] + tm * dth, obj_r, ov, on, obj_reach,
            circ, pv, pn, pb, width, height, tau,
        )  # fmt: skip
        if cm < tau:
            return False
        top += 1
        st_t0[top], st_c0[top], st_t1[top], st_c1[top], st_d[top] = t0, c0, tm, cm, d + 1
        top += 1
        st_t0[top], st_c0[top], st_t1[top], st_c1[top], st_d[top] = tm, cm, t1, c1, d + 1
    return True
