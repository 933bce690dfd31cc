"""The verified transition: robot trajectories that realise one object motion.

``Verify`` (paper Sec. III-A-1, Alg. 1 lines 17-25, :class:`lamp.planners.verifier.Verifier`)
returns one; the planners put them in their plans and the closed loop executes them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lamp.contract.trajectory import concat

__all__ = ["Transition"]


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
