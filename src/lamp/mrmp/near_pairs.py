"""Point pairs within a distance, for fleets: a k-d tree instead of the full matrix.

``near_pairs(A, B, r)`` lists the pairs ``(a, b)`` with ``|A[a] - B[b]| <= r`` (``< r``
when ``strict``), in row-major order (by ``a``, then ``b``), with their distances, as
``np.nonzero`` of the dense matrix ``np.hypot(A[:, None, 0] - B[None, :, 0],
A[:, None, 1] - B[None, :, 1])`` would: the k-d tree proposes the pairs within a slightly
larger radius, and each is decided on the same float expression, element by element
(the same values bit for bit, so the same pairs). Up to :data:`DENSE` pairs the matrix
is made as it is; beyond, the work grows with the pairs found, not with ``len(A) *
len(B)`` (on den520d's 1,600 robots, 2.56 million distances a round).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["DENSE", "NearPairs", "near_pairs"]

#: Up to this many point pairs, the dense matrix.
DENSE = 4096
#: :meth:`NearPairs.within` finds the pairs this much (relatively) beyond the bound asked
#: for, and answers larger bounds up to there from them.
REACH_AHEAD = 0.3


def near_pairs(A: np.ndarray, B: np.ndarray, r: float, strict: bool = False,
               trees: tuple[cKDTree, cKDTree] | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(a, b, distance) of the pairs within ``r`` (see the module docstring); ``trees``:
    k-d trees of ``A`` and ``B`` already built."""
    A = np.asarray(A, dtype=np.float64).reshape(-1, 2)
    B = np.asarray(B, dtype=np.float64).reshape(-1, 2)
    if len(A) * len(B) <= DENSE or not np.isfinite(r):
        D = np.hypot(A[:, None, 0] - B[None, :, 0], A[:, None, 1] - B[None, :, 1])
        a, b = np.nonzero(r > D if strict else r >= D)
        return a, b, D[a, b]
    ta, tb = trees if trees is not None else (cKDTree(A), cKDTree(B))
    got = ta.sparse_distance_matrix(tb, r * (1.0 + 1e-9) + 1e-12, output_type="ndarray")
    a = got["i"].astype(np.int64)
    b = got["j"].astype(np.int64)
    order = np.argsort(a * len(B) + b, kind="stable")
    a, b = a[order], b[order]
    d = np.hypot(A[a, 0] - B[b, 0], A[a, 1] - B[b, 1])
    keep = r > d if strict else r >= d
    return a[keep], b[keep], d[keep]


class NearPairs:
    """Goal-robot pairs of the straight lines ``|G[m] - S[i]|`` (the matrix ``E`` of
    :mod:`lamp.mrmp.assignment`), found within a bound as needed (the same pairs, order
    and distances as :func:`near_pairs` for every bound)."""

    def __init__(self, S: np.ndarray, G: np.ndarray) -> None:
        self.S, self.G = S, G
        self.M, self.N = len(G), len(S)
        big = self.M * self.N > DENSE
        self._tree = cKDTree(S) if big else None
        self._trees = (cKDTree(G), self._tree) if big else None
        self._cache: tuple | None = None  # (radius, goal, robot, distance) found

    def within(self, bound: float, strict: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(goal, robot, straight line) of the pairs within ``bound`` (below it when
        ``strict``), by goal then robot."""
        if self._trees is None:
            return near_pairs(self.G, self.S, bound, strict)
        if self._cache is None or bound > self._cache[0]:
            # a third beyond the bound: the next rounds' pairs found in the same query
            R = bound * (1.0 + REACH_AHEAD)
            self._cache = (R, *near_pairs(self.G, self.S, R, False, self._trees))
        _, a, b, d = self._cache
        keep = bound > d if strict else bound >= d
        return a[keep], b[keep], d[keep]

    def nearest(self) -> float:
        """The largest, over the goals, of the distance to the nearest robot."""
        if self._tree is None:
            D = np.hypot(self.G[:, None, 0] - self.S[None, :, 0],
                         self.G[:, None, 1] - self.S[None, :, 1])
            return float(D.min(axis=1).max())
        d, i = self._tree.query(self.G, k=1)
        # the same float as the dense expression, for the nearest robot found
        i = np.asarray(i, np.int64)
        return float(np.hypot(self.G[:, 0] - self.S[i, 0], self.G[:, 1] - self.S[i, 1]).max())
