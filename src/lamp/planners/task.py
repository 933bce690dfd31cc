"""One manipulation task: move object ``index`` of a scene while the others stand still.

A ``ManipulationTask`` bundles what every planner asks repeatedly while moving one object,
and caches it: the object's collision space, the robots' configuration spaces (without the
object, and with the object at a given pose), and model proposals per requested motion.

Robot spaces are built over a *window* of the map around the object and the robots
(:meth:`ManipulationTask.window`): approach paths, waiting spots and ``Collide`` are local
to them, so memory and time per space grow with that window, not with the map. Windows
are snapped to a 1 m grid (nearby poses share spaces) and at least 4 m wide (the paper's
4 m maps are always covered whole).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.robot_space import RobotSpace
from lamp.geometry.shapes import signed_distance
from lamp.planners.config import PlannerConfig
from lamp.planners.trajectory import MAX_STEP, densify
from lamp.scene.model import Scene, Shape

#: Margin (m) of a robot-space window around the object and the robots; more than the
#: waiting-spot search radius of ``Reassign`` plus a robot.
WINDOW_MARGIN = 1.5
#: Windows are snapped outward to multiples of this (m), so that nearby poses share spaces.
WINDOW_SNAP = 1.0
#: Smallest window side (m), where the map allows.
WINDOW_MIN_SIDE = 4.0
#: Largest window side (m) a failed approach may grow its window to.
WINDOW_MAX_SIDE = 16.0
#: Robot spaces kept per task: at most this many, and this many bytes in all.
_SPACES_KEPT = 64
_SPACES_BYTES = 96 * 2**20


@dataclass(frozen=True)
class PushCandidates:
    """The K proposals for one (motion, budget, attempt), prepared for fast ``Collide`` checks.

    A proposal lives in the object frame, and rigid motions preserve distances and linear
    interpolation, so two of ``Collide``'s three tests do not depend on where the object
    is: a contact inside the object and two pushing robots closer than 2r. They are done
    once here (``intrinsic_ok``). The third, push paths in the robots' free space, is
    done per pose on ``dense_points``: every push path densified to ``MAX_STEP / 2`` in
    the object frame and stacked, proposal ``i`` owning rows ``starts[i]:starts[i + 1]``.
    """

    pushes_local: list[np.ndarray]  # K arrays (B, H, 2), object frame
    intrinsic_ok: np.ndarray  # (K,) bool
    dense_points: np.ndarray  # (P, 2) stacked densified push points, object frame
    starts: np.ndarray  # (K + 1,) row offsets into dense_points


def pairwise_min_distance(paths: np.ndarray) -> float:
    """Smallest distance between any two of the (B, T, 2) synchronised paths."""
    b = paths.shape[0]
    if b < 2:
        return np.inf
    i, j = np.triu_indices(b, 1)
    d = paths[i] - paths[j]
    return float(np.sqrt(np.min(d[..., 0] ** 2 + d[..., 1] ** 2)))


@dataclass
class TaskStats:
    """Counters reported in result.json's ``stats``."""

    verify_calls: int = 0
    verify_success: int = 0
    model_calls: int = 0
    gspi_calls: int = 0
    gspi_success: int = 0
    #: Gspi calls ended by the wall-clock cap ``gspi_time_limit`` (0 on an unloaded
    #: machine: then no result depended on the clock).
    gspi_timeouts: int = 0
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
        self._spaces: OrderedDict[tuple, RobotSpace] = OrderedDict()
        self._proposals: dict[tuple, list] = {}
        self._candidates: dict[tuple, PushCandidates] = {}

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
        space = self._spaces.get(key)
        if space is None:
            space = RobotSpace.from_scene(self.scene, object_poses=self.poses_with(q_object),
                                          window=window)
            self._spaces[key] = space
            total = sum(sp.nbytes for sp in self._spaces.values())
            while len(self._spaces) > 1 and (len(self._spaces) > _SPACES_KEPT
                                             or total > _SPACES_BYTES):
                _, old = self._spaces.popitem(last=False)
                total -= old.nbytes
        else:
            self._spaces.move_to_end(key)
        return space

    def static_space_near(self, q_object: np.ndarray) -> RobotSpace:
        """The space without the manipulated object (see :attr:`static_space`) over the
        window of :meth:`window` around ``q_object``: it answers every point within
        ``WINDOW_MARGIN`` of the object (farther points may read as not free)."""
        return RobotSpace.from_scene(self.scene, object_poses=self.object_poses,
                                     exclude_objects=(self.index,),
                                     window=self.window(q_object))

    def proposals(self, motion: np.ndarray, budget: int, attempt: int) -> list:
        """K model proposals for ``motion`` (object frame) with ``budget`` robots.

        Cached per (motion, budget, attempt): the object frame makes proposals independent
        of where the object is, so lattice primitives are answered once; a repeated
        verification of the same edge (``attempt`` > 0) draws fresh samples, as the paper
        relies on (Sec. III-A-1: "a different sampling in a future call may yield valid
        manipulation trajectories").
        """
        key = _proposal_key(motion, budget, attempt)
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


    def push_candidates(self, motion: np.ndarray, budget: int, attempt: int) -> PushCandidates:
        """``proposals`` prepared for ``Collide`` (see ``PushCandidates``), cached alike."""
        key = _proposal_key(motion, budget, attempt)
        cands = self._candidates.get(key)
        if cands is None:
            cands = self._prepare(self.proposals(motion, budget, attempt))
            self._candidates[key] = cands
        else:
            self.stats.cache_hits += 1
        return cands

    def _prepare(self, props: list) -> PushCandidates:
        r = self.robot_radius
        pushes = [np.asarray(p.pushes, float) for p in props]
        dense = [densify(p, MAX_STEP / 2) for p in pushes]
        ok = np.array([
            bool(np.all(signed_distance(self.shape, p[:, 0]) >= r - self.config.contact_tolerance))
            and pairwise_min_distance(d) >= 2 * r - 1e-9
            for p, d in zip(pushes, dense, strict=True)
        ], dtype=bool)
        sizes = [d.shape[0] * d.shape[1] for d in dense]
        points = np.concatenate([d.reshape(-1, 2) for d in dense]) if dense else np.zeros((0, 2))
        return PushCandidates(pushes, ok, points, np.concatenate([[0], np.cumsum(sizes)]).astype(int))


def _proposal_key(motion: np.ndarray, budget: int, attempt: int) -> tuple:
    """Cache key of a proposal request: the motion rounded to 0.1 mm / 0.1 mrad."""
    return tuple(np.round(np.asarray(motion, float), 4)), int(budget), int(attempt)


def _stable_seed(seed: int, key: tuple) -> int:
    """A deterministic 31-bit seed from a run seed and a hashable key (no Python hash())."""
    motion, budget, attempt = key
    words = [seed, budget, attempt, *[int(round(m * 1e4)) + 10**6 for m in motion]]
    return int(np.random.default_rng([abs(int(w)) for w in words]).integers(2**31 - 1))
