"""The team that still works: an executor seen by the robots that have not failed, and the
scene as they plan in it (a failed robot is an obstacle where it stopped).

Used by :class:`~lamp.planners.runner.ClosedLoopRunner` when the executor reports failed
robots (``lamp.sim.disturbed.DisturbedExecutor.failed``): planning carries on with the
robots that remain (smaller budgets, Gspi routing around the stopped one) and the robots'
indices map back to the scene's.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from lamp.contract.runner import Execution, Executor
from lamp.scene.model import Circle, Obstacle, Scene

__all__ = ["TeamView", "team_scene"]


def team_scene(scene: Scene, alive: list[int], failed: dict[int, np.ndarray]) -> Scene:
    """``scene`` with only the robots ``alive`` (at their start rows) and each failed robot
    a disk obstacle of the robot radius where it stopped."""
    stopped = tuple(Obstacle(Circle(float(scene.robot_radius)), (float(p[0]), float(p[1]), 0.0))
                    for _, p in sorted(failed.items()))
    return replace(scene, robot_starts=tuple(scene.robot_starts[i] for i in alive),
                   obstacles=tuple(scene.obstacles) + stopped)


class TeamView:
    """``executor`` as the robots ``alive`` see it: their positions only; their paths run
    with every other robot holding; ``team_changed`` turns True once another robot fails
    during a call (the closed loop then stops, and the runner plans anew)."""

    def __init__(self, executor: Executor, alive: list[int]) -> None:
        self.executor = executor
        self.alive = list(alive)
        self.team_changed = False

    @property
    def object_poses(self) -> np.ndarray:
        return self.executor.object_poses

    @property
    def robot_positions(self) -> np.ndarray:
        return np.asarray(self.executor.robot_positions, float)[self.alive]

    def execute(self, robot_paths: np.ndarray, record_every: int | None = None,
                stop: Callable[[np.ndarray], bool] | None = None) -> Execution:
        paths = np.asarray(robot_paths, float)
        full = np.repeat(np.asarray(self.executor.robot_positions, float)[:, None],
                         paths.shape[1], axis=1)
        full[self.alive] = paths
        out = self.executor.execute(full, record_every=record_every, stop=stop)
        if set(getattr(self.executor, "failed", {})) & set(self.alive):
            self.team_changed = True
        return replace(out, robot_positions=np.asarray(out.robot_positions)[self.alive])
