"""SE(2) poses ``(x, y, theta)``: composition, inverse, angle wrapping, interpolation.

All functions accept a single pose of shape (3,) or a batch (..., 3) and broadcast.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def wrap_angle(theta: ArrayLike) -> np.ndarray | float:
    """Wrap angles to [-pi, pi)."""
    out = (np.asarray(theta, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi
    return float(out) if out.ndim == 0 else out


def compose(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """``a * b``: the pose ``b`` (expressed in frame ``a``) mapped to the world."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    y = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    th = wrap_angle(a[..., 2] + b[..., 2])
    return np.stack(np.broadcast_arrays(x, y, th), axis=-1)


def inverse(a: ArrayLike) -> np.ndarray:
    """``a^-1`` so that ``compose(a, inverse(a)) == identity``."""
    a = np.asarray(a, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = -(c * a[..., 0] + s * a[..., 1])
    y = -(-s * a[..., 0] + c * a[..., 1])
    return np.stack([x, y, wrap_angle(-a[..., 2])], axis=-1)


def relative(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """``a^-1 * b``: pose ``b`` expressed in the frame of ``a`` (the motion from a to b)."""
    return compose(inverse(a), b)


def transform_points(pose: ArrayLike, points: ArrayLike) -> np.ndarray:
    """Map (..., 2) points from the frame ``pose`` to the world."""
    pose = np.asarray(pose, dtype=float)
    p = np.asarray(points, dtype=float)
    c, s = np.cos(pose[2]), np.sin(pose[2])
    out = np.empty(p.shape, dtype=float)
    out[..., 0] = pose[0] + c * p[..., 0] - s * p[..., 1]
    out[..., 1] = pose[1] + s * p[..., 0] + c * p[..., 1]
    return out


def inverse_transform_points(pose: ArrayLike, points: ArrayLike) -> np.ndarray:
    """Map (..., 2) world points into the frame ``pose``."""
    pose = np.asarray(pose, dtype=float)
    p = np.asarray(points, dtype=float)
    c, s = np.cos(pose[2]), np.sin(pose[2])
    dx = p[..., 0] - pose[0]
    dy = p[..., 1] - pose[1]
    out = np.empty(p.shape, dtype=float)
    out[..., 0] = c * dx + s * dy
    out[..., 1] = -s * dx + c * dy
    return out


def interpolate(a: ArrayLike, b: ArrayLike, t: ArrayLike) -> np.ndarray:
    """Poses along the straight line from ``a`` to ``b`` (shortest rotation), t in [0, 1].

    Translation and rotation are interpolated independently (the linear SE(2) blend
    used for object motion primitives). ``t`` may be a vector: the result is (len(t), 3).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    t = np.asarray(t, dtype=float)[..., None]
    d = b - a
    d[..., 2] = wrap_angle(d[..., 2])
    out = a + t * d
    out[..., 2] = wrap_angle(out[..., 2])
    return out


def pose_distance(a: ArrayLike, b: ArrayLike) -> tuple[np.ndarray | float, np.ndarray | float]:
    """(translation distance, absolute wrapped angle difference) between poses."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    dt = np.hypot(b[..., 0] - a[..., 0], b[..., 1] - a[..., 1])
    dr = np.abs(wrap_angle(b[..., 2] - a[..., 2]))
    return dt, dr
