"""The verified transition and the pure helpers ``Verify`` builds it with.

``Verify`` itself (paper Sec. III-A-1, Alg. 1 lines 17-25) is
:class:`lamp.planners.verifier.Verifier`: it returns a :class:`Transition`, the robot
trajectories T_R = T_move (+) T_manip that realise one object motion. This module holds
that record, the optimal robot-to-contact pairing and the push paths of all robots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from lamp.planners.trajectory import concat, hold, retime

__all__ = ["Transition", "assign_to_contacts", "push_paths"]


@dataclass
class Transition:
    """Verified robot trajectories for one object motion (an edge of LAMP's search)."""

    q_from: np.ndarray  # (3,) object pose before the push
    q_to: np.ndarray  # (3,) planned object pose after the push
    contacts: np.ndarray  # (B, 2) contact points, world frame
    pushes_local: np.ndarray  # (B, H, 2) push paths in the object frame at q_from
    move: np.ndarray  # (N, Tm, 2) approach: robots to contacts / waiting spots
    manip: np.ndarray  # (N, Tp, 2) push: contact robots follow pushes, others hold
    #: The search edge (u, v) this transition realises, when a planner tracks it.
    edge: tuple | None = None

    @property
    def robot_paths(self) -> np.ndarray:
        """T_R = T_move (+) T_manip: the synchronised paths to execute."""
        return concat(self.move, self.manip)

    @property
    def robot_start(self) -> np.ndarray:
        return self.move[:, 0]

    @property
    def robot_end(self) -> np.ndarray:
        return self.manip[:, -1]

    @property
    def steps(self) -> int:
        """Synchronised time steps of T_R (its makespan)."""
        return int(self.move.shape[1] + self.manip.shape[1] - 1)

    @property
    def budget(self) -> int:
        return int(self.contacts.shape[0])


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
