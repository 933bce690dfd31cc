"""Test helpers for Gspi's fleet plans: the makespan of synchronised rows, and a plan
that must pass the independent checker and come out the same twice."""

from __future__ import annotations

from typing import Any

import numpy as np
from fleet_checker import check_fleet_plan

from lamp.mrmp import plan_paths


def row_makespan(paths: np.ndarray) -> float:
    """The length of a plan's synchronised rows: each row lasts as long as its longest
    move (robots, rows, 2)."""
    return float(np.hypot(*np.diff(paths, axis=1).transpose(2, 0, 1)).max(axis=0).sum())


def checked_plan(scene: Any, starts: np.ndarray, goals: np.ndarray, seed: int,
                 robot_radius: float) -> Any:
    """``plan_paths`` on the instance, asserted to succeed, to keep one robot on each
    goal, to pass the fleet checker (``fleet_checker``, no lamp code) and to be the same
    when planned a second time; the plan."""
    plan = plan_paths(scene, starts, goals, seed=seed, time_limit=600.0)
    assert plan.success, plan.reason
    assert sorted(plan.goal_of.tolist()) == list(range(len(goals)))
    assert check_fleet_plan(scene.to_dict(), starts, goals, plan, robot_radius) == []
    again = plan_paths(scene, starts, goals, seed=seed, time_limit=600.0)
    assert np.array_equal(again.paths, plan.paths)
    return plan
