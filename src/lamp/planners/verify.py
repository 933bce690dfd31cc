"""The pure helpers ``Verify`` builds a transition with (``lamp.contract.transition``).

``Verify`` itself (paper Sec. III-A-1, Alg. 1 lines 17-25) is
:class:`lamp.planners.verifier.Verifier`. This module holds the optimal robot-to-contact
pairing and the push paths of all robots.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from lamp.contract.trajectory import hold, retime

__all__ = ["assign_to_contacts", "push_paths"]


def assign_to_contacts(q_R: np.ndarray, contacts: np.ndarray) -> tuple[np.ndarray, float]:
    """Optimal robot-to-contact pairing by Euclidean distance: (paired robot rows, total)."""
    cost = np.linalg.norm(q_R[:, None, :] - contacts[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    return rows, float(cost[rows, cols].sum())


def push_paths(end_of_move: np.ndarray, goal_of: np.ndarray, pushes_world: np.ndarray) -> np.ndarray:
    """T_manip for all N robots: robot at contact j follows push j, the others hold."""
    n = end_of_move.shape[0]
    h = pushes_world.shape[1]
    manip = hold(end_of_move, h)
    for i in range(n):
        j = int(goal_of[i])
        if 0 <= j < pushes_world.shape[0]:
            manip[i] = pushes_world[j]
            manip[i, 0] = end_of_move[i]
    return retime(manip)
