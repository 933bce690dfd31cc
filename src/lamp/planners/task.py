"""One manipulation task: move object ``index`` of a scene while the others stand still.

A ``ManipulationTask`` bundles what every planner asks repeatedly while moving one object,
and caches it: the object's collision space, the robots' configuration spaces (without the
object, and with the object at a given pose), and model proposals per requested motion.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.robot_space import RobotSpace
from lamp.planners.config import PlannerConfig
from lamp.scene.model import Scene, Shape


@dataclass
class TaskStats:
    """Counters reported in result.json's ``stats``."""

    verify_calls: int = 0
    verify_success: int = 0
    model_calls: int = 0
    gspi_calls: int = 0
    gspi_success: int = 0
    cache_hits: int = 0

    def add(self, other: TaskStats) -> None:
        for k, v in vars(other).items():
            setattr(self, k, getattr(self, k) + v)


@dataclass
class ManipulationTask:
    """Moving ``scene.objects[index]`` from ``object_poses[index]`` to its goal."""

    scene: Scene
    index: int
    object_poses: np.ndarray  # (K, 3) current poses of all objects
    model: Any  # a proposer: .propose(shape, motion, budget, k, seed)
    config: PlannerConfig
    seed: int = 0
    stats: TaskStats = field(default_factory=TaskStats)

    def __post_init__(self) -> None:
        self.object_poses = np.array(self.object_poses, dtype=float).reshape(-1, 3)
        self.object_space = ObjectSpace.from_scene(self.scene, self.index, self.object_poses)
        self.static_space = RobotSpace.from_scene(
            self.scene, object_poses=self.object_poses, exclude_objects=(self.index,)
        )
        self._spaces: dict[tuple, RobotSpace] = {}
        self._proposals: dict[tuple, list] = {}

    @property
    def shape(self) -> Shape:
        return self.scene.objects[self.index].shape

    @property
    def goal(self) -> np.ndarray:
        return np.asarray(self.scene.objects[self.index].goal, dtype=float)

    @property
    def robot_radius(self) -> float:
        return self.scene.robot_radius

    @property
    def n_robots(self) -> int:
        return self.scene.n_robots

    def poses_with(self, q_object: np.ndarray) -> np.ndarray:
        """All object poses with the manipulated object at ``q_object``."""
        poses = self.object_poses.copy()
        poses[self.index] = q_object
        return poses

    def robot_space_at(self, q_object: np.ndarray) -> RobotSpace:
        """Robot configuration space with the manipulated object at ``q_object`` (cached)."""
        key = tuple(np.round(np.asarray(q_object, float), 4))
        space = self._spaces.get(key)
        if space is None:
            if len(self._spaces) > 256:
                self._spaces.clear()
            space = RobotSpace.from_scene(self.scene, object_poses=self.poses_with(q_object))
            self._spaces[key] = space
        return space

    def proposals(self, motion: np.ndarray, budget: int, attempt: int) -> list:
        """K model proposals for ``motion`` (object frame) with ``budget`` robots.

        Cached per (motion, budget, attempt): the object frame makes proposals independent
        of where the object is, so lattice primitives are answered once; a repeated
        verification of the same edge (``attempt`` > 0) draws fresh samples, as the paper
        relies on (Sec. III-A-1: "a different sampling in a future call may yield valid
        manipulation trajectories").
        """
        key = (tuple(np.round(np.asarray(motion, float), 4)), int(budget), int(attempt))
        props = self._proposals.get(key)
        if props is None:
            seed = _stable_seed(self.seed, key)
            props = self.model.propose(self.shape, motion=tuple(map(float, motion)), budget=budget,
                                       k=self.config.k, seed=seed)
            self.stats.model_calls += 1
            self._proposals[key] = props
        else:
            self.stats.cache_hits += 1
        return props


def _stable_seed(seed: int, key: tuple) -> int:
    """A deterministic 31-bit seed from a run seed and a hashable key (no Python hash())."""
    motion, budget, attempt = key
    words = [seed, budget, attempt, *[int(round(m * 1e4)) + 10**6 for m in motion]]
    return int(np.random.default_rng([abs(int(w)) for w in words]).integers(2**31 - 1))
