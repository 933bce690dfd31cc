"""The manipulation model's proposals for one object, cached (:class:`ProposalCache`).

The object frame makes proposals independent of where the object is, so a request is
keyed by the motion alone (:func:`proposal_key`: rounded to 0.1 mm / 0.1 mrad), the robot
budget and the attempt; each key draws with its own seed (:func:`stable_seed`), so the
same run asks the model the same questions with the same seeds however its cache is
visited.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lamp.planners.collide import PushCandidates, prepare_candidates
from lamp.planners.task_stats import TaskStats
from lamp.scene.model import Shape

__all__ = ["ProposalCache", "proposal_key", "stable_seed"]


def proposal_key(motion: np.ndarray, budget: int, attempt: int) -> tuple:
    """Cache key of a proposal request: the motion rounded to 0.1 mm / 0.1 mrad."""
    return tuple(np.round(np.asarray(motion, float), 4)), int(budget), int(attempt)


def stable_seed(seed: int, key: tuple) -> int:
    """A deterministic 31-bit seed from a run seed and a hashable key (no Python hash())."""
    motion, budget, attempt = key
    words = [seed, budget, attempt, *[int(round(m * 1e4)) + 10**6 for m in motion]]
    return int(np.random.default_rng([abs(int(w)) for w in words]).integers(2**31 - 1))


class ProposalCache:
    """K proposals of ``model`` for ``shape`` per (motion, budget, attempt), raw
    (:meth:`get`) and prepared for ``Collide`` (:meth:`push_candidates`), each cached;
    :meth:`sample` draws one fresh, uncached. Counts ``model_calls`` and ``cache_hits``
    in ``stats``."""

    def __init__(self, model: Any, shape: Shape, robot_radius: float, k: int,
                 contact_tolerance: float, seed: int, stats: TaskStats) -> None:
        self.model = model
        self.shape = shape
        self.robot_radius = float(robot_radius)
        self.k = k
        self.contact_tolerance = contact_tolerance
        self.seed = int(seed)
        self.stats = stats
        self._proposals: dict[tuple, list] = {}
        self._candidates: dict[tuple, PushCandidates] = {}

    def get(self, motion: np.ndarray, budget: int, attempt: int) -> list:
        """K model proposals for ``motion`` (object frame) with ``budget`` robots.

        Cached per (motion, budget, attempt): lattice primitives are answered once (a
        repeat counts in ``stats.cache_hits``, a model call in ``stats.model_calls``); a
        repeated verification of the same edge (``attempt`` > 0) draws fresh samples, as
        the paper relies on (Sec. III-A-1: "a different sampling in a future call may
        yield valid manipulation trajectories").
        """
        key = proposal_key(motion, budget, attempt)
        props = self._proposals.get(key)
        if props is None:
            props = self.model.propose(self.shape, motion=tuple(map(float, motion)),
                                       budget=budget, k=self.k,
                                       seed=stable_seed(self.seed, key))
            self.stats.model_calls += 1
            self._proposals[key] = props
        else:
            self.stats.cache_hits += 1
        return props

    def push_candidates(self, motion: np.ndarray, budget: int, attempt: int) -> PushCandidates:
        """:meth:`get`'s proposals prepared for ``Collide`` (``PushCandidates``), cached
        alike."""
        key = proposal_key(motion, budget, attempt)
        cands = self._candidates.get(key)
        if cands is None:
            cands = prepare_candidates(self.get(motion, budget, attempt), self.shape,
                                       self.robot_radius, self.contact_tolerance)
            self._candidates[key] = cands
        else:
            self.stats.cache_hits += 1
        return cands

    def sample(self, motion: np.ndarray, budget: int, seed: int) -> np.ndarray:
        """One fresh model sample's push paths (B, H, 2, object frame) for ``motion``:
        never cached, never checked (``Collide`` is not applied); one ``model_calls``."""
        self.stats.model_calls += 1
        prop = self.model.propose(self.shape, motion=tuple(map(float, motion)), budget=budget,
                                  k=1, seed=seed)[0]
        return np.asarray(prop.pushes, float)
