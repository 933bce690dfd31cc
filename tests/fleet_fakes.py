"""Test helper: a ``Fleet`` over an executor that only reports poses (no simulator), for
tests of the schedule's decisions."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from lamp.fleet.config import FleetConfig
from lamp.fleet.coordinator import Fleet


def fleet_at_starts(scene: Any, robot_positions: np.ndarray | None = None,
                    **settings: float) -> Fleet:
    """A ``Fleet`` on ``scene`` whose executor reports the objects at their starts and the
    robots at ``robot_positions`` (default: their starts); ``settings`` are its
    ``FleetConfig``.
    Its loops do nothing: the test sets the objects' states."""
    robots = np.array(scene.robot_starts if robot_positions is None else robot_positions,
                      float)
    poses = np.array([o.start for o in scene.objects])
    executor = SimpleNamespace(object_poses=poses, true_object_poses=poses,
                               robot_positions=robots, failed={}, disturbed=False,
                               pushes_tracked=True)
    return Fleet(scene, executor, lambda f, k: None, lambda *a: None,
                 config=FleetConfig(**settings))
