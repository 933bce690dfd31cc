"""Object masks: the model's view of an object (binary top-down image, object-centred).

The image covers ``IMAGE_EXTENT`` x ``IMAGE_EXTENT`` metres centred on the object's origin
and aligned with the object's own axes (GCo: 128 px over 1.0 m; we use 64 px, 15.6 mm/px,
a coarser grid that makes the CNN ~4x cheaper). Pixel ``[i, j]`` (row i,
column j) covers the square centred at ``x = -E/2 + (j + 0.5) E/S``,
``y = -E/2 + (i + 0.5) E/S``: rows grow with +y (no display flip). Each pixel holds the
fraction of ``SUPERSAMPLE**2`` sub-pixel samples inside the shape, so edges are
anti-aliased and sizes are resolved below one pixel; the interior is 1, the outside 0.
Parts of a shape beyond the image are cut off; the learned model therefore sees objects
wider than its training data scaled down (``lamp.manip.scaling``).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from lamp.manip.contacts import signed_distance
from lamp.scene.model import Circle, Rectangle, Shape

IMAGE_SIZE = 64
IMAGE_EXTENT = 1.0
SUPERSAMPLE = 4


def _subpixel_coords(size: int, extent: float, supersample: int) -> np.ndarray:
    """(size * supersample,) sub-pixel sample coordinates along one axis."""
    n = size * supersample
    return -0.5 * extent + (np.arange(n) + 0.5) * extent / n


def _pool(inside: np.ndarray, size: int, supersample: int) -> np.ndarray:
    """Average (..., n, n) sub-pixel samples into (..., size, size) pixels."""
    lead = inside.shape[:-2]
    x = inside.reshape(*lead, size, supersample, size, supersample)
    return x.mean(axis=(-3, -1), dtype=np.float32)


def _image_uncached(shape: Shape, size: int, extent: float, supersample: int) -> np.ndarray:
    g = _subpixel_coords(size, extent, supersample)
    xx, yy = np.meshgrid(g, g)  # rows: y, columns: x
    if isinstance(shape, Circle):
        inside = xx**2 + yy**2 <= shape.radius**2
    elif isinstance(shape, Rectangle):
        inside = (np.abs(xx) <= 0.5 * shape.size[0]) & (np.abs(yy) <= 0.5 * shape.size[1])
    else:
        pts = np.stack([xx, yy], axis=-1)
        inside = signed_distance(shape, pts) <= 0.0
    img = _pool(inside, size, supersample)
    img.setflags(write=False)
    return img


@lru_cache(maxsize=512)
def _image_cached(shape: Shape, size: int, extent: float, supersample: int) -> np.ndarray:
    return _image_uncached(shape, size, extent, supersample)


def object_image(
    shape: Shape,
    size: int = IMAGE_SIZE,
    extent: float = IMAGE_EXTENT,
    supersample: int = SUPERSAMPLE,
) -> np.ndarray:
    """(size, size) float32 mask of ``shape`` in its own frame (cached per shape, read-only)."""
    if size < 1 or extent <= 0 or supersample < 1:
        raise ValueError(
            f"object_image: size, extent and supersample must be positive, got "
            f"{size!r}, {extent!r}, {supersample!r}"
        )
    try:
        return _image_cached(shape, size, extent, supersample)
    except TypeError:  # unhashable shape fields
        return _image_uncached(shape, size, extent, supersample)


def batch_images(
    kind: np.ndarray,
    params: np.ndarray,
    size: int = IMAGE_SIZE,
    extent: float = IMAGE_EXTENT,
    supersample: int = SUPERSAMPLE,
) -> np.ndarray:
    """(B, size, size) masks of circles (kind 0, params (r, r)) and rectangles (kind 1,
    params (sx, sy)) in one vectorised pass; equal to ``object_image`` of each shape.

    Rectangles are separable, so each pixel's coverage is the product of per-axis sub-sample
    counts; circles use the sub-pixel samples directly.
    """
    kind = np.asarray(kind)
    params = np.asarray(params, dtype=float)
    g = _subpixel_coords(size, extent, supersample)
    out = np.empty((len(kind), size, size), dtype=np.float32)
    rect = kind == 1
    if rect.any():
        ix = (np.abs(g)[None, :] <= 0.5 * params[rect, 0:1]).reshape(-1, size, supersample)
        iy = (np.abs(g)[None, :] <= 0.5 * params[rect, 1:2]).reshape(-1, size, supersample)
        fx = ix.mean(axis=2, dtype=np.float32)  # (R, size) coverage along x per column
        fy = iy.mean(axis=2, dtype=np.float32)  # along y per row
        out[rect] = fy[:, :, None] * fx[:, None, :]
    circ = ~rect
    if circ.any():
        r2 = g[None, :] ** 2 + g[:, None] ** 2
        inside = r2[None] <= (params[circ, 0] ** 2)[:, None, None]
        out[circ] = _pool(inside, size, supersample)
    return out
