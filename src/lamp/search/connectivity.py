"""Whether an object can get from one position to another at all, answered in the plane.

A lattice search that has no path to find proves it by exhausting every pose it can
reach, and LAMP-Lazy then refines the lattice over ever larger windows and searches again
(``RefinedLattice.refine``): on a 45 x 50 m map that is minutes of planning for nothing
(a fleet's object whose way out is blocked by another object, or a goal walled in). This
module gives the answer first, from a necessary condition.

The disk of radius ``r`` inscribed in the object's footprint about its origin
(``landmark.inscribed_radius``) is inside the footprint at every heading. So along any
continuous collision-free motion of the object (any heading, any path) the origin stays
in ``F_r``: the positions where that disk lies inside the workspace and meets no
obstacle. If two positions lie in different connected components of ``F_r``, no motion
joins them, on the lattice, off it (refined poses) or anywhere else.

``F_r`` is computed with Shapely: the workspace shrunk by ``r`` minus the union of the
obstacles grown by ``r``. Shapely draws circles and round joins as polygons whose vertices
lie on the true curves, so the obstacles it grows are a little *smaller* than the true
ones and the ``F_r`` it returns *contains* the true one: the true component of each
position lies inside its computed component, and "different components" stays a proof.
A position outside the computed ``F_r`` (a pose already touching something, a drifted
object) gets no verdict: :meth:`PlaneConnectivity.separated` answers False (not proven).

Guarantee (``tests/test_connectivity.py``): ``separated(a, b)`` is True only when no
lattice path joins the poses (checked against an exhaustive search on random maps), and
it is True across a wall with no gap wide enough.
"""

from __future__ import annotations

import shapely
from numpy.typing import ArrayLike

from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.shapes import obstacle_geometry
from lamp.search.landmark import inscribed_radius

__all__ = ["PlaneConnectivity"]


class PlaneConnectivity:
    """The components of ``F_r`` (module docstring) for ``space``'s object shrunk by
    ``slack`` (m: the most any motion the planner accepts shrinks the footprint, e.g. a
    tolerant join), built on first use."""

    def __init__(self, space: ObjectSpace, slack: float = 0.0) -> None:
        if not slack >= 0.0:
            raise ValueError(f"slack must be >= 0, got {slack!r}")
        self.space = space
        self.radius = inscribed_radius(space) - float(slack)
        self._parts: list[shapely.Geometry] | None = None

    @property
    def parts(self) -> list[shapely.Geometry]:
        """The connected components of the computed ``F_r`` (empty when ``r <= 0``: no
        verdict is possible then)."""
        if self._parts is None:
            self._parts = self._build()
        return self._parts

    def _build(self) -> list[shapely.Geometry]:
        r = self.radius
        w, h = (float(v) for v in self.space.workspace)
        if r <= 0.0 or 2.0 * r >= min(w, h):
            return []
        free = shapely.box(r, r, w - r, h - r)
        grown = [shapely.buffer(obstacle_geometry(o), r) for o in self.space.obstacles]
        if grown:
            free = shapely.difference(free, shapely.union_all(grown))
        parts = list(getattr(free, "geoms", [free]))
        for p in parts:
            shapely.prepare(p)
        return [p for p in parts if not p.is_empty]

    def component(self, xy: ArrayLike) -> int | None:
        """Index of the component whose interior holds position ``xy``; None when it lies
        in none (outside ``F_r`` or on a boundary)."""
        x, y = (float(v) for v in list(xy)[:2])
        point = shapely.Point(x, y)
        for i, part in enumerate(self.parts):
            if part.contains_properly(point):
                return i
        return None

    def separated(self, a: ArrayLike, b: ArrayLike) -> bool:
        """True only when no collision-free motion of the object joins positions (or
        poses) ``a`` and ``b``: both lie inside ``F_r``, in different components."""
        ca = self.component(a)
        if ca is None:
            return False
        cb = self.component(b)
        return cb is not None and ca != cb
