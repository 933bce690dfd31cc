"""Object poses off the lattice for narrow passages: corridor centrelines, aligned headings.

The object lattice (0.1 m, 16 headings) cannot pass a corridor only a few centimetres wider
than the object unless the corridor happens to lie on it: the object must be centred to
within a centimetre and aligned to within a degree or two. ``narrow_poses`` finds such
passages and returns poses that pass them; ``RefinedLattice`` adds them to the search.

1. **Clearance raster.** Over a window of the map, the obstacles (and everything outside
   the workspace) are rasterised on ``raster`` cells and a Euclidean distance transform
   gives each cell's clearance ``c``.
2. **Ridges.** A cell lies on a ridge of the clearance (the medial axis) where the
   gradient of ``c`` is short: a distance field's gradient has length 1 except where two
   walls are equally near (``ridge_mask``). The ridge is *narrow* where the object only
   just fits: half the passage's width ``c`` lies between half the object's narrowest extent (less a cell) and
   half its widest hull-aligned extent plus ``slack``.
3. **Samples.** Narrow ridge cells are thinned to points at least ``spacing`` apart (in
   raster order, deterministic); the local corridor direction ``phi`` at a point is the
   weakest axis of the clearance gradients' structure tensor around it (the gradients
   point away from the walls on both sides, across the corridor).
4. **Aligned poses.** For each point, each heading that lays an edge of the object's convex
   hull along ``phi`` (a rectangle: 4 headings; a circle, which fits at any heading: the
   lattice's own headings when given, so that it need not turn in the corridor, else
   ``CIRCLE_HEADINGS``, ``phi`` and every 45 degrees from it) gives a pose, shifted
   across the corridor so that the object's extent across it is centred on the ridge and
   nudged by up to one raster cell more if needed. A pose is kept when the exact checker
   (``ExactSpace``) finds it free.
5. **Extensions.** Where a chain of aligned poses ends (no pose of the same heading ahead
   along ``phi``), poses continue straight along ``phi`` for up to twice the object's reach
   plus ``extension`` while free, so that the whole object leaves the corridor before it
   turns (the ridge may end well inside the corridor's mouth).

Guarantee: every returned pose is free by ``ExactSpace.pose_free``. Nothing is promised
about completeness: the poses are candidates, connected by checked motions in
``lamp.search.refined_lattice``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from scipy import ndimage
from scipy.spatial import cKDTree

from lamp.geometry.exact_space import ExactSpace
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.primitives import Circle
from lamp.geometry.shapes import local_outline, obstacle_geometry

#: Headings (evenly spaced) given to a circle's poses.
CIRCLE_HEADINGS = 8


@dataclass(frozen=True)
class NarrowParams:
    """Settings of :func:`narrow_poses` (metres)."""

    raster: float = 0.01
    #: ridge clearance above the object's inscribed radius still counted as narrow
    slack: float = 0.08
    spacing: float = 0.08
    #: the raster is coarsened so that a window never has more cells than this
    max_cells: int = 2_000_000
    #: how far beyond twice the object's reach a chain of aligned poses is extended
    extension: float = 0.3
    #: radius of the ridge neighbourhood that gives a point's corridor direction
    direction_radius: float = 0.12

    def __post_init__(self) -> None:
        for name in ("raster", "slack", "spacing", "extension", "direction_radius"):
            v = getattr(self, name)
            if not (v > 0 and math.isfinite(v)):
                raise ValueError(f"NarrowParams.{name} must be finite and > 0, got {v!r}")
        if self.max_cells < 1000:
            raise ValueError(f"NarrowParams.max_cells must be >= 1000, got {self.max_cells!r}")


def aligned_headings(shape: object, phi: float,
                     circle_headings: Sequence[float] | None = None,
                     ) -> list[tuple[float, float, float]]:
    """``(theta, shift, width)`` for each heading that lays a convex-hull edge of ``shape``
    along direction ``phi``: ``width`` is the object's extent across ``phi`` and ``shift``
    the offset (along the normal of ``phi``) that centres that extent on the object's
    position line; narrowest first.

    A circle fits at every heading: it gets ``circle_headings`` (the lattice's own heading
    set, so that it passes the corridor without turning), or else ``CIRCLE_HEADINGS``
    headings evenly spaced from ``phi``."""
    if isinstance(shape, Circle):
        w = 2.0 * float(shape.radius)
        if circle_headings is None:
            circle_headings = [phi + k * 2.0 * math.pi / CIRCLE_HEADINGS
                               for k in range(CIRCLE_HEADINGS)]
        return [(math.remainder(float(t), 2.0 * math.pi), 0.0, w) for t in circle_headings]
    pts = local_outline(shape)
    hull = np.asarray(shapely.MultiPoint(pts).convex_hull.exterior.coords)[:-1]
    edges = np.roll(hull, -1, axis=0) - hull
    alphas = np.arctan2(edges[:, 1], edges[:, 0])
    out: list[tuple[float, float, float]] = []
    n = np.array([-math.sin(phi), math.cos(phi)])
    for alpha in alphas:
        for flip in (0.0, math.pi):
            theta = math.remainder(phi - alpha + flip, 2.0 * math.pi)
            if any(abs(math.remainder(theta - t, 2.0 * math.pi)) < 1e-3 for t, _, _ in out):
                continue
            c, s = math.cos(theta), math.sin(theta)
            world = pts @ np.array([[c, s], [-s, c]])
            across = world @ n
            lo, hi = float(across.min()), float(across.max())
            out.append((theta, -0.5 * (lo + hi), hi - lo))
    out.sort(key=lambda r: (round(r[2], 9), r[0]))
    return out


def clearance_raster(space: ObjectSpace, window: tuple[float, float, float, float],
                     raster: float) -> tuple[np.ndarray, float, float]:
    """(rows, cols) clearance of cell centres over ``window`` = (x0, y0, x1, y1), with the
    window's lower-left corner: ``(c, x0, y0)``; cell (r, k) is centred at
    ``(x0 + (k + 0.5) raster, y0 + (r + 0.5) raster)``."""
    x0, y0, x1, y1 = window
    nx = max(1, math.ceil((x1 - x0) / raster))
    ny = max(1, math.ceil((y1 - y0) / raster))
    xs = x0 + (np.arange(nx) + 0.5) * raster
    ys = y0 + (np.arange(ny) + 0.5) * raster
    gx, gy = np.meshgrid(xs, ys)
    w, h = space.workspace
    occ = (gx <= 0) | (gx >= w) | (gy <= 0) | (gy >= h)
    box = shapely.box(x0 - raster, y0 - raster, x1 + raster, y1 + raster)
    geoms = [g for g in (obstacle_geometry(o) for o in space.obstacles) if g.intersects(box)]
    if geoms:
        union = shapely.union_all(geoms).intersection(box)
        shapely.prepare(union)
        occ |= shapely.contains_xy(union, gx, gy)
    # the workspace border outside the window still counts: pad with its cells
    c = ndimage.distance_transform_edt(~occ) * raster
    border = np.minimum(np.minimum(gx, w - gx), np.minimum(gy, h - gy))
    return np.minimum(c, border), x0, y0


#: A clearance gradient shorter than this marks the medial axis (it is 1 elsewhere).
RIDGE_GRADIENT = 0.75


def ridge_mask(c: np.ndarray, lo: float, hi: float, raster: float) -> np.ndarray:
    """Cells on the medial axis of the free space with ``lo <= c <= hi``: where the
    clearance's central-difference gradient is shorter than ``RIDGE_GRADIENT`` (a distance
    field has gradient length 1 except where two walls are equally near)."""
    gy, gx = np.gradient(c, raster)
    return (np.hypot(gx, gy) < RIDGE_GRADIENT) & (c >= lo) & (c <= hi)


def _thin(points: np.ndarray, spacing: float) -> np.ndarray:
    """Indices of a subset of ``points`` at least ``spacing`` apart (greedy, in order)."""
    cells: dict[tuple[int, int], list[int]] = {}
    keep: list[int] = []
    for i, (x, y) in enumerate(points):
        cx, cy = int(math.floor(x / spacing)), int(math.floor(y / spacing))
        near = False
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for j in cells.get((cx + dx, cy + dy), ()):
                    if (points[j, 0] - x) ** 2 + (points[j, 1] - y) ** 2 < spacing * spacing:
                        near = True
                        break
                if near:
                    break
            if near:
                break
        if not near:
            cells.setdefault((cx, cy), []).append(i)
            keep.append(i)
    return np.asarray(keep, dtype=np.int64)


def narrow_poses(space: ObjectSpace, exact: ExactSpace,
                 window: tuple[float, float, float, float],
                 params: NarrowParams | None = None,
                 circle_headings: Sequence[float] | None = None) -> np.ndarray:
    """(M, 3) free poses through the narrow passages inside ``window`` (module docstring);
    ``circle_headings`` as in ``aligned_headings``."""
    params = params or NarrowParams()
    x0, y0, x1, y1 = window
    area = max(x1 - x0, 1e-9) * max(y1 - y0, 1e-9)
    raster = max(params.raster, math.sqrt(area / params.max_cells))
    c, ox, oy = clearance_raster(space, window, raster)
    widths = [w for _, _, w in aligned_headings(space.shape, 0.0)]
    lo = 0.5 * min(widths) + space.inflation
    mask = ridge_mask(c, lo - raster, 0.5 * max(widths) + space.inflation + params.slack, raster)
    rows, cols = np.nonzero(mask)
    if len(rows) == 0:
        return np.zeros((0, 3))
    cells = np.stack([ox + (cols + 0.5) * raster, oy + (rows + 0.5) * raster], axis=1)
    picked = cells[_thin(cells, params.spacing)]
    poses: list[np.ndarray] = []
    dirs: list[float] = []
    nudges = raster * np.array([0.0, 0.5, -0.5, 1.0, -1.0])
    radius = max(params.direction_radius, 0.5 * exact.reach)
    gy, gx = np.gradient(c, raster)
    half = max(1, int(round(radius / raster)))
    for p in picked:
        # the corridor runs across the clearance gradient (walls on both sides): the
        # direction is the structure tensor's weakest axis over the neighbourhood
        k0 = int((p[0] - ox) / raster)
        r0 = int((p[1] - oy) / raster)
        win = (slice(max(0, r0 - half), r0 + half + 1), slice(max(0, k0 - half), k0 + half + 1))
        ax, ay = gx[win].ravel(), gy[win].ravel()
        tensor = np.array([[ax @ ax, ax @ ay], [ax @ ay, ay @ ay]])
        evals, evecs = np.linalg.eigh(tensor)
        if evals[1] <= 0.0:
            continue
        u = evecs[:, 0]
        phi = math.atan2(u[1], u[0])
        n = np.array([-u[1], u[0]])
        for theta, shift, _ in aligned_headings(space.shape, phi, circle_headings):
            for nudge in nudges:
                xy = p + (shift + nudge) * n
                pose = np.array([xy[0], xy[1], theta])
                if exact.pose_free(pose):
                    poses.append(_centre(exact, pose, n, raster))
                    dirs.append(phi)
                    break
    if not poses:
        return np.zeros((0, 3))
    base = np.array(poses)
    return np.concatenate([base, _extensions(base, np.array(dirs), exact, params, raster)])


#: Heading steps (rad) of ``_centre``'s coordinate ascent, coarse to fine; the lateral
#: steps are these fractions of a raster cell.
_CENTRE_TURNS = np.deg2rad([1.0, 0.5, 0.25, 0.1, 0.05])
_CENTRE_SHIFTS = np.array([1.0, 0.5, 0.25, 0.12, 0.06])
#: Poses with at least this clearance (m) are not centred any further.
_CENTRED_ENOUGH = 0.02


def _centre(exact: ExactSpace, pose: np.ndarray, n: np.ndarray, raster: float) -> np.ndarray:
    """``pose`` turned and moved across the corridor (along ``n``) to a local maximum of
    the exact clearance (coordinate ascent, coarse to fine steps), unless it already has
    ``_CENTRED_ENOUGH``: a free pose stays free, and neighbouring poses end up aligned and
    centred, so the motions between them keep clearance too."""
    best, c = pose.copy(), exact.clearance(pose)
    if c >= _CENTRED_ENOUGH:
        return best
    for turn, shift in zip(_CENTRE_TURNS, _CENTRE_SHIFTS, strict=True):
        for sign in (1.0, -1.0):
            q = best.copy()
            q[2] = math.remainder(q[2] + sign * turn, 2.0 * math.pi)
            cq = exact.clearance(q)
            if cq > c:
                c, best = cq, q
                break
        for sign in (1.0, -1.0):
            q = best.copy()
            q[:2] += sign * shift * raster * n
            cq = exact.clearance(q)
            if cq > c:
                c, best = cq, q
                break
    return best


def _extensions(poses: np.ndarray, dirs: np.ndarray, exact: ExactSpace,
                params: NarrowParams, raster: float) -> np.ndarray:
    """Straight continuations of the chains of aligned poses beyond their ends, along the
    chain's own axis (the line through its last poses), re-centred at every step."""
    out: list[np.ndarray] = []
    tree = cKDTree(poses[:, :2])
    reach = 2.0 * exact.reach + params.extension  # the whole object out of the corridor
    steps = max(1, math.ceil(reach / params.spacing))
    for i, (pose, phi) in enumerate(zip(poses, dirs, strict=True)):
        same = [j for j in tree.query_ball_point(pose[:2], 0.5) if
                abs(math.remainder(poses[j, 2] - pose[2], 2.0 * math.pi)) < 0.05]
        u = np.array([math.cos(phi), math.sin(phi)])
        if len(same) >= 3:
            pts = poses[same, :2]
            axis = np.linalg.eigh(np.cov((pts - pts.mean(axis=0)).T))[1][:, 1]
            u = axis if axis @ u >= 0 else -axis
        n = np.array([-u[1], u[0]])
        for sign in (1.0, -1.0):
            ahead = [j for j in same if j != i and 0.3 * params.spacing
                     < sign * float((poses[j, :2] - pose[:2]) @ u) < 1.5 * params.spacing]
            if ahead:
                continue
            q = pose.copy()
            for _ in range(steps):
                q = q.copy()
                q[:2] += sign * params.spacing * u
                q = _centre(exact, q, n, raster)
                if not exact.pose_free(q):
                    break
                out.append(q)
    return np.array(out).reshape(-1, 3)
