"""The fleet's task desk: which task each object serves, and which wait their turn.

:class:`TaskDesk` takes the released tasks from the run's ``tasks.TaskFeed``, queues them
per object (an object serves its tasks one after another, in release order), hands an
object its next task when it has none, and moves each task's status as the coordinator
reports (``begin``, ``end``), telling the feed of every move. It decides nothing about
robots or motion: the coordinator (``coordinator.Fleet``) asks it and applies.

Guarantee (``tests/test_lifelong.py``): every task handed out by the feed ends ``done``
or ``failed`` exactly once, an object's tasks start in the order they were released, and
no task starts before its release time.
"""

from __future__ import annotations

from collections import deque

from lamp.fleet.tasks import TaskFeed, TaskRecord, TaskStatus

__all__ = ["TaskDesk"]


class TaskDesk:
    """The tasks of ``n_objects`` objects, as ``feed`` releases them."""

    def __init__(self, feed: TaskFeed, n_objects: int) -> None:
        self.feed = feed
        self.queues: list[deque[TaskRecord]] = [deque() for _ in range(n_objects)]
        #: the task each object serves now (queued until it starts, then active); None: none
        self.current: list[TaskRecord | None] = [None] * n_objects
        #: every task handed out, in the order the feed released them
        self.records: list[TaskRecord] = []
        #: how many tasks each object was handed (its first is its own goal's)
        self.served = [0] * n_objects

    def take(self, now: float) -> None:
        """Queue the tasks released by simulated time ``now``."""
        for task in self.feed.released(now):
            if not 0 <= task.object < len(self.queues):
                raise ValueError(f"task {task.id}: no object {task.object}")
            self.records.append(task)
            self.queues[task.object].append(task)

    def next_for(self, k: int) -> TaskRecord | None:
        """Object ``k``'s next task, now its current one, if it has none and one waits."""
        if self.current[k] is not None or not self.queues[k]:
            return None
        self.current[k] = self.queues[k].popleft()
        self.served[k] += 1
        return self.current[k]

    def first(self, k: int) -> bool:
        """Whether object ``k`` serves (or last served) its first task."""
        return self.served[k] <= 1

    def pending(self) -> bool:
        """Whether a released task waits for its object."""
        return any(self.queues)

    def begin(self, k: int, now: float) -> None:
        """Object ``k``'s current task starts (its object got a team)."""
        task = self.current[k]
        if task is not None and task.status is TaskStatus.QUEUED:
            task.move_to(TaskStatus.ACTIVE, now)
            self.feed.changed(task)

    def end(self, k: int, now: float, done: bool, reason: str | None = None,
            **figures: object) -> None:
        """Object ``k``'s current task ends, ``done`` or failed for ``reason``."""
        task = self.current[k]
        if task is None:
            return
        self.current[k] = None
        task.figures.update(figures)
        task.move_to(TaskStatus.DONE if done else TaskStatus.FAILED, now,
                     None if done else (reason or "failed"))
        self.feed.changed(task)

    def stop(self, now: float, reason: str) -> None:
        """Every task not ended fails for ``reason`` (the run ends before them)."""
        for k, task in enumerate(self.current):
            if task is not None:
                self.end(k, now, False, reason)
        for q in self.queues:
            while q:
                task = q.popleft()
                task.move_to(TaskStatus.FAILED, now, reason)
                self.feed.changed(task)
