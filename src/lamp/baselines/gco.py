"""The GCo baselines (``gco-ori``, ``gco-var``): GCo's own manipulation loop, no verification.

Each iteration (as GCo drives a manipulation, the LAMP paper's baseline): weighted A* (w = 2)
for the object alone on a 0.1 m / 0.1 rad lattice, with the object inflated by 0.2 m
(``gco-ori``) or not at all (``gco-var``); take the waypoint about 0.3 m ahead; clamp the
step to +-0.2 m and +-0.3 rad; ask the model for ONE sample with budget = number of robots
(at most 3); route the robots to its contacts with Gspi; execute; repeat. Proposals are
never checked for collisions and robot-level feasibility is never verified: that is the
gap LAMP closes, and the baseline keeps it on purpose.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from lamp.contract.plan import Plan, PlanStatus
from lamp.contract.transition import Transition
from lamp.geometry import se2
from lamp.planners.config import PlannerConfig
from lamp.planners.task import ManipulationTask
from lamp.planners.verifier import Verifier
from lamp.search.gco_lattice import gco_object_path

#: ``object_path(q_O, inflation, time_limit)``: GCo's object-only lattice path from
#: ``q_O`` to the goal (an (M, 3) array, or None / empty when there is none).
ObjectPathSearch = Callable[[np.ndarray, float, float | None], "np.ndarray | None"]

LOOKAHEAD = 0.3  # m: the waypoint GCo steers towards
MAX_STEP_XY = 0.2  # m: step clamp per axis
MAX_STEP_THETA = 0.3  # rad


class GCoPlanner:
    """One GCo iteration per ``plan`` call: a single unverified push towards the goal."""

    def __init__(self, object_path: ObjectPathSearch, verifier: Verifier, config: PlannerConfig,
                 inflation: float, seed: int = 0) -> None:
        self.object_path = object_path
        self.verifier = verifier
        self.config = config
        self.inflation = inflation
        self.seed = int(seed)
        self.iteration = 0

    @classmethod
    def from_task(cls, task: ManipulationTask, inflation: float) -> GCoPlanner:
        """GCo for ``task``'s object: its lattice search (the other objects where the task
        has them), verifier, config and seed."""
        scene, index, poses = task.scene, task.index, task.object_poses

        def object_path(q_O: np.ndarray, inflation: float, time_limit: float | None):
            return gco_object_path(scene, index, q_O, poses, inflation, time_limit=time_limit)

        return cls(object_path, task.verifier, task.config, inflation, seed=task.seed)

    def _next_pose(self, q_O: np.ndarray, deadline: float | None) -> np.ndarray | None:
        remaining = None if deadline is None else max(1e-3, deadline - time.perf_counter())
        path = None
        # After a drift the object may sit inside the collision checker's conservative
        # band (about 1 cm) next to an obstacle; like LAMP's lattice join, a footprint
        # shrunk by up to 2 cm lets the search start from there.
        for shrink in (0.0, 0.02):
            path = self.object_path(q_O, self.inflation - shrink, remaining)
            if path is not None and len(path) > 0:
                break
        if path is None or len(path) == 0:
            return None
        path = np.asarray(path, float)
        along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1))])
        idx = int(np.searchsorted(along, LOOKAHEAD))
        waypoint = path[min(idx, len(path) - 1)]
        motion = se2.relative(q_O, waypoint)
        motion[:2] = np.clip(motion[:2], -MAX_STEP_XY, MAX_STEP_XY)
        motion[2] = np.clip(motion[2], -MAX_STEP_THETA, MAX_STEP_THETA)
        return se2.compose(q_O, motion)

    def report_failure(self, trans: Transition) -> None:
        """GCo learns nothing from a failed push (it never verifies one)."""

    def clear(self) -> None:
        self.iteration = 0

    def plan(self, q_O: np.ndarray, q_R: np.ndarray, deadline: float | None = None) -> Plan:
        self.iteration += 1
        q_O = np.asarray(q_O, float)
        q_R = np.asarray(q_R, float)
        q_to = self._next_pose(q_O, deadline)
        if q_to is None:
            timed_out = deadline is not None and time.perf_counter() > deadline
            if timed_out:
                return Plan.failed(PlanStatus.TIME_LIMIT, limit="deadline")
            return Plan.failed(PlanStatus.NO_PATH)
        motion = se2.relative(q_O, q_to)
        budget = min(self.verifier.n_robots, self.config.verify.max_budget)
        seed = (self.seed * 7919 + self.iteration) % (2**31 - 1)
        # one fresh sample, no Collide
        pushes_local = self.verifier.proposals.sample(motion, budget, seed)
        trans = self.verifier.route_push(q_O, q_to, q_R, pushes_local, deadline=deadline)
        if trans is None:
            return Plan.failed(PlanStatus.PUSH_UNREACHABLE)
        return Plan(PlanStatus.SOLVED, [trans], [(q_O[:2].copy(), q_to[:2].copy())], [])
