"""When an object is at its goal: the scene format's success tolerances and the pose errors.

The scene format (``docs/scene-format.md``) defines success: the object's final position
within ``SUCCESS_POSITION_TOL`` metres of its goal and its heading within
``SUCCESS_ORIENTATION_TOL`` radians (wrapped). Everything that decides success (the closed
loop, the baselines, the environments, the checkers) reads these two constants.
"""

from __future__ import annotations

import numpy as np

from lamp.geometry.se2 import pose_distance

__all__ = ["SUCCESS_ORIENTATION_TOL", "SUCCESS_POSITION_TOL", "goal_errors", "within_goal"]

#: Success tolerances of the scene format (position metres, orientation radians).
SUCCESS_POSITION_TOL = 0.1
SUCCESS_ORIENTATION_TOL = 0.1


def goal_errors(pose: np.ndarray, goal: np.ndarray) -> tuple[float, float]:
    """(position error, wrapped orientation error) of ``pose`` against ``goal``."""
    dt, dr = pose_distance(np.asarray(pose, float), np.asarray(goal, float))
    return float(dt), float(dr)


def within_goal(pose, goal, position_tol: float, orientation_tol: float) -> bool:
    dt, dr = goal_errors(pose, goal)
    return dt <= position_tol and dr <= orientation_tol
