"""When two robot configurations count as "the same": one definition for every cache.

A configuration is an (N, 2) array of robot centres. Two relations are used:

* :func:`robots_match` (ordered): robot ``i`` of one is within ``tolerance`` of robot ``i``
  of the other, for every ``i``. Used where the robots' identities matter: LAMP-Lazy's
  per-node cache D_T (a cached T_R starts each robot where it stands) and the closed
  loop's decision to join a plan with a short straight move instead of re-routing.
* :func:`robot_state_key` (anonymous): a hashable key, equal for configurations whose
  robots fall into the same ``tolerance`` grid cells as a multiset. Used by LAMP-A* to merge
  explored states; robots are interchangeable there (Gspi assigns them anonymously).

Guarantees (tested): ``robots_match`` is symmetric and exact at the tolerance; equal keys
imply that, after pairing the robots cell by cell, each pair lies within one cell
diagonal (``tolerance * sqrt(2)``) of each other; a permutation never changes the key.
"""

from __future__ import annotations

import numpy as np

__all__ = ["robot_state_key", "robots_match"]


def robots_match(a: np.ndarray, b: np.ndarray, tolerance: float) -> bool:
    """Whether every robot ``i`` of ``a`` (N, 2) is within ``tolerance`` of robot ``i`` of ``b``."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    if a.shape != b.shape:
        return False
    return bool(np.max(np.hypot(*(a - b).T), initial=0.0) <= tolerance)


def robot_state_key(q_R: np.ndarray, tolerance: float) -> tuple:
    """The robots' grid cells of side ``tolerance``, sorted: permutations share a key."""
    cells = np.round(np.asarray(q_R, float) / tolerance).astype(int)
    return tuple(sorted(map(tuple, cells.tolist())))
