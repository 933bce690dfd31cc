"""The argument checks of :func:`lamp.mrmp.gspi.plan_paths`, and what they yield.

:func:`check_inputs` raises :class:`lamp.errors.InputError` (a ValueError) for malformed
arguments, in the order ``plan_paths`` documents; starts or goals that are well formed but
unusable (outside the workspace, too deep in an obstacle, overlapping) are no error: their
message is returned in :attr:`PlanInputs.bad_start` / :attr:`PlanInputs.bad_goal`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from lamp.errors import InputError
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.assignment import ASSIGNMENTS
from lamp.mrmp.endpoints import as_points, check_points
from lamp.scene.model import Scene


@dataclass(frozen=True)
class PlanInputs:
    """Checked arguments: the space to plan in, starts (N, 2) and goals (M, 2) with their
    exact clearances, why a start or goal cannot be used ("" when all can), the initial
    goal per robot (None: the optimal assignment) and the lattice steps to try."""

    space: RobotSpace
    starts: np.ndarray
    goals: np.ndarray
    c_start: np.ndarray
    bad_start: str
    c_goal: np.ndarray
    bad_goal: str
    goal0: np.ndarray | None
    steps: tuple[float, ...]


def _check_numbers(time_limit: float, max_spacing: float, goal_tolerance: float,
                   start_tolerance: float, assignment: str, swap_radius: float | None) -> None:
    if not (np.isfinite(time_limit) and time_limit > 0):
        raise InputError(f"time_limit must be positive, got {time_limit!r}")
    if not (np.isfinite(max_spacing) and max_spacing > 0):
        raise InputError(f"max_spacing must be positive, got {max_spacing!r}")
    if goal_tolerance < 0 or start_tolerance < 0:
        raise InputError("goal_tolerance and start_tolerance must be >= 0")
    if assignment not in ASSIGNMENTS:
        raise InputError(f"assignment must be one of {', '.join(ASSIGNMENTS)}, got "
                         f"{assignment!r}")
    if swap_radius is not None and not (np.isfinite(swap_radius) and swap_radius > 0):
        raise InputError(f"swap_radius must be positive, got {swap_radius!r}")


def _initial_goals(initial_goal_of: ArrayLike | None, N: int, M: int) -> np.ndarray | None:
    if initial_goal_of is None:
        return None
    goal0 = np.asarray(initial_goal_of, dtype=np.int64).reshape(-1)
    if goal0.shape != (N,) or np.any(goal0 < -1) or np.any(goal0 >= M):
        raise InputError(f"initial_goal_of must be (N,) goal indices or -1, got {goal0}")
    used = goal0[goal0 >= 0]
    if len(np.unique(used)) != M or len(used) != M:
        raise InputError("initial_goal_of must give every goal to exactly one robot")
    return goal0


def check_inputs(
    scene: Scene | RobotSpace, starts: ArrayLike, goals: ArrayLike,
    object_poses: ArrayLike | None, extra_obstacles: Any, time_limit: float, *,
    space: RobotSpace | None, max_spacing: float, goal_tolerance: float,
    start_tolerance: float, assignment: str, swap_radius: float | None,
    initial_goal_of: ArrayLike | None, lattice_step: float | tuple[float, ...],
) -> PlanInputs:
    """Check ``plan_paths``' arguments (see there) and build the space when none is given."""
    if isinstance(scene, RobotSpace):
        if space is not None or object_poses is not None or len(extra_obstacles):
            raise InputError("plan_paths(space, ...) plans in that space: pass no space=, "
                             "object_poses= or extra_obstacles= beside it")
        space = scene
    elif not isinstance(scene, Scene):
        raise InputError(f"scene must be a lamp Scene or a RobotSpace, got "
                         f"{type(scene).__name__}")
    S = as_points(starts, "starts")
    G = as_points(goals, "goals")
    N, M = len(S), len(G)
    if N < 1:
        raise InputError("starts must hold at least one robot")
    if M > N:
        raise InputError(f"goals has {M} points but there are only {N} robots (need M <= N)")
    _check_numbers(time_limit, max_spacing, goal_tolerance, start_tolerance, assignment,
                   swap_radius)
    if space is None:
        space = RobotSpace.from_scene(scene, object_poses, extra_obstacles)
    elif not isinstance(space, RobotSpace):
        raise InputError(f"space must be a RobotSpace, got {type(space).__name__}")
    c_start, bad_start = check_points(space, S, "starts", start_tolerance)
    c_goal, bad_goal = check_points(space, G, "goals", goal_tolerance)
    goal0 = _initial_goals(initial_goal_of, N, M)
    steps = (lattice_step,) if np.isscalar(lattice_step) else tuple(lattice_step)  # type: ignore[arg-type]
    if not steps:
        raise InputError("lattice_step must be a step or a non-empty sequence of steps")
    return PlanInputs(space, S, G, c_start, bad_start, c_goal, bad_goal, goal0, steps)
