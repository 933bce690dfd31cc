"""The team that still works: an executor seen by the robots that have not failed, and the
scene as they plan in it (a failed robot is an obstacle where it stopped).

Used by :class:`~lamp.planners.runner.ClosedLoopRunner` when the executor reports failed
robots (``lamp.sim.disturbed.DisturbedExecutor.failed``): planning carries on with the
robots that remain (smaller budgets, Gspi routing around the stopped one) and the robots'
indices map back to the scene's.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace

import numpy as np

from lamp.contract.runner import Execution, LoopHooks, WorldExecutor
from lamp.scene.model import Circle, Obstacle, Scene

__all__ = ["TeamView", "team_scene"]


def team_scene(scene: Scene, team: list[int], standing: Mapping[int, np.ndarray],
               at: np.ndarray | None = None) -> Scene:
    """``scene`` as the robots ``team`` plan in it: those robots only, at ``at`` ((len(team),
    2); default: their start rows), and each robot of ``standing`` (robot -> where it
    stands) a disk obstacle of the robot radius there (in robot order)."""
    stopped = tuple(Obstacle(Circle(float(scene.robot_radius)), (float(p[0]), float(p[1]), 0.0))
                    for _, p in sorted(standing.items()))
    out = replace(scene, robot_starts=tuple(scene.robot_starts[i] for i in team),
                  obstacles=tuple(scene.obstacles) + stopped, fixed=scene.fixed_obstacles)
    return out if at is None else out.with_robot_starts(at)


class TeamView:
    """``executor`` as the robots ``team`` see it: their positions only; their paths run
    with every other robot holding; ``team_changed`` turns True once one of them fails
    during a call (the closed loop then stops, and the runner plans anew). The fleet
    schedule's view (``lamp.fleet.view.FleetView``) is one too, its paths run beside
    the other teams'."""

    def __init__(self, executor: WorldExecutor, team: list[int]) -> None:
        self.executor = executor
        self.team = list(team)
        self._failed = False

    @property
    def team_changed(self) -> bool:
        """Whether a robot of the team failed since the view was made."""
        return self._failed

    @property
    def hooks(self) -> LoopHooks:
        """What its loop is told and asks (``LoopHooks``): whether the team changed."""
        return LoopHooks(team_changed=lambda: self.team_changed)

    @property
    def object_poses(self) -> np.ndarray:
        return self.executor.object_poses

    @property
    def robot_positions(self) -> np.ndarray:
        return np.asarray(self.executor.robot_positions, float)[self.team]

    def execute(self, robot_paths: np.ndarray, record_every: int | None = None,
                stop: Callable[[np.ndarray], bool] | None = None) -> Execution:
        paths = np.asarray(robot_paths, float)
        full = np.repeat(np.asarray(self.executor.robot_positions, float)[:, None],
                         paths.shape[1], axis=1)
        full[self.team] = paths
        out = self.executor.execute(full, record_every=record_every, stop=stop)
        if set(self.executor.failed) & set(self.team):
            self._failed = True
        return replace(out, robot_positions=np.asarray(out.robot_positions)[self.team])
