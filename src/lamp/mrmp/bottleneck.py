"""Lower bounds on a fleet's makespan from the bottleneck assignment of its distances.

Robots with interchangeable goals, each driving at most at unit speed: whichever robot
takes which goal, some robot must cover the longest distance of its own pair, so no plan
ends before the least, over the assignments that give every goal its own robot, of their
longest distance (the *bottleneck*). Two bounds follow, each a bottleneck of distances
that are themselves never longer than a robot's way:

- :func:`straight_line_bottleneck`: straight lines, whatever the map;
- :func:`geodesic_bottleneck`: the shortest ways round the obstacles, for disks of the
  robots' radius (``lamp.scene.geodesic``), never below the straight-line one.

Guarantee (``tests/test_bottleneck_bound.py``): :func:`matrix_bottleneck` equals a brute
force over every assignment; :func:`geodesic_bottleneck` equals the brute force over the
pairs' :meth:`~lamp.scene.geodesic.GrownObstacles.distance`, and is at least the
straight-line bottleneck.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linear_sum_assignment

from lamp.scene.geodesic import GrownObstacles

__all__ = ["FIRST_CAP", "GROW", "geodesic_bottleneck", "least_threshold", "matrix_bottleneck",
           "straight_line_bottleneck"]

#: The first cap of :func:`geodesic_bottleneck`'s distances, over the straight-line
#: bottleneck, and the factor each later cap grows by.
FIRST_CAP, GROW = 1.25, 1.5
#: Finite stand-in for an unreachable pair in the assignment problems.
_BIG = 1e18


def least_threshold(C: np.ndarray, vals: np.ndarray, a: int, b: int) -> int:
    """The least ``i`` in ``[a, b]`` such that the pairs with ``C <= vals[i]`` match every
    row of ``C`` (binary search; ``b`` must be such an index)."""
    while a < b:
        mid = (a + b) // 2
        rows, cols = linear_sum_assignment(vals[mid] < C)
        if (C[rows, cols] > vals[mid]).any():
            a = mid + 1
        else:
            b = mid
    return a


def matrix_bottleneck(C: np.ndarray) -> float:
    """The least, over the assignments giving every row of ``C`` (goals x robots) its own
    column, of the largest cost of a chosen pair; ``inf`` when no assignment avoids an
    infinite cost. Exact: bisection over the distinct costs between the largest of the
    rows' least costs and the largest cost of a least-sum assignment, each threshold tried
    as a least-sum assignment of the 0/1 matrix "above the threshold" (dense; Hopcroft-Karp
    on the sparse pairs can take seconds when one goal is left over); the result is one of
    the costs. Raises ``ValueError`` with more rows than columns."""
    C = np.asarray(C, dtype=float)
    M, N = C.shape
    if M == 0:
        return 0.0
    if N < M:
        raise ValueError(f"{N} robots cannot reach {M} goals")
    floor = C.min(axis=1).max()  # every goal needs some robot
    if N == M:
        floor = max(floor, C.min(axis=0).max())  # and every robot some goal
    if not math.isfinite(floor):
        return math.inf
    rows, cols = linear_sum_assignment(np.where(np.isfinite(C), C, _BIG))
    top = C[rows, cols].max()  # one assignment's longest cost
    if not math.isfinite(top):
        return math.inf
    vals = np.unique(C[(floor <= C) & (top >= C)])
    return float(vals[least_threshold(C, vals, 0, len(vals) - 1)])


def _points(P: np.ndarray) -> np.ndarray:
    return np.asarray(P, dtype=float).reshape(-1, 2)


def straight_line_bottleneck(S: np.ndarray, G: np.ndarray) -> float:
    """The least, over the assignments giving every goal ``G[m]`` its own robot ``S[i]``,
    of the longest straight-line start-goal distance (same units as the points): a lower
    bound whatever the map (module docstring). Exact (:func:`matrix_bottleneck`); the
    result is one of the distances. Raises ``ValueError`` with fewer robots than goals."""
    S, G = _points(S), _points(G)
    return matrix_bottleneck(np.hypot(G[:, None, 0] - S[None, :, 0],
                                      G[:, None, 1] - S[None, :, 1]))  # (M, N)


def geodesic_bottleneck(grown: GrownObstacles, S: np.ndarray, G: np.ndarray) -> float:
    """The bottleneck of the shortest ways round ``grown`` (the obstacles grown by the
    robots' radius) from the robots' starts ``S`` to the goals ``G`` ((n, 2), (m, 2)):
    a lower bound on the makespan at unit speed of any plan that brings those robots onto
    every goal (module docstring), at least the straight-line bottleneck; ``inf`` when
    the obstacles leave some goal no robot of its own. Only pairs shorter than a cap are
    searched (``GrownObstacles.distance_matrix``): the first cap :data:`FIRST_CAP` times
    the straight-line bottleneck, grown by :data:`GROW` until the bottleneck lies below
    it (then the longer pairs cannot change it), the whole matrix once the cap passes
    twice the longest straight line between any two of the points."""
    S, G = _points(S), _points(G)
    straight = straight_line_bottleneck(S, G)
    if len(G) == 0:
        return 0.0
    ends = np.vstack([S, G])
    longest = float(np.hypot(*np.ptp(ends, axis=0)))  # no straight line is longer
    cap = max(straight, 1e-9) * FIRST_CAP
    while True:
        below = cap if cap <= 2.0 * longest else math.inf
        value = matrix_bottleneck(grown.distance_matrix(G, S, below=below))
        if value < below or not math.isfinite(below):
            return value
        cap *= GROW
