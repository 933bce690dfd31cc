"""Tasks while the fleet works: their records, where they come from, and the figures of
a lifelong run.

A task (``scene.model.Task``) asks that an object go to a goal from its release time on.
The fleet (``coordinator.Fleet``) takes its tasks from a :class:`TaskFeed`, the one
contract between the schedule and whatever supplies tasks: the scene file's list
(:class:`ScheduledFeed`) or a live service (``lamp.serve``). Each task has a
:class:`TaskRecord`; its status moves ``queued`` (released, not started) -> ``active``
(its object is being moved to its goal) -> ``done`` or ``failed`` (``TASK_MOVES``), and
the fleet tells the feed of every move (:meth:`TaskFeed.changed`).

Time is the simulation's: a task released at ``release_s`` is taken up at the first
event of the fleet's clock at or after it (the end of a running segment; when nothing
runs, the fleet idles exactly until the release, :meth:`TaskFeed.wait`). Idle time is
simulated until the world is at rest (nothing moved more than ``REST_M`` in a stretch),
then skipped: the clock moves on with nothing run (``rest_until``), unless the executor
is disturbed (its failures are timed by its own clock).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import Any, Protocol

import numpy as np

from lamp.contract.events import TRACE_EVERY
from lamp.contract.runner import ObjectOutcome
from lamp.scene.model import Scene
from lamp.scene.tasks import numbered, served_order

__all__ = ["IDLE_STRETCH_S", "REST_M", "TASK_MOVES", "ScheduledFeed", "TaskFeed",
           "TaskRecord", "TaskStatus", "at_rest", "hold_still", "lifelong_figures",
           "merged_tasks", "rest_until"]

#: The longest stretch (simulated s) the fleet idles at once, simulated, waiting for a
#: release; the feed is asked again after each (a live one may have a task by then).
IDLE_STRETCH_S = 5.0
#: How far (m) anything may move in a simulated idle stretch for the world to count as
#: at rest, after which idling needs no physics (``rest_until``).
REST_M = 1e-4


def at_rest(trace: Any) -> bool:
    """Whether no robot and no object moved more than ``REST_M`` during ``trace``."""
    robots = np.abs(trace.robot_positions - trace.robot_positions[:1]).max(initial=0.0)
    objects = np.abs(trace.object_poses[..., :2] - trace.object_poses[:1, :, :2])
    return max(float(robots), float(objects.max(initial=0.0))) <= REST_M


def rest_until(robots: np.ndarray, objects: np.ndarray, seconds: float) -> Any:
    """The result of holding a world at rest for ``seconds`` (robots at ``robots``, the
    objects' true poses ``objects``): nothing moves, so no physics is run; its trace is
    the world at the start and at the end (``sim.simulator.ExecutionResult``)."""
    from lamp.sim.simulator import ExecutionResult, Trace

    robots, objects = np.asarray(robots, float), np.asarray(objects, float)
    trace = Trace(np.array([0.0, float(seconds)]), np.stack([robots, robots]),
                  np.stack([objects, objects]))
    return ExecutionResult(objects, robots, False, np.zeros(len(objects), bool),
                           float(seconds), 0, np.zeros(len(robots)), trace)


def hold_still(executor: Any, now: np.ndarray, resting: bool, seconds: float
               ) -> tuple[Any, bool]:
    """``executor``'s robots hold still at ``now`` (their positions, (N, 2)) for
    ``seconds`` of simulated time: the result (without physics when the world was
    ``resting`` and nothing disturbs it, else a stretch of at most ``IDLE_STRETCH_S``
    simulated) and whether the world is at rest after it."""
    if resting and not executor.disturbed:
        return rest_until(now, executor.true_object_poses, max(seconds, 0.0)), True
    out = executor.execute(now[:, None], record_every=TRACE_EVERY,
                           settle_time=min(max(seconds, 1e-9), IDLE_STRETCH_S))
    return out, at_rest(out.trace)


class TaskStatus(StrEnum):
    """Where a task is (module docstring)."""

    QUEUED = "queued"
    ACTIVE = "active"
    DONE = "done"
    FAILED = "failed"


#: The allowed moves between task statuses.
TASK_MOVES: Mapping[TaskStatus, frozenset[TaskStatus]] = {
    TaskStatus.QUEUED: frozenset({TaskStatus.ACTIVE, TaskStatus.FAILED}),
    TaskStatus.ACTIVE: frozenset({TaskStatus.DONE, TaskStatus.FAILED}),
    TaskStatus.DONE: frozenset(),
    TaskStatus.FAILED: frozenset(),
}


@dataclass
class TaskRecord:
    """One task and what became of it (``result.json``'s ``tasks``; times in simulated
    seconds)."""

    id: int
    object: int
    goal: tuple[float, float, float]
    release_s: float
    status: TaskStatus = TaskStatus.QUEUED
    start_s: float | None = None
    done_s: float | None = None
    reason: str | None = None
    #: extra figures of the task (segments, replans)
    figures: dict[str, Any] = field(default_factory=dict)

    def move_to(self, status: TaskStatus, now: float, reason: str | None = None) -> None:
        """Its status becomes ``status`` at simulated time ``now`` (``start_s`` on
        becoming active, ``done_s`` on ending); ValueError, nothing changed, when
        ``TASK_MOVES`` does not allow it."""
        status = TaskStatus(status)
        if status not in TASK_MOVES[self.status]:
            raise ValueError(f"task {self.id}: {self.status} -> {status} is not a task move")
        self.status = status
        if status is TaskStatus.ACTIVE:
            self.start_s = float(now)
        else:
            self.done_s = float(now)
        if reason is not None:
            self.reason = reason

    @property
    def service_s(self) -> float | None:
        """Done time less release time (None unless done)."""
        return (None if self.status is not TaskStatus.DONE or self.done_s is None
                else self.done_s - self.release_s)

    def to_dict(self) -> dict[str, Any]:
        def r(t: float | None) -> float | None:
            return None if t is None else round(float(t), 4)

        return {"id": self.id, "object": self.object,
                "goal": [round(float(v), 6) for v in self.goal],
                "release_s": r(self.release_s), "status": str(self.status),
                "start_s": r(self.start_s), "done_s": r(self.done_s),
                "service_s": r(self.service_s), "reason": self.reason, **self.figures}


class TaskFeed(Protocol):
    """Where the fleet's tasks come from. Called from the fleet's threads (its event loop
    and its objects' loops, ``turns.Turns``), one at a time, never concurrently; a feed
    that other threads also touch (a live service's) guards its own state."""

    def released(self, now: float) -> list[TaskRecord]:
        """The tasks released at or before simulated time ``now`` that were not handed
        out before, by release time then id; each in status ``queued``."""
        ...

    def wait(self, now: float) -> float | None:
        """The fleet has nothing to do at ``now`` (every released task ended): the
        simulated time to idle until (>= ``now``; the robots hold still meanwhile), at
        which a task may be released; None when no task will come: the run ends."""
        ...

    def changed(self, task: TaskRecord) -> None:
        """``task`` moved to another status (its times and reason set)."""
        ...

    def moved(self, start_s: float, trace: Any) -> None:
        """The world moved: ``trace`` (``sim.simulator.Trace``: times from 0, robot
        positions, object poses, row by row) from simulated time ``start_s`` on."""
        ...

    @property
    def stopped(self) -> bool:
        """True when the run must end now: every task not done fails (``stopped``)."""
        ...


class ScheduledFeed:
    """The tasks of a scene file (``scene.tasks.numbered``), released at their times."""

    def __init__(self, scene: Scene) -> None:
        tasks = numbered(scene)
        self.records = [TaskRecord(i, t.object, tuple(float(v) for v in t.goal),  # type: ignore[arg-type]
                                   float(t.release_s)) for i, t in enumerate(tasks)]
        self._order = [self.records[i] for i in served_order(scene)]
        self._next = 0  # the first not handed out in ``_order``
        self.stopped = False

    def released(self, now: float) -> list[TaskRecord]:
        out = []
        while self._next < len(self._order) and self._order[self._next].release_s <= now:
            out.append(self._order[self._next])
            self._next += 1
        return out

    def wait(self, now: float) -> float | None:
        if self._next >= len(self._order):
            return None
        return max(float(now), self._order[self._next].release_s)

    def changed(self, task: TaskRecord) -> None:
        """Nothing to tell: the records are this feed's own."""

    def moved(self, start_s: float, trace: Any) -> None:
        """Nothing to show."""


def merged_tasks(parts: Sequence[ObjectOutcome]) -> ObjectOutcome | None:
    """One object's outcome over its tasks: the last task's verdict, pose and goal, every
    task's segments, replans, planning and makespan (None: it served none; one task: its
    outcome as it is)."""
    if len(parts) <= 1:
        return parts[0] if parts else None
    last = parts[-1]
    result = replace(last.result, segments=sum(p.result.segments for p in parts),
                     replans=sum(p.result.replans for p in parts),
                     full_horizon_plan=all(p.result.full_horizon_plan for p in parts),
                     planning_time_s=sum(p.result.planning_time_s for p in parts))
    return replace(last, result=result,
                   planning_time_s=[t for p in parts for t in p.planning_time_s],
                   makespan=sum(p.makespan for p in parts),
                   unexecuted_planning_s=sum(p.unexecuted_planning_s for p in parts))


def lifelong_figures(tasks: Sequence[TaskRecord], makespan_s: float,
                     utilisation: Mapping[str, float] | None = None) -> dict[str, Any]:
    """A lifelong run's figures: tasks done and failed, throughput (tasks done per
    simulated hour over ``makespan_s``), service time (done - release) median and 95th
    percentile, and the robots' ``utilisation`` (``stats.RobotTime.shares``) if given."""
    service = np.array([t.service_s for t in tasks if t.service_s is not None], float)
    hours = max(float(makespan_s), 1e-9) / 3600.0

    def pct(q: float) -> float | None:
        return round(float(np.percentile(service, q)), 4) if len(service) else None

    out: dict[str, Any] = {
        "tasks": len(tasks),
        "done": int(sum(t.status is TaskStatus.DONE for t in tasks)),
        "failed": int(sum(t.status is TaskStatus.FAILED for t in tasks)),
        "throughput_per_hour": round(len(service) / hours, 4),
        "service_median_s": pct(50),
        "service_p95_s": pct(95),
    }
    if utilisation is not None:
        out["utilisation"] = dict(utilisation)
    return out
