"""The robots' side of ``Verify``: the free space they move in, around the manipulated
object at a given pose (:class:`FreeSpace`, :class:`RobotValidity`; a
``ManipulationTask`` is one), and the multi-robot planner that routes them there
(:class:`MultiRobotPlanner`; Gspi behind :class:`GspiRouter`).

A :class:`~lamp.planners.verifier.Verifier` asks only these narrow protocols, so a test
can hand it a small fake of either.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from lamp.scene.model import Scene

__all__ = ["FreeSpace", "GspiRouter", "MultiRobotPlanner", "RobotValidity", "Window"]

#: A window of the map, (x0, y0, x1, y1) in m.
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
