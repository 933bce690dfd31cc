"""One manipulation task: move object ``index`` of a scene while the others stand still.

A ``ManipulationTask`` builds the pieces a planner is given for one object, and caches
what they ask repeatedly: the object's collision space (for the lattice), the robots'
configuration spaces (without the object, and with the object at a given pose: the task
is the ``RobotValidity`` of its ``Verifier``) and the :class:`Verifier` itself, which owns
the model proposals per requested motion and the counters. Planners hold the lattice, the
verifier and the config, never the task.

Robot spaces are built over a *window* of the map around the object and the robots
(:meth:`ManipulationTask.window`): approach paths, waiting spots and ``Collide`` are local
to them, so memory and time per space grow with that window, not with the map. Windows
are snapped to a 1 m grid (nearby poses share spaces) and at least 4 m wide (the paper's
4 m maps are always covered whole).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from lamp.geometry.clearance_layers import lru_get, lru_put
from lamp.geometry.exact_space import ExactSpace
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.robot_space import RobotSpace
from lamp.planners.config import PlannerConfig
from lamp.planners.robot_routing import GspiRouter
from lamp.planners.task_stats import TaskStats
from lamp.planners.verifier import Verifier
from lamp.scene.model import Obstacle, Scene, Shape
from lamp.search.landmark import route_length

#: Margin (m) of a robot-space window around the object and the robots; more than the
#: waiting-spot search radius of ``Reassign`` plus a robot.
WINDOW_MARGIN = 1.5
#: Windows are snapped outward to multiples of this (m), so that nearby poses share spaces.
WINDOW_SNAP = 1.0
#: Smallest window side (m), where the map allows.
WINDOW_MIN_SIDE = 4.0
#: Largest window side (m) a failed approach may grow its window to.
WINDOW_MAX_SIDE = 16.0
#: Robot spaces kept per task: at most this many (and ``LoopConfig.space_cache_mb``).
_SPACES_KEPT = 64


def route_distance(scene: Scene, index: int, pose: np.ndarray, step: float) -> float:
    """How far object ``index`` has to go from ``pose`` to its goal around the map's
    obstacles (the other objects move, so they do not count): the longer of the straight
    line and ``landmark.route_length`` on a grid of side ``step`` (the straight line when
    no route joins them). What a scaled segment limit is measured on
    (``config.segment_limit``)."""
    obj = scene.objects[index]
    start, goal = np.asarray(pose, float), np.asarray(obj.goal, float)
    straight = float(np.hypot(*(goal[:2] - start[:2])))
    space = ObjectSpace(obj.shape, scene.workspace, scene.obstacles, static=scene.fixed_obstacles)
    route = route_length(space, (start[0], start[1]), (goal[0], goal[1]), step)
    return straight if route is None else max(straight, route)


@dataclass
class ManipulationTask:
    """Moving ``scene.objects[index]`` from ``object_poses[index]`` to its goal."""

    scene: Scene
    index: int
    object_poses: np.ndarray  # (K, 3) current poses of all objects
    model: Any  # a proposer: .propose(shape, motion, budget, k, seed)
    config: PlannerConfig
    seed: int = 0
    #: The largest window side ``Verifier.approach`` may grow a window to (``RobotValidity``).
    max_window_side: ClassVar[float] = WINDOW_MAX_SIDE

    def __post_init__(self) -> None:
        self.object_poses = np.array(self.object_poses, dtype=float).reshape(-1, 3)
        self.object_space = ObjectSpace.from_scene(self.scene, self.index, self.object_poses)
        self._exact_space: ExactSpace | None = None
        self._spaces: OrderedDict[tuple, RobotSpace] = OrderedDict()
        self._layer: tuple[tuple, RobotSpace] | None = None  # _space_with_object's
        #: This object's ``Verifier``: the model, this task as its ``RobotValidity``, Gspi
        #: over this scene, and the config's Verify parameters. It owns the proposal cache
        #: and the counters (``stats``).
        self.verifier = Verifier(
            self.model, self.shape, self.scene.robot_radius, self.scene.n_robots, self,
            GspiRouter(self.scene, self.index, self.object_poses.copy(), seed=self.seed,
                       goal_tolerance=self.config.verify.contact_tolerance),
            self.config.verify, seed=self.seed)

    def close(self) -> None:
        """Let go of what this task holds once its loop has ended: its robot-space cache,
        its exact space and its Verifier's reference back to it. The task and its
        Verifier refer to each other, so without this they and their caches (some 40 MB
        per object on a 40 x 30 m map) wait for the garbage collector's rare full pass:
        a fleet's finished objects piled up so (``tests/test_verify.py``). ``stats``
        stays readable."""
        self._spaces.clear()
        self._layer = None
        self._exact_space = None
        self.verifier.robots = None  # type: ignore[assignment]

    @property
    def exact_space(self) -> ExactSpace:
        """The exact twin of ``object_space`` (built on first use), the one shared by the
        refined lattice and the closed loop's drift limits."""
        if self._exact_space is None:
            self._exact_space = ExactSpace.from_space(self.object_space)
        return self._exact_space

    @property
    def stats(self) -> TaskStats:
        """The counters of this object's ``verifier``."""
        return self.verifier.stats

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

    @property
    def static_space(self) -> RobotSpace:
        """Robot space of the whole map without the manipulated object (the other objects
        at their poses); planners use the windowed :meth:`static_space_near`."""
        return RobotSpace.from_scene(self.scene, object_poses=self.object_poses,
                                     exclude_objects=(self.index,))

    def window(self, q_object: np.ndarray, points: np.ndarray | None = None,
               scale: float = 1.0) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1): the robot-space window for the object at ``q_object`` and the
        (K, 2) ``points`` (robots, goals): their bounding box grown by the object's
        bounding radius and ``scale * WINDOW_MARGIN``, snapped outward to ``WINDOW_SNAP``,
        widened to ``scale * WINDOW_MIN_SIDE`` (at most the map) and kept inside the map.
        Every given point and the whole object lie inside it, at least the margin from
        its sides that face into the map."""
        W, H = (float(v) for v in self.scene.workspace)
        q = np.asarray(q_object, float).reshape(3)
        rad = float(self.shape.bounding_radius)
        lo = q[:2] - rad
        hi = q[:2] + rad
        if points is not None and len(points):
            pts = np.asarray(points, float).reshape(-1, 2)
            lo = np.minimum(lo, pts.min(axis=0))
            hi = np.maximum(hi, pts.max(axis=0))
        m = scale * WINDOW_MARGIN
        out = []
        for axis, size in ((0, W), (1, H)):
            a = max(0.0, WINDOW_SNAP * math.floor((lo[axis] - m) / WINDOW_SNAP))
            b = min(size, WINDOW_SNAP * math.ceil((hi[axis] + m) / WINDOW_SNAP))
            short = min(size, scale * WINDOW_MIN_SIDE) - (b - a)
            if short > 0:  # widen both ways, then shift back inside the map
                a, b = a - 0.5 * short, b + 0.5 * short
                a, b = (0.0, b - a) if a < 0 else (a, b)
                a, b = (max(0.0, a - (b - size)), size) if b > size else (a, b)
                a = max(0.0, WINDOW_SNAP * math.floor(a / WINDOW_SNAP + 1e-9))
                b = min(size, WINDOW_SNAP * math.ceil(b / WINDOW_SNAP - 1e-9))
            out.append((a, b))
        (x0, x1), (y0, y1) = out
        return (x0, y0, x1, y1)

    def robot_space_at(self, q_object: np.ndarray,
                       window: tuple[float, float, float, float] | None = None) -> RobotSpace:
        """Robot configuration space with the manipulated object at ``q_object``, over
        ``window`` (default: the whole map). Cached, bounded in entries and bytes."""
        key = (tuple(np.round(np.asarray(q_object, float), 4)),
               None if window is None else tuple(float(v) for v in window))
        return self._cached(key, lambda: self._space_with_object(q_object, window))

    def _space_with_object(self, q_object: np.ndarray,
                           window: tuple[float, float, float, float] | None) -> RobotSpace:
        """:meth:`robot_space_at`'s space, built. Over a window: the space without the
        object there (kept for the last window asked: a plan's Verify calls ask one window
        after another) with the object laid over it, ``RobotSpace.with_obstacle``, the
        space ``RobotSpace.from_scene`` builds with the object at ``q_object``."""
        if window is None:
            return RobotSpace.from_scene(self.scene, object_poses=self.poses_with(q_object))
        if self._layer is None or self._layer[0] != window:
            self._layer = (window, RobotSpace.from_scene(
                self.scene, object_poses=self.object_poses, exclude_objects=(self.index,),
                window=window))
        at = len(self.scene.obstacles) - len(self.scene.fixed_obstacles) + self.index
        pose = tuple(float(v) for v in np.asarray(q_object, float).reshape(3))
        return self._layer[1].with_obstacle(Obstacle(self.shape, pose), at)

    def _cached(self, key: tuple, build: Callable[[], RobotSpace]) -> RobotSpace:
        """The robot space cached under ``key``, built by ``build`` on a miss; the least
        recently used are dropped beyond ``_SPACES_KEPT`` entries or
        ``LoopConfig.space_cache_mb`` (the newest is always kept)."""
        space = lru_get(self._spaces, key)
        if space is None:
            space = build()
            lru_put(self._spaces, key, space, _SPACES_KEPT,
                    self.config.loop.space_cache_mb * 2**20, lambda sp: sp.nbytes)
        return space

    def static_space_near(self, q_object: np.ndarray) -> RobotSpace:
        """The space without the manipulated object (see :attr:`static_space`) over the
        window of :meth:`window` around ``q_object``: it answers every point within
        ``WINDOW_MARGIN`` of the object (farther points may read as not free). Cached by
        window (the other objects stand still for the task's life)."""
        window = self.window(q_object)
        return self._cached(("static", window), lambda: RobotSpace.from_scene(
            self.scene, object_poses=self.object_poses, exclude_objects=(self.index,),
            window=window))
