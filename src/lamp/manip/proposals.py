"""What a manipulation model returns, and the protocol every proposer follows.

A proposal answers "which robots go where, and how do they push?" for one requested
short object motion (the paper's C_manip and T_manip, Sec. "GCo"). Frames: everything is in
the object's frame at its current pose, in metres; the requested motion ``(dx, dy,
dtheta)`` is expressed in that same frame, so the object's target pose is
``compose(current_pose, motion)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from lamp.scene.model import Shape

ShapeLike = Shape | Mapping[str, Any]


@dataclass(frozen=True, eq=False)
class Proposal:
    """One candidate contact formation with its push trajectories.

    Attributes:
        contacts: (b, 2) robot-centre positions touching the object, object frame (m).
        pushes: (b, H, 2) robot-centre waypoints of the push, object frame of the start
            pose (m); ``pushes[i, 0] == contacts[i]`` and ``pushes[i, -1]`` is where robot
            i ends. Executed from the contacts, they should move the object by the motion.
        source: which proposer (and strategy) made it, for statistics and debugging.
    """

    contacts: np.ndarray
    pushes: np.ndarray
    source: str = ""

    def __post_init__(self) -> None:
        c, p = self.contacts, self.pushes
        if c.ndim != 2 or c.shape[1] != 2 or c.shape[0] < 1:
            raise ValueError(f"contacts must have shape (b, 2) with b >= 1, got {c.shape}")
        if p.ndim != 3 or p.shape[0] != c.shape[0] or p.shape[2] != 2:
            raise ValueError(f"pushes must have shape ({c.shape[0]}, H, 2), got {p.shape}")

    @property
    def n_robots(self) -> int:
        """b, the number of robots this proposal uses (masked slots already dropped)."""
        return int(self.contacts.shape[0])

    @property
    def horizon(self) -> int:
        return int(self.pushes.shape[1])

    def in_world(self, pose: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Contacts (b, 2) and pushes (b, H, 2) mapped to the world for an object at ``pose``."""
        from lamp.geometry.se2 import transform_points

        return transform_points(pose, self.contacts), transform_points(pose, self.pushes)


@runtime_checkable
class ProposalModel(Protocol):
    """A manipulation model: requested object motion -> K candidate proposals.

    Implementations: ``GeometricProposer`` (hand-made strategies, fast, no learning) and
    ``FlowProposer`` (the trained discrete-continuous flow-matching model, ``load_model``).
    """

    horizon: int
    #: Radius (m) of the robots the proposals are made for: contacts lie that far (plus a
    #: small gap) off the object's boundary. A scene with other robots cannot use them.
    robot_radius: float

    def propose(
        self,
        shape: ShapeLike,
        motion: ArrayLike,
        budget: int,
        k: int = 16,
        seed: int | np.random.Generator | None = None,
    ) -> list[Proposal]:
        """``k`` proposals for moving ``shape`` by ``motion`` with at most ``budget`` robots."""
        ...

    def propose_batch(
        self,
        shape: ShapeLike,
        motions: Sequence[ArrayLike] | np.ndarray,
        budget: int,
        k: int = 16,
        seed: int | np.random.Generator | None = None,
    ) -> list[list[Proposal]]:
        """``propose`` for several motions of the same shape at once (one list per motion)."""
        ...


def make_rng(seed: int | np.random.Generator | None) -> np.random.Generator:
    """A numpy Generator from a seed, an existing Generator (used as is) or None (fresh)."""
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is not None and (isinstance(seed, bool) or int(seed) != seed):
        raise ValueError(f"seed must be an int, a numpy Generator or None, got {seed!r}")
    return np.random.default_rng(None if seed is None else int(seed))


def check_k(k: int) -> int:
    """Validate the number of candidates requested."""
    if isinstance(k, bool) or int(k) != k or int(k) < 1:
        raise ValueError(f"k must be a positive integer, got {k!r}")
    return int(k)
