"""Building a :class:`~lamp.record.format.Recording` while a run executes.

``Recorder`` is the observer ``lamp.planners.closed_loop.run_object`` calls after every
executed segment; it keeps the segment's traced trajectories, contacts, pushes and the plan
in force, and ``finish`` packs them into the arrays of ``lamp-recording/1``. Plans are
stored once each: consecutive segments executing the same plan share its entry.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lamp.geometry.se2 import transform_points
from lamp.record.format import OUTCOMES, Recording
from lamp.scene.model import Scene


def _offsets(counts: list[int]) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(counts, dtype=np.int64)]).astype(np.int64)


def _stack(parts: list[np.ndarray], shape: tuple[int, ...], dtype: str) -> np.ndarray:
    if not parts:
        return np.zeros((0, *shape), dtype)
    return np.concatenate([np.asarray(p, float).reshape(-1, *shape) for p in parts]).astype(dtype)


def _edges(edges: Any) -> np.ndarray:
    """Object-level edges ((x, y, ...), (x, y, ...)) as an (E, 2, 2) float array."""
    arr = np.asarray(edges if edges is not None else [], dtype=float)
    if arr.size == 0:
        return np.zeros((0, 2, 2))
    return arr.reshape(len(arr), 2, -1)[:, :, :2]


class Recorder:
    """Collects executed segments of one run: a ``lamp.contract.events.RunObserver`` (or
    call it with each ``SegmentEvent``). ``sim_time_s`` is the simulated time recorded so
    far: the run's makespan in seconds once it is finished."""

    def __init__(self, scene: Scene, row_dt_s: float) -> None:
        self.scene = scene
        self.row_dt_s = float(row_dt_s)
        self._clock = 0.0
        self._times: list[np.ndarray] = [np.zeros(1)]
        self._robots: list[np.ndarray] = [scene.robot_starts_array[None]]
        self._objects: list[np.ndarray] = [scene.object_starts()[None]]
        self._rows = [0]
        self._seg: dict[str, list[Any]] = {k: [] for k in (
            "object", "plan", "outcome", "replanned", "planning", "sim", "drift", "from", "to")}
        self._contacts: list[np.ndarray] = []
        self._pushes: list[np.ndarray] = []
        self._plans: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]] = []
        self._last_plan: Any = None
        #: Set by :meth:`follow`: the run keeps the clock (several objects move at once)
        #: and segment events carry no trace.
        self._following = False
        self._row_count = 0
        self._teams: list[np.ndarray] = []

    def follow(self, trace: Any, sim_time: float, team: np.ndarray | None = None) -> None:
        """Record a stretch of a run's shared clock (the fleet schedule, whose segments
        overlap in time); the segment events that follow record their data only, each
        ending at the row recorded last (so ``segment_rows`` holds the segments' end rows
        in the order they ended). ``team`` (N,): the object each robot worked for during
        the stretch (-1: none), kept as the optional ``robot_team`` array."""
        if not self._following:
            self._following = True
            self._robots[0] = trace.robot_positions[:1]
            self._objects[0] = trace.object_poses[:1]
            self._teams = [np.full((1, self.scene.n_robots), -1, np.int16)]
        if team is not None:
            self._teams.append(np.repeat(np.asarray(team, np.int16)[None],
                                         len(trace.times) - 1, axis=0))
        self._times.append(self._clock + trace.times[1:])
        self._robots.append(trace.robot_positions[1:])
        self._objects.append(trace.object_poses[1:])
        self._row_count += len(trace.times) - 1
        self._clock += float(sim_time)

    def __call__(self, event: Any) -> None:
        if self._following:
            self._rows.append(self._row_count)
        else:
            self._add_trace(event)
        trans = event.transition
        seg = self._seg
        seg["object"].append(event.object_index)
        seg["plan"].append(self._plan_index(event))
        seg["outcome"].append(OUTCOMES.index(event.outcome))
        seg["replanned"].append(bool(event.replanned))
        seg["planning"].append(float(event.planning_time_s))
        seg["sim"].append(float(event.execution.sim_time))
        seg["drift"].append(event.drift)
        seg["from"].append(np.asarray(trans.q_from, float))
        seg["to"].append(np.asarray(trans.q_to, float))
        contacts = np.asarray(trans.contacts, float).reshape(-1, 2)
        self._contacts.append(contacts)
        pushes = np.asarray(trans.pushes_local, float)
        if pushes.ndim != 3 or len(pushes) != len(contacts):
            raise ValueError(f"Recorder: pushes_local has shape {pushes.shape}, expected "
                             f"({len(contacts)}, H, 2), one push per contact")
        self._pushes.extend(transform_points(np.asarray(trans.q_from, float), pushes))

    def _add_trace(self, event: Any) -> None:
        trace = event.execution.trace
        if trace is None:
            raise ValueError("Recorder: the segment was executed without a trace")
        if len(self._seg["object"]) == 0:  # the true start state replaces the scene's
            self._robots[0] = trace.robot_positions[:1]
            self._objects[0] = trace.object_poses[:1]
        self._times.append(self._clock + trace.times[1:])
        self._robots.append(trace.robot_positions[1:])
        self._objects.append(trace.object_poses[1:])
        self._rows.append(self._rows[-1] + len(trace.times) - 1)
        self._clock += float(event.execution.sim_time)

    def segment(self, event: Any) -> None:
        self(event)

    def object_started(self, index: int, n_objects: int) -> None:
        pass

    def object_finished(self, index: int, n_objects: int, result: Any) -> None:
        pass

    @property
    def sim_time_s(self) -> float:
        """Simulated seconds recorded so far (the last time of the recording)."""
        return float(self._clock)

    def _plan_index(self, event: Any) -> int:
        plan = event.plan
        if plan is None:
            return -1
        if plan is self._last_plan:
            return len(self._plans) - 1
        self._last_plan = plan
        self._plans.append((event.object_index, np.asarray(plan.object_path, float),
                            _edges(plan.verified_edges), _edges(plan.penalised_edges)))
        return len(self._plans) - 1

    def finish(self, planner: str, seed: int, result: dict[str, Any]) -> Recording:
        """The recording of everything observed so far, with the run's ``result.json``."""
        seg = self._seg
        n_robots, n_objects = self.scene.n_robots, len(self.scene.objects)
        plans = self._plans
        arrays = {
            "times": np.concatenate(self._times).astype("float64"),
            "robots": _stack(self._robots, (n_robots, 2), "float32"),
            "objects": _stack(self._objects, (n_objects, 3), "float32"),
            "segment_rows": np.asarray(self._rows, np.int64),
            "segment_object": np.asarray(seg["object"], np.int32),
            "segment_plan": np.asarray(seg["plan"], np.int32),
            "segment_outcome": np.asarray(seg["outcome"], np.int8),
            "segment_replanned": np.asarray(seg["replanned"], bool),
            "planning_time_s": np.asarray(seg["planning"], np.float64),
            "sim_time_s": np.asarray(seg["sim"], np.float64),
            "drift": _stack(seg["drift"], (2,), "float32"),
            "planned_from": _stack(seg["from"], (3,), "float32"),
            "planned_to": _stack(seg["to"], (3,), "float32"),
            "contact_offsets": _offsets([len(c) for c in self._contacts]),
            "contacts": _stack(self._contacts, (2,), "float32"),
            "push_offsets": _offsets([len(p) for p in self._pushes]),
            "pushes": _stack(self._pushes, (2,), "float32"),
            "plan_object": np.asarray([p[0] for p in plans], np.int32),
            "plan_path_offsets": _offsets([len(p[1]) for p in plans]),
            "plan_path": _stack([p[1] for p in plans], (3,), "float32"),
            "verified_offsets": _offsets([len(p[2]) for p in plans]),
            "verified": _stack([p[2] for p in plans], (2, 2), "float32"),
            "penalised_offsets": _offsets([len(p[3]) for p in plans]),
            "penalised": _stack([p[3] for p in plans], (2, 2), "float32"),
        }
        if self._following and sum(len(t) for t in self._teams) == len(arrays["times"]):
            arrays["robot_team"] = np.concatenate(self._teams).astype(np.int16)
        return Recording(self.scene.to_dict(), planner, int(seed), result, self.row_dt_s, arrays)
