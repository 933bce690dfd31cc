"""What a :class:`~lamp.planners.verifier.Verifier` is built from: the narrow protocols of
the robots' free space and of the multi-robot planner (Gspi behind :class:`GspiRouter`),
its numbers (:class:`VerifierParams`), its counters (:class:`TaskStats`) and the prepared
proposals it checks (:class:`PushCandidates`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from lamp.scene.model import Scene

__all__ = ["FreeSpace", "GspiRouter", "MultiRobotPlanner", "PushCandidates", "RobotValidity",
           "TaskStats", "VerifierParams", "pairwise_min_distance", "proposal_key",
           "stable_seed"]

Window = tuple[float, float, float, float]


class FreeSpace(Protocol):
    """What ``Verify`` asks of a robot configuration space (``RobotSpace`` is one)."""

    @property
    def covers_workspace(self) -> bool:
        """Whether the space spans the whole map (a larger window cannot help)."""
        ...

    def is_free(self, points: np.ndarray) -> np.ndarray:
        """(P,) whether a robot centred at each of the (P, 2) points is collision-free."""
        ...

    def segment_free(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether a robot moving straight from each ``a`` to each ``b`` stays free."""
        ...

    def nearest_free(self, point: np.ndarray, accept: Callable[[np.ndarray], np.ndarray] | None
                     = None, max_distance: float | None = None) -> np.ndarray | None:
        """The nearest free (and accepted) spot to ``point``, or None."""
        ...


class RobotValidity(Protocol):
    """The robots' free space around the manipulated object, at a given object pose."""

    #: The largest window side (m) ``approach`` may grow a window to.
    max_window_side: float

    def window(self, q_object: np.ndarray, points: np.ndarray | None = None,
               scale: float = 1.0) -> Window:
        """(x0, y0, x1, y1) around the object at ``q_object`` and ``points``."""
        ...

    def robot_space_at(self, q_object: np.ndarray, window: Window | None = None) -> FreeSpace:
        """Robot space with the manipulated object at ``q_object``, over ``window``."""
        ...

    def static_space_near(self, q_object: np.ndarray) -> FreeSpace:
        """Robot space without the manipulated object, around ``q_object``."""
        ...


class MultiRobotPlanner(Protocol):
    """Paths for all robots from ``starts`` to ``goals`` (anonymous goals), with the object
    at ``q_object``, in ``space``; the answer has ``success``, ``status`` (a
    ``GspiStatus``), ``paths`` (N, T, 2) and ``goal_of`` (N,)."""

    def __call__(self, q_object: np.ndarray, starts: np.ndarray, goals: np.ndarray,
                 space: Any, time_limit: float) -> Any: ...


@dataclass(frozen=True, eq=False)
class GspiRouter:
    """Gspi (``lamp.mrmp.plan_paths``) for one object of ``scene``, the others at
    ``object_poses``; ``seed`` and ``goal_tolerance`` are passed on unchanged."""

    scene: Scene
    index: int
    object_poses: np.ndarray
    seed: int = 0
    goal_tolerance: float = 0.006

    def __call__(self, q_object: np.ndarray, starts: np.ndarray, goals: np.ndarray,
                 space: Any, time_limit: float) -> Any:
        from lamp.mrmp import plan_paths

        if space is not None:  # the robot space Verify checked the push in
            return plan_paths(space, starts, goals, time_limit=time_limit, seed=self.seed,
                              goal_tolerance=self.goal_tolerance)
        poses = np.array(self.object_poses, float).reshape(-1, 3)
        poses[self.index] = q_object
        return plan_paths(self.scene, starts, goals, object_poses=poses, time_limit=time_limit,
                          seed=self.seed, goal_tolerance=self.goal_tolerance)


@dataclass(frozen=True)
class VerifierParams:
    """The ``PlannerConfig`` numbers ``Verify`` reads. Validated: positive counts and times,
    a non-negative tolerance (``ValueError`` naming the field)."""

    k: int = 16
    max_budget: int = 3
    gspi_attempts_per_budget: int = 3
    contact_tolerance: float = 0.006
    gspi_time_limit: float = 10.0

    def __post_init__(self) -> None:
        for name in ("k", "max_budget", "gspi_attempts_per_budget"):
            v = getattr(self, name)
            if not (isinstance(v, int) and not isinstance(v, bool) and v >= 1):
                raise ValueError(f"{name}: a positive integer, got {v!r}")
        if not self.gspi_time_limit > 0:
            raise ValueError(f"gspi_time_limit: positive seconds, got {self.gspi_time_limit!r}")
        if not self.contact_tolerance >= 0:
            raise ValueError(f"contact_tolerance: >= 0, got {self.contact_tolerance!r}")

    @classmethod
    def from_config(cls, cfg: Any) -> VerifierParams:
        return cls(k=cfg.k, max_budget=cfg.max_budget,
                   gspi_attempts_per_budget=cfg.gspi_attempts_per_budget,
                   contact_tolerance=cfg.contact_tolerance, gspi_time_limit=cfg.gspi_time_limit)


@dataclass
class TaskStats:
    """Counters reported in result.json's ``stats``."""

    verify_calls: int = 0
    verify_success: int = 0
    model_calls: int = 0
    gspi_calls: int = 0
    gspi_success: int = 0
    #: Gspi calls ended by the wall-clock cap ``gspi_time_limit`` (0 on an unloaded
    #: machine: then no result depended on the clock).
    gspi_timeouts: int = 0
    cache_hits: int = 0
    #: vertices LAMP-Lazy's D* Lite expanded (its budget: ``lazy_max_expansions``)
    search_expansions: int = 0
    #: the most of them in one LAMP-Lazy ``plan`` call (a maximum: ``add`` keeps the larger)
    max_plan_expansions: int = 0

    def add(self, other: TaskStats) -> None:
        for k, v in vars(other).items():
            setattr(self, k, max(getattr(self, k), v) if k.startswith("max_")
                    else getattr(self, k) + v)


@dataclass(frozen=True)
class PushCandidates:
    """The K proposals for one (motion, budget, attempt), prepared for fast ``Collide`` checks.

    A proposal lives in the object frame, and rigid motions preserve distances and linear
    interpolation, so two of ``Collide``'s three tests do not depend on where the object
    is: a contact inside the object and two pushing robots closer than 2r. They are done
    once here (``intrinsic_ok``). The third, push paths in the robots' free space, is
    done per pose on ``dense_points``: every push path densified to ``MAX_STEP / 2`` in
    the object frame and stacked, proposal ``i`` owning rows ``starts[i]:starts[i + 1]``.
    """

    pushes_local: list[np.ndarray]  # K arrays (B, H, 2), object frame
    intrinsic_ok: np.ndarray  # (K,) bool
    dense_points: np.ndarray  # (P, 2) stacked densified push points, object frame
    starts: np.ndarray  # (K + 1,) row offsets into dense_points


def pairwise_min_distance(paths: np.ndarray) -> float:
    """Smallest distance between any two of the (B, T, 2) synchronised paths."""
    b = paths.shape[0]
    if b < 2:
        return np.inf
    i, j = np.triu_indices(b, 1)
    d = paths[i] - paths[j]
    return float(np.sqrt(np.min(d[..., 0] ** 2 + d[..., 1] ** 2)))


def proposal_key(motion: np.ndarray, budget: int, attempt: int) -> tuple:
    """Cache key of a proposal request: the motion rounded to 0.1 mm / 0.1 mrad."""
    return tuple(np.round(np.asarray(motion, float), 4)), int(budget), int(attempt)


def stable_seed(seed: int, key: tuple) -> int:
    """A deterministic 31-bit seed from a run seed and a hashable key (no Python hash())."""
    motion, budget, attempt = key
    words = [seed, budget, attempt, *[int(round(m * 1e4)) + 10**6 for m in motion]]
    return int(np.random.default_rng([abs(int(w)) for w in words]).integers(2**31 - 1))
