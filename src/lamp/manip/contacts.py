"""Object-frame contact geometry shared by the geometric proposer, the learned model and checks.

Everything here works in the object's own frame (shape centred on the origin, axes aligned
with the shape), in metres. A *contact* is the position of a robot's centre when it touches
the object: a boundary point pushed out along the outward normal by ``ROBOT_RADIUS +
CONTACT_GAP``. The gap keeps a freshly placed robot from starting in penetration.

Circles are handled exactly; rectangles and polygons through their outline (rectangles are
4-vertex polygons). All functions are vectorised over points.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from lamp.contract.model import MAX_ROBOTS, MOTION_RANGE  # noqa: F401  (re-exported: the model's contract)
from lamp.geometry.shapes import local_outline
from lamp.geometry.team import DEFAULT_TEAM
from lamp.scene.model import Circle, Polygon, Rectangle, Shape, shape_from_dict

ROBOT_RADIUS = DEFAULT_TEAM.radius
"""Robot disk radius (m); the project-wide default (``Scene.robot_radius``)."""
CONTACT_GAP = 0.005
"""Clearance (m) between a robot placed at a contact and the object boundary."""
CONTACT_OFFSET = ROBOT_RADIUS + CONTACT_GAP
"""Distance (m) from the object boundary to a contact (a robot centre)."""
HORIZON = 20
"""Waypoints per push trajectory (GCo's H)."""


def as_shape(shape: Shape | Mapping[str, Any]) -> Shape:
    """Accept a shape object or its dict form (``{"type": "rectangle", "size": [..]}``)."""
    if isinstance(shape, (Circle, Rectangle, Polygon)):
        return shape
    if isinstance(shape, Mapping):
        return shape_from_dict(dict(shape))
    raise ValueError(
        f"shape must be a Circle, Rectangle, Polygon or a shape dict, got {type(shape).__name__}"
    )


def check_budget(budget: int) -> int:
    """Validate a robot budget (1..MAX_ROBOTS)."""
    if isinstance(budget, bool) or int(budget) != budget or not 1 <= int(budget) <= MAX_ROBOTS:
        raise ValueError(f"budget must be an integer in 1..{MAX_ROBOTS}, got {budget!r}")
    return int(budget)


def check_motion(motion: ArrayLike) -> np.ndarray:
    """Validate a requested object motion ``(dx, dy, dtheta)`` (object frame)."""
    m = np.asarray(motion, dtype=float)
    if m.shape != (3,) or not np.all(np.isfinite(m)):
        raise ValueError(f"motion must be three finite numbers (dx, dy, dtheta), got {motion!r}")
    return m


def polygon_vertices(shape: Shape) -> np.ndarray:
    """(V, 2) counter-clockwise vertices of a rectangle or polygon (read-only, cached)."""
    return _segments(shape)[0]


def _segments_uncached(shape: Shape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a = np.ascontiguousarray(local_outline(shape), dtype=float)
    e = np.roll(a, -1, axis=0) - a
    length = np.hypot(e[:, 0], e[:, 1])
    normal = np.stack([e[:, 1], -e[:, 0]], axis=1) / length[:, None]
    for arr in (a, e, normal):
        arr.setflags(write=False)
    return a, e, normal


@lru_cache(maxsize=256)
def _segments_cached(shape: Shape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return _segments_uncached(shape)


def _segments(shape: Shape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Edge start points a, edge vectors e and outward unit normals of a CCW polygon."""
    try:
        return _segments_cached(shape)
    except TypeError:
        return _segments_uncached(shape)


def _closest_on_polygon(shape: Shape, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest boundary point (n, 2), its distance (n,) and the edge index (n,) per point."""
    a, e, _ = _segments(shape)
    rel = p[:, None, :] - a[None, :, :]  # (n, E, 2)
    ee = np.sum(e * e, axis=1)
    t = np.clip(np.einsum("nek,ek->ne", rel, e) / ee[None, :], 0.0, 1.0)
    q = a[None] + t[..., None] * e[None]
    d = np.hypot(p[:, None, 0] - q[..., 0], p[:, None, 1] - q[..., 1])
    idx = np.argmin(d, axis=1)
    rows = np.arange(len(p))
    return q[rows, idx], d[rows, idx], idx


def _inside_polygon(shape: Shape, p: np.ndarray) -> np.ndarray:
    """Even-odd (crossing number) point-in-polygon test, vectorised over points."""
    a, e, _ = _segments(shape)
    b = a + e
    px, py = p[:, 0:1], p[:, 1:2]
    ay, by = a[None, :, 1], b[None, :, 1]
    straddle = (ay > py) != (by > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[None, :, 0] + (py - ay) * (b[None, :, 0] - a[None, :, 0]) / (by - ay)
    crossings = np.sum(straddle & (px < x_cross), axis=1)
    return (crossings % 2) == 1


def signed_distance(shape: Shape, points: ArrayLike) -> np.ndarray:
    """Signed distance from object-frame points to the shape's boundary (negative inside)."""
    p = np.asarray(points, dtype=float)
    flat = p.reshape(-1, 2)
    if isinstance(shape, Circle):
        out = np.hypot(flat[:, 0], flat[:, 1]) - shape.radius
    else:
        _, d, _ = _closest_on_polygon(shape, flat)
        out = np.where(_inside_polygon(shape, flat), -d, d)
    return out.reshape(p.shape[:-1])


def closest_boundary(shape: Shape, points: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Closest boundary point and the outward unit direction there, for each point.

    The direction is the one from the boundary point towards an outside query point (and
    away from an inside one), so ``q + direction * s`` for ``s > 0`` lies outside the shape
    near ``q``; on the boundary itself the edge normal is used.
    """
    p = np.asarray(points, dtype=float)
    flat = p.reshape(-1, 2)
    if isinstance(shape, Circle):
        norm = np.hypot(flat[:, 0], flat[:, 1])
        safe = np.where(norm > 1e-12, norm, 1.0)
        u = np.where((norm > 1e-12)[:, None], flat / safe[:, None], np.array([1.0, 0.0]))
        q = shape.radius * u
    else:
        q, d, idx = _closest_on_polygon(shape, flat)
        _, _, normal = _segments(shape)
        sign = np.where(_inside_polygon(shape, flat), -1.0, 1.0)
        safe = np.where(d > 1e-9, d, 1.0)
        u = np.where((d > 1e-9)[:, None], sign[:, None] * (flat - q) / safe[:, None], normal[idx])
    return q.reshape(p.shape), u.reshape(p.shape)


def project_to_contacts(
    shape: Shape, points: ArrayLike, offset: float = CONTACT_OFFSET
) -> np.ndarray:
    """Move points onto the contact ring: the closest boundary point plus ``offset`` outwards.

    Used to clean up quantised or sampled contacts so that every robot starts touching
    (but not penetrating) the object.
    """
    q, u = closest_boundary(shape, points)
    return q + offset * u


def ray_hit(
    shape: Shape, origin: ArrayLike, direction: ArrayLike
) -> tuple[np.ndarray, np.ndarray] | None:
    """Last crossing of the line ``origin + t * direction`` with the boundary (largest t).

    Returns (boundary point, outward normal there) or None if the line misses the shape.
    For a convex shape and a line through it, this is where the line leaves the shape.
    """
    o = np.asarray(origin, dtype=float)
    d = np.asarray(direction, dtype=float)
    d = d / np.hypot(*d)
    if isinstance(shape, Circle):
        b = float(o @ d)
        c = float(o @ o) - shape.radius**2
        disc = b * b - c
        if disc < 0.0:
            return None
        p = o + (-b + np.sqrt(disc)) * d
        return p, p / shape.radius
    a, e, normal = _segments(shape)
    # solve o + t d = a + s e for (t, s) per edge
    den = d[0] * (-e[:, 1]) - d[1] * (-e[:, 0])
    rel = a - o
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # masked by ``ok``
        t = (rel[:, 0] * (-e[:, 1]) - rel[:, 1] * (-e[:, 0])) / den
        s = (d[0] * rel[:, 1] - d[1] * rel[:, 0]) / den
    ok = (np.abs(den) > 1e-12) & (s >= 0.0) & (s <= 1.0)
    if not np.any(ok):
        return None
    i = int(np.argmax(np.where(ok, t, -np.inf)))
    return o + t[i] * d, normal[i].copy()


def boundary_samples(shape: Shape, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` boundary points evenly spaced by arc length, with outward normals (n, 2) each."""
    if isinstance(shape, Circle):
        ang = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
        u = np.stack([np.cos(ang), np.sin(ang)], axis=1)
        return shape.radius * u, u
    a, e, normal = _segments(shape)
    length = np.hypot(e[:, 0], e[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(length)])
    s = (np.arange(n) + 0.5) * cum[-1] / n
    idx = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(a) - 1)
    frac = (s - cum[idx]) / length[idx]
    return a[idx] + frac[:, None] * e[idx], normal[idx]


def rigid_pushes(
    contacts: ArrayLike, motion: ArrayLike, horizon: int = HORIZON
) -> np.ndarray:
    """Push trajectories that carry each contact rigidly with the object along the motion.

    The object pose follows the linear SE(2) interpolation from the identity to ``motion``
    (object frame of the start pose), so waypoint h of contact c is ``T(s_h) c`` with
    ``s_h = h / (horizon - 1)``. Returns (b, horizon, 2) with ``out[:, 0] == contacts``.
    """
    c = np.asarray(contacts, dtype=float).reshape(-1, 2)
    m = np.asarray(motion, dtype=float)
    s = np.linspace(0.0, 1.0, horizon)
    th = s * m[2]
    cos, sin = np.cos(th), np.sin(th)
    x = s[None, :] * m[0] + cos[None, :] * c[:, 0:1] - sin[None, :] * c[:, 1:2]
    y = s[None, :] * m[1] + sin[None, :] * c[:, 0:1] + cos[None, :] * c[:, 1:2]
    out = np.stack([x, y], axis=-1)
    out[:, 0] = c
    return out


def contacts_valid(
    shape: Shape,
    contacts: ArrayLike,
    robot_radius: float = ROBOT_RADIUS,
    tol: float = 1e-3,
) -> bool:
    """True when no robot at ``contacts`` penetrates the object and robots are >= 2r apart."""
    c = np.asarray(contacts, dtype=float).reshape(-1, 2)
    if np.any(signed_distance(shape, c) < robot_radius - tol):
        return False
    if len(c) > 1:
        d = np.hypot(*(c[:, None, :] - c[None, :, :]).transpose(2, 0, 1))
        d[np.diag_indices(len(c))] = np.inf
        if np.any(d < 2.0 * robot_radius - tol):
            return False
    return True


def rigid_displacements(
    contacts: ArrayLike, motion: ArrayLike, horizon: int = HORIZON
) -> np.ndarray:
    """Batched ``rigid_pushes`` minus the contacts: (..., S, 2) contacts and (..., 3) motions
    -> (..., S, horizon, 2) displacements of each contact carried rigidly with the object
    (zero at waypoint 0; NaN contacts give NaN)."""
    c = np.asarray(contacts, dtype=float)
    m = np.asarray(motion, dtype=float)
    s = np.linspace(0.0, 1.0, horizon)
    th = m[..., None, None, 2] * s  # (..., 1, H)
    cos, sin = np.cos(th), np.sin(th)
    cx, cy = c[..., 0:1], c[..., 1:2]  # (..., S, 1)
    dx = m[..., None, None, 0] * s + (cos - 1.0) * cx - sin * cy
    dy = m[..., None, None, 1] * s + sin * cx + (cos - 1.0) * cy
    return np.stack([dx, dy], axis=-1)
