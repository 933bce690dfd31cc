"""The contact ring of an object shape and its characteristic radius (both cached per shape).

The contact ring is the closed curve where the centre of a robot touching the object lies
(one robot radius plus ``offset`` outside the boundary), sampled evenly by arc length with
the outward push normal at each sample; :func:`characteristic_radius` is the moment scale of
the shape's friction limit surface under uniform pressure. Shapes that cannot be hashed are
computed afresh each call, with the same result.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from lamp.manip.contacts import CONTACT_OFFSET, polygon_vertices, signed_distance
from lamp.scene.model import Circle, Shape


@dataclass(frozen=True)
class Ring:
    """The contact ring of a shape, sampled evenly by arc length (closed curve).

    points: (M, 2) contact positions; normals: (M, 2) outward push normals (from the touched
    boundary point to the contact); boundary: (M, 2) the touched boundary points;
    step: arc length between consecutive samples (m).
    """

    points: np.ndarray
    normals: np.ndarray
    boundary: np.ndarray
    step: float

    def __len__(self) -> int:
        return len(self.points)

    def nearest(self, p: ArrayLike) -> int:
        p = np.asarray(p, dtype=float)
        return int(np.argmin(np.sum((self.points - p) ** 2, axis=1)))

    def walk(self, i: int, distance: float) -> int:
        """Index of the sample ``distance`` metres further along the ring (CCW if > 0)."""
        return int((i + round(distance / self.step)) % len(self))


def _ring_uncached(shape: Shape, offset: float, spacing: float) -> Ring:
    if isinstance(shape, Circle):
        m = max(16, int(np.ceil(2 * np.pi * (shape.radius + offset) / spacing)))
        ang = np.linspace(0.0, 2 * np.pi, m, endpoint=False)
        u = np.stack([np.cos(ang), np.sin(ang)], axis=1)
        return Ring(u * (shape.radius + offset), u, u * shape.radius,
                    2 * np.pi * (shape.radius + offset) / m)
    v = polygon_vertices(shape)
    e = np.roll(v, -1, axis=0) - v
    n = np.stack([e[:, 1], -e[:, 0]], axis=1) / np.hypot(e[:, 0], e[:, 1])[:, None]
    pts, nrm, bnd = [], [], []
    for i in range(len(v)):
        # edge i, then the arc around vertex i+1 from normal i to normal i+1 (convex corners)
        length = float(np.hypot(*e[i]))
        ts = np.linspace(0.0, 1.0, max(2, int(np.ceil(length / (0.25 * spacing)))), endpoint=False)
        b = v[i] + ts[:, None] * e[i]
        pts.append(b + offset * n[i])
        nrm.append(np.repeat(n[i][None], len(ts), axis=0))
        bnd.append(b)
        j = (i + 1) % len(v)
        cross = e[i, 0] * e[j, 1] - e[i, 1] * e[j, 0]
        if cross > 1e-12:
            a0 = np.arctan2(n[i, 1], n[i, 0])
            turn = np.arctan2(cross, float(e[i] @ e[j]))
            angs = a0 + np.linspace(0.0, turn, max(2, int(np.ceil(turn * offset / (0.25 * spacing)))))
            u = np.stack([np.cos(angs), np.sin(angs)], axis=1)
            pts.append(v[j] + offset * u)
            nrm.append(u)
            bnd.append(np.repeat(v[j][None], len(u), axis=0))
    p = np.concatenate(pts)
    nr = np.concatenate(nrm)
    bd = np.concatenate(bnd)
    # drop samples that come too close to another part of a concave outline
    ok = signed_distance(shape, p) >= offset - 1e-6
    p, nr, bd = p[ok], nr[ok], bd[ok]
    # resample evenly by arc length
    seg = np.hypot(*(np.roll(p, -1, axis=0) - p).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    total = cum[-1]
    m = max(16, int(np.ceil(total / spacing)))
    s = np.arange(m) * total / m
    idx = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(p) - 1)
    return Ring(p[idx], nr[idx], bd[idx], total / m)


@lru_cache(maxsize=256)
def _ring_cached(shape: Shape, offset: float, spacing: float) -> Ring:
    return _ring_uncached(shape, offset, spacing)


def contact_ring(shape: Shape, offset: float = CONTACT_OFFSET, spacing: float = 0.004) -> Ring:
    """The contact ring of ``shape`` (cached per shape)."""
    try:
        return _ring_cached(shape, offset, spacing)
    except TypeError:
        return _ring_uncached(shape, offset, spacing)


def _char_radius_uncached(shape: Shape) -> float:
    if isinstance(shape, Circle):
        return 2.0 * shape.radius / 3.0
    v = polygon_vertices(shape)
    lo, hi = v.min(axis=0), v.max(axis=0)
    g = (np.arange(48) + 0.5) / 48
    xs = lo[0] + g * (hi[0] - lo[0])
    ys = lo[1] + g * (hi[1] - lo[1])
    p = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    inside = p[signed_distance(shape, p) <= 0.0]
    if len(inside) == 0:
        return float(np.mean(np.hypot(v[:, 0], v[:, 1])))
    return float(np.mean(np.hypot(inside[:, 0], inside[:, 1])))


@lru_cache(maxsize=256)
def _char_radius_cached(shape: Shape) -> float:
    return _char_radius_uncached(shape)


def characteristic_radius(shape: Shape) -> float:
    """Mean distance of the support area from the centre: the ratio m_max / f_max of the
    friction limit surface under uniform pressure (used to trade force against moment)."""
    try:
        return _char_radius_cached(shape)
    except TypeError:
        return _char_radius_uncached(shape)
