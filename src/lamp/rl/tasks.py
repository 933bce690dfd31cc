"""The mid-level task: push the object to a subgoal a short way along its object path.

This is what the MAPush-style high level (``lamp.baselines.mapush``) asks of the policy:
the object ``SUBGOAL_AHEAD`` metres further along its obstacle-aware lattice path, within
``SUBGOAL_TOLERANCE`` (orientation ignored), in ``SUBGOAL_TIME`` simulated seconds, with
the robots driving at ``ROBOT_SPEED`` (every planner's speed: the scene format's default
``robots.speed``). The time is what a robot at that speed needs to drive ``SUBGOAL_DRIVE``
metres, so the task is stated in distances and scales with the speed.

Episodes (``EpisodeSampler``) are drawn from a list of maps (training: maps of the paper
families' generators with seeds of their own, ``lamp.rl.maps``; evaluation: the benchmark
scenes, ``lamp.rl.evaluate``): a pose along the object's lattice path from its start to
its goal, the subgoal further along that path, and the robots scattered in free space up
to ``scatter`` metres from the object's bounding circle. Two *tasks*:

* ``open``: the same map with its obstacles removed (the workspace border stays). This is
  MAPush's mid-level protocol (its mid level trains and is measured in open space; the
  high level handles obstacles) and the task the success target refers to.
* ``maps``: the map as it is, obstacles included (what the benchmark then meets).

``Curriculum`` moves training from easy to hard by the share of training done (a count,
so a run is reproducible): robots start close to the object and only in open space, then
scatter up to ``ROBOT_SCATTER``, then half the episodes are on the cluttered maps.
Everything is seeded by its generator: the same seed gives the same episodes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from lamp.geometry.robot_space import RobotSpace
from lamp.scene.model import Scene
from lamp.scene.physics import DEFAULT_PHYSICS

#: Distance along the object path from the object to its subgoal [m] (high and mid level).
SUBGOAL_AHEAD = 0.5
#: The mid level's success radius around a subgoal [m].
SUBGOAL_TOLERANCE = 0.15
#: The robots' driving speed of the mid-level task [m/s]: the scene format's default
#: ``robots.speed``, what every other planner's robots drive at. A policy drives scenes at
#: this speed only (``lamp.baselines.mapush.check_scene``).
ROBOT_SPEED = DEFAULT_PHYSICS.robot_speed
#: Driving distance the mid level gets per subgoal [m] (a robot may have to go round the
#: object before it pushes).
SUBGOAL_DRIVE = 4.0
#: Simulated time the mid level gets per subgoal [s]: ``SUBGOAL_DRIVE`` at ``ROBOT_SPEED``
#: (16 s at 0.25 m/s).
SUBGOAL_TIME = SUBGOAL_DRIVE / ROBOT_SPEED
#: Robots start at most this far from the object's bounding circle [m] (suite scenes place
#: them up to about 0.6 m away; later subgoals find them right at the object).
ROBOT_SCATTER = 0.8
#: The paper's single-object families: training maps come from their generators
#: (``lamp.rl.maps``), evaluation episodes from their benchmark suites.
FAMILIES = ("random", "maze", "tilt", "warehouse")
#: The two tasks (see the module docstring).
TASKS = ("open", "maps")


def along(path: np.ndarray) -> np.ndarray:
    """Cumulative translation length along a (P, 3) pose path."""
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path[:, :2], axis=0).T))])


def pose_at(path: np.ndarray, s: float) -> np.ndarray:
    """The path pose at arc length ``s`` (clamped to the path; poses are not interpolated
    across headings: the next lattice pose at or after ``s``)."""
    acc = along(path)
    return path[min(int(np.searchsorted(acc, s)), len(path) - 1)].copy()


def open_variant(scene: Scene) -> Scene:
    """``scene`` without its obstacles (same workspace, robots and objects)."""
    return replace(scene, name=f"{scene.name}-open", obstacles=(), source=None)


def scatter_robots(scene: Scene, poses: np.ndarray, index: int, rng: np.random.Generator,
                   near: float = ROBOT_SCATTER, tries: int = 400) -> np.ndarray | None:
    """Robot centres in free space within ``near`` of object ``index``'s bounding circle,
    not overlapping each other; None when no placement was found."""
    space = RobotSpace.from_scene(scene, object_poses=poses, robot_radius=scene.robot_radius)
    r = scene.robot_radius
    c = poses[index, :2]
    bound = scene.objects[index].shape.bounding_radius
    out: list[np.ndarray] = []
    for _ in range(tries):
        ang = rng.uniform(-math.pi, math.pi)
        dist = bound + r + rng.uniform(0.01, max(near, 0.02))
        p = c + dist * np.array([math.cos(ang), math.sin(ang)])
        if not space.is_free(p[None])[0]:
            continue
        if any(np.hypot(*(p - q)) < 2 * r + 0.01 for q in out):
            continue
        out.append(p)
        if len(out) == scene.n_robots:
            return np.array(out)
    return None


@dataclass(frozen=True)
class Stage:
    """How hard the episodes are: robot scatter [m] and the share on cluttered maps."""

    scatter: float = ROBOT_SCATTER
    maps_share: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.scatter) and 0.0 < self.scatter <= 5.0):
            raise ValueError(f"scatter = {self.scatter!r}: must be in (0, 5] m")
        if not (0.0 <= self.maps_share <= 1.0):
            raise ValueError(f"maps_share = {self.maps_share!r}: must be in [0, 1]")


def task_stage(task: str) -> Stage:
    """The evaluation stage of ``task`` (full scatter; open space or the maps)."""
    if task not in TASKS:
        raise ValueError(f"task = {task!r}: must be one of {', '.join(TASKS)}")
    return Stage(ROBOT_SCATTER, 1.0 if task == "maps" else 0.0)


@dataclass(frozen=True)
class Curriculum:
    """Stage as a function of the share of training done, ``f`` in [0, 1]: scatter rises
    linearly from ``scatter0`` to ``ROBOT_SCATTER`` until ``f = scatter_until``; the share
    of cluttered-map episodes rises linearly from 0 at ``maps_from`` to ``maps_share`` at
    ``maps_full``."""

    scatter0: float = 0.25
    scatter_until: float = 0.4
    maps_from: float = 0.3
    maps_full: float = 0.6
    maps_share: float = 0.5

    def stage(self, f: float) -> Stage:
        f = min(max(f, 0.0), 1.0)
        s = self.scatter0 + (ROBOT_SCATTER - self.scatter0) * min(1.0, f / self.scatter_until)
        span = max(self.maps_full - self.maps_from, 1e-9)
        m = self.maps_share * min(1.0, max(0.0, (f - self.maps_from) / span))
        return Stage(s, m)


class EpisodeSampler:
    """Random mid-level episodes over ``scenes`` (each with one object path from its start
    to its goal; paths computed once per scene, on demand)."""

    def __init__(self, scenes: list[Scene], seed: int) -> None:
        if not scenes:
            raise ValueError("EpisodeSampler: no scenes")
        self.scenes = list(scenes)
        self.opens = [open_variant(s) for s in self.scenes]
        self.rng = np.random.default_rng(seed)
        self._paths: dict[int, np.ndarray | None] = {}

    def path(self, k: int) -> np.ndarray | None:
        """Object 0's lattice path from its start to its goal in scene k (cached)."""
        if k not in self._paths:
            from lamp.search.gco_lattice import gco_object_path

            sc = self.scenes[k]
            p = gco_object_path(sc, 0, sc.objects[0].start, inflation=0.0, time_limit=5.0)
            self._paths[k] = None if p is None or len(p) < 2 else np.asarray(p, float)
        return self._paths[k]

    def sample(self, stage: Stage) -> tuple[Scene, dict[str, Any]]:
        """(scene, reset options) of one episode of ``stage``."""
        for _ in range(1000):
            k = int(self.rng.integers(len(self.scenes)))
            on_map = self.rng.random() < stage.maps_share
            path = self.path(k)
            if path is None:
                continue
            total = along(path)[-1]
            s = self.rng.uniform(0.0, max(total - 0.1, 0.0))
            pose = pose_at(path, s)
            goal = pose_at(path, s + SUBGOAL_AHEAD)
            if math.hypot(*(goal[:2] - pose[:2])) <= SUBGOAL_TOLERANCE:
                continue
            scene = self.scenes[k] if on_map else self.opens[k]
            poses = scene.object_starts()
            poses[0] = pose
            robots = scatter_robots(scene, poses, 0, self.rng, near=stage.scatter)
            if robots is None:
                continue
            return scene, {"object_poses": poses, "robot_positions": robots, "goal": goal}
        raise RuntimeError("EpisodeSampler: no episode found in 1000 tries")


#: Physics steps per policy step of the mid level (50 ms at the simulator's 2 ms).
MID_FRAME_SKIP = 25
#: Reward weights of the mid-level task (``lamp.env.core.RewardWeights`` fields): the
#: defaults plus MAPush's "robots behind the object" term.
MID_REWARD = {"behind": 1.0}


def mid_level_config(frame_skip: int = MID_FRAME_SKIP, **settings: Any):
    """The ``PushConfig`` of the mid-level task: robots at ``ROBOT_SPEED``, ``SUBGOAL_TIME``
    per episode (``settings`` override fields, e.g. a trained policy's speed, time and
    patch settings)."""
    from lamp.env.core import PushConfig, RewardWeights

    fields = {"max_speed": ROBOT_SPEED, "time_limit": SUBGOAL_TIME, **settings}
    return PushConfig(position_tolerance=SUBGOAL_TOLERANCE, orientation_tolerance=None,
                      frame="goal", frame_skip=frame_skip,
                      reward=RewardWeights(**MID_REWARD), **fields)


def check_speed(scenes, speed: float, what: str) -> None:
    """ValueError naming the first of ``scenes`` whose ``robots.speed`` is not ``speed``
    (``what``: who refuses it)."""
    for sc in scenes:
        if not math.isclose(sc.physics.robot_speed, speed, rel_tol=0, abs_tol=1e-9):
            raise ValueError(f"{what}: scene {sc.name!r} has robots.speed = "
                             f"{sc.physics.robot_speed:g} m/s, but the mid-level policy is "
                             f"trained for {speed:g} m/s")
