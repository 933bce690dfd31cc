"""Scale-aware use of the learned model: how big an object is, and how far to shrink it.

The learned model sees an object through a fixed window (``lamp.manip.image``: an
``IMAGE_EXTENT`` square centred on the object) and places contacts on a grid of the same
size (``lamp.manip.flow``), and it was trained on rectangles up to ``TRAINED_EXTENT`` and
circles up to ``TRAINED_CIRCLE_EXTENT`` across (``lamp.manip.dataset``; ``trained_extent``).
A larger object (a 1.5 m bar, a 1.2 m L) would be clipped and its ends unreachable, so ``FlowProposer`` proposes for the object scaled down about its
origin by ``s = model_scale(shape) < 1``, with the requested translation scaled by the same
``s`` (the rotation is scale-free), and maps the result back (contacts and generated
residuals divided by ``s``). These helpers are the geometry of that mapping; the mapping
itself lives in ``FlowProposer.sample``.

Quasi-statically the mapping is consistent: scaling an object, its contacts and the
translation by the same factor keeps the ratio of translation to rotation times the
radius of gyration, which is what decides which contact forces produce the motion.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry.shapes import local_outline
from lamp.manip.dataset import TRAINED_CIRCLE_EXTENT, TRAINED_EXTENT
from lamp.scene.model import Circle, Polygon, Rectangle, Shape

__all__ = ["model_scale", "scale_motions", "scale_shape", "shape_extent", "trained_extent"]


def shape_extent(shape: Shape) -> float:
    """Side (m) of the smallest square centred on the object's origin and aligned with its
    own axes that holds the object: ``2 max(|x|, |y|)`` over its outline (circles: 2r).

    It is what the model's image and contact grid, both such squares, must cover.
    """
    if isinstance(shape, Circle):
        return 2.0 * float(shape.radius)
    return 2.0 * float(np.max(np.abs(local_outline(shape))))


def trained_extent(shape: Shape) -> float:
    """The largest extent (m) of the training objects of ``shape``'s kind: circles
    ``TRAINED_CIRCLE_EXTENT``, rectangles ``TRAINED_EXTENT`` (polygons, which training
    never had, are held to the rectangles' bound)."""
    return TRAINED_CIRCLE_EXTENT if isinstance(shape, Circle) else TRAINED_EXTENT


def model_scale(shape: Shape, max_extent: float | None = None) -> float:
    """The factor ``s`` in (0, 1] the model sees ``shape`` scaled by: exactly 1.0 when the
    object's extent is at most ``max_extent`` (default: ``trained_extent(shape)``), else
    ``max_extent / extent`` (the scaled object is then exactly ``max_extent`` across)."""
    if max_extent is None:
        max_extent = trained_extent(shape)
    if not max_extent > 0:
        raise ValueError(f"max_extent must be > 0, got {max_extent!r}")
    extent = shape_extent(shape)
    if extent <= max_extent:
        return 1.0
    return float(max_extent / extent)


def scale_shape(shape: Shape, s: float) -> Shape:
    """``shape`` scaled by ``s`` about its origin (same type; ``s == 1`` returns it as is)."""
    if not s > 0:
        raise ValueError(f"scale must be > 0, got {s!r}")
    if s == 1.0:
        return shape
    if isinstance(shape, Circle):
        return Circle(float(shape.radius) * s)
    if isinstance(shape, Rectangle):
        return Rectangle((float(shape.size[0]) * s, float(shape.size[1]) * s))
    if isinstance(shape, Polygon):
        return Polygon(tuple((float(x) * s, float(y) * s) for x, y in shape.points))
    raise ValueError(f"cannot scale a {type(shape).__name__}")


def scale_motions(motions: ArrayLike, s: float) -> np.ndarray:
    """Motions (..., 3) with the translation scaled by ``s`` and the rotation unchanged:
    the motion of the scaled object that corresponds to ``motions`` of the real one."""
    m = np.array(motions, dtype=float)
    m[..., :2] *= s
    return m
