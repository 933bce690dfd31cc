"""The object lattice's metric: its heuristic, and the cost of straight motions.

:func:`lattice_metric` is the heuristic and ``distance`` of
:class:`~lamp.search.lattice.ObjectLattice`: the octile norm of the translation in the
lattice's (world) axes, ``max(|dx|, |dy|) + (sqrt(2) - 1) * min(|dx|, |dy|)``, plus ``w_rot * |wrap(dtheta)|``. With a ``landmark``, the translation
term is ``max(octile, |D(a) - D(b)|)`` for the landmark potential ``D`` of
:mod:`lamp.search.landmark` (2D geodesic distances from the landmark, 1-Lipschitz along
every lattice edge), which accounts for the detours obstacles force. Every primitive's
cost equals the metric between its ends (an axis step costs ``step``, a diagonal ``step *
sqrt(2)``, both the octile norm, never below ``|D(u) - D(v)|``), and the metric is a max
and a sum of pseudometrics, so it obeys the triangle inequality between any poses, lattice
nodes or continuous ones. Hence it is a lower bound of every lattice path cost
(admissible), consistent on every lattice edge, and D* Lite's key modifier may add it
between successive starts. A joining motion costs its true length, which the metric may
exceed (the octile norm by at most ``sqrt(4 - 2 sqrt(2)) - 1``, 8.2 %, of the
translation): D* Lite lowers its heuristic from a virtual start by the largest such excess
over the start's edges, which keeps it consistent there (``dstar_lite``). In free space
it is exact between nodes ``(i, j, k)`` and ``(i', j', k')`` whose heading bins differ by
at most ``max(|i - i'|, |j - j'|)`` (an octile path can turn one bin per step), which the
Euclidean norm is not off the axes and diagonals: a search guided by it expands far fewer
vertices on long routes.

Tested against a plain Dijkstra on random maps in ``tests/test_lattice.py`` (lower bound,
consistency on every edge, exactness in free space, triangle inequality, the joining
motions' bounded excess) and ``tests/test_landmark.py``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry import se2

TWO_PI = 2.0 * math.pi
#: weight of the smaller axis displacement in the octile norm
OCTILE_MINOR = math.sqrt(2.0) - 1.0


def motion_cost(a: ArrayLike, b: ArrayLike, w_rot: float) -> np.ndarray | float:
    """Cost of the straight SE(2) motion between (..., 3) poses: ``hypot(dx, dy) + w_rot *
    |wrap(dtheta)|`` (vectorised). Every primitive costs this, and it never exceeds
    :func:`lattice_metric` (equal on primitives)."""
    dt, dr = se2.pose_distance(a, b)
    out = dt + w_rot * dr
    return float(out) if np.ndim(out) == 0 else out


def lattice_metric(
    dx: ArrayLike, dy: ArrayLike, dtheta: ArrayLike, w_rot: float, dpot: ArrayLike = 0.0
) -> np.ndarray | float:
    """The lattice's metric for a displacement ``(dx, dy)`` (world axes), a heading change
    ``dtheta`` (any real, wrapped here) and a landmark potential difference ``dpot``:
    ``max(octile(dx, dy), |dpot|) + w_rot * |wrap(dtheta)|`` with ``octile = max(|dx|,
    |dy|) + (sqrt(2) - 1) * min(|dx|, |dy|)``. Vectorised; a float for scalar arguments.
    Equals every primitive's cost (``|dpot|`` never exceeds it along an edge), obeys the
    triangle inequality, and is symmetric."""
    ax, ay = np.abs(dx), np.abs(dy)
    d = np.abs(dtheta) % TWO_PI
    trans = np.maximum(np.maximum(ax, ay) + OCTILE_MINOR * np.minimum(ax, ay), np.abs(dpot))
    out = trans + w_rot * np.minimum(d, TWO_PI - d)
    return float(out) if np.ndim(out) == 0 else out
