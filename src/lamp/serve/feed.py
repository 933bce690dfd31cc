"""The live task feed of ``lamp serve``: tasks posted while the fleet works, and the world
as it moves, shared between the fleet's thread and the HTTP server's.

:class:`LiveFeed` is a ``lamp.fleet.tasks.TaskFeed``. The fleet calls it from the one
thread that runs it (``released``, ``wait``, ``changed``, ``moved``, ``stopped``); the
HTTP handlers call :meth:`LiveFeed.post`, :meth:`LiveFeed.state` and the other readers
from theirs. One lock guards everything both sides touch, and the readers see a snapshot
(plain dicts and lists, copied under the lock), never the fleet's own objects: a reader
waits at most for a copy, never for planning or physics.

Guarantees (``tests/test_serve_feed.py``):

- **Numbering.** The scene's own tasks keep their numbers (``scene.tasks.numbered``: the
  objects' goals, then the file's ``tasks``); posted tasks are numbered after them, in the
  order they were posted, each number given once.
- **Release.** A posted task's ``release_s`` is the simulated time of the post: the last
  time the feed heard of (``released``/``wait``'s ``now``, the end of the last motion it
  was shown) or, while the fleet idles at ``realtime > 0``, the paced clock. It is never
  later than the fleet's next ``now``, so the fleet takes it at its next event.
- **Hand-out.** ``released(now)`` returns each task once, the scene's as
  ``ScheduledFeed`` would, posted ones once ``release_s <= now``; all by release time,
  then number. Statuses are the fleet's (``changed``), as in ``result.json``.
- **Idle.** ``wait(now)`` with ``realtime == 0``: ``now`` at once if a task waits to be
  handed out, the next scene task's release if there is one, else it blocks until a post
  (``now``) or :meth:`LiveFeed.stop` (None). With ``realtime F > 0`` the clock runs at
  ``F`` simulated seconds per wall second while idle: it returns the simulated time
  reached when a task is posted, the next scene task is due, ``IDLE_S`` wall seconds
  passed or the feed stops (None).
- **Pace.** With ``realtime F > 0``, ``moved`` returns no sooner than the pace allows
  (``serve.pace``): the simulation runs at most ``F`` times wall pace, and the snapshot
  follows the motion row by row meanwhile. After :meth:`LiveFeed.stop` nothing waits.
"""

from __future__ import annotations

import json
import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from lamp.fleet.tasks import IDLE_STRETCH_S, ScheduledFeed, TaskRecord
from lamp.scene.model import Scene
from lamp.serve.pace import Pace

__all__ = ["FRAME_S", "IDLE_S", "FeedStopped", "LiveFeed"]

#: Wall seconds between two snapshots while the feed paces a motion or an idle stretch.
FRAME_S = 0.04
#: Wall seconds an idle stretch lasts at most at ``realtime > 0`` (module docstring).
IDLE_S = 0.5


class FeedStopped(RuntimeError):
    """A task was posted after :meth:`LiveFeed.stop`."""


class LiveFeed:
    """The tasks of ``scene`` and those posted while it runs (module docstring);
    ``realtime``: simulated seconds per wall second (0: as fast as it can); ``wall``:
    the wall clock (monotonic seconds)."""

    def __init__(self, scene: Scene, realtime: float = 0.0,
                 wall: Callable[[], float] = time.monotonic) -> None:
        if not (isinstance(realtime, (int, float)) and math.isfinite(realtime)
                and realtime >= 0):
            raise ValueError(f"realtime: a finite number >= 0, got {realtime!r}")
        self.scene = scene
        self.realtime = float(realtime)
        self.wall = wall
        self._pace = Pace(self.realtime, wall) if self.realtime > 0 else None
        self._scheduled = ScheduledFeed(scene)
        self._cv = threading.Condition()
        self._posted: list[TaskRecord] = []  # posted, not handed out yet (in id order)
        self._next_id = len(self._scheduled.records)
        self._stopped = False
        self._now = 0.0
        self._robots = np.asarray(scene.robot_starts_array, float).copy()
        self._objects = np.asarray(scene.object_starts(), float).copy()
        self._tasks: dict[int, dict[str, Any]] = {
            r.id: r.to_dict() for r in self._scheduled.records}
        self.world_version = 0  #: bumped whenever time, robots or objects change
        self.tasks_version = 0  #: bumped whenever a task is posted or changes
        self._world_json: tuple[int, bytes] | None = None
        self._tasks_json: tuple[int, bytes] | None = None

    # ------------------------------------------------------------------ HTTP side
    def post(self, obj: int, goal: Sequence[float]) -> dict[str, Any]:
        """Queue a task (object ``obj`` to ``goal``, both already checked against the
        scene, ``serve.intake``), released now; its dict as in ``result.json``.
        ``FeedStopped`` after :meth:`stop`."""
        with self._cv:
            if self._stopped:
                raise FeedStopped("the service is stopping: no more tasks are taken")
            task = TaskRecord(self._next_id, int(obj), tuple(float(v) for v in goal),  # type: ignore[arg-type]
                              self._now)
            self._next_id += 1
            self._posted.append(task)
            self._tasks[task.id] = d = task.to_dict()
            self.tasks_version += 1
            self._cv.notify_all()
            return dict(d)

    def task(self, task_id: int) -> dict[str, Any] | None:
        """Task ``task_id`` as in ``result.json`` (None: no such task)."""
        with self._cv:
            d = self._tasks.get(task_id)
            return None if d is None else dict(d)

    def tasks(self) -> list[dict[str, Any]]:
        """Every task the service knows, by number."""
        with self._cv:
            return [dict(self._tasks[i]) for i in sorted(self._tasks)]

    def world(self) -> dict[str, Any]:
        """The world now: ``time_s`` (simulated), ``robots`` ([x, y] each), ``objects``
        ([x, y, theta] each), ``stopped``."""
        with self._cv:
            return self._world()

    def state(self) -> dict[str, Any]:
        """:meth:`world` and ``tasks`` (``GET /state``)."""
        with self._cv:
            return {**self._world(), "tasks": [dict(self._tasks[i]) for i in sorted(self._tasks)]}

    def state_json(self) -> bytes:
        """:meth:`state` as JSON bytes; the world's part made once per motion, the tasks'
        once per task change (a long queue costs nothing while only the world moves)."""
        with self._cv:
            if self._world_json is None or self._world_json[0] != self.world_version:
                self._world_json = (self.world_version, _dumps(self._world()))
            if self._tasks_json is None or self._tasks_json[0] != self.tasks_version:
                self._tasks_json = (self.tasks_version, _dumps(
                    [self._tasks[i] for i in sorted(self._tasks)]))
            return self._world_json[1][:-1] + b',"tasks":' + self._tasks_json[1] + b"}"

    def stop(self) -> None:
        """The run must end: ``stopped`` becomes True, nothing waits any more, and no task
        is taken after this."""
        with self._cv:
            self._stopped = True
            self.world_version += 1
            self._cv.notify_all()

    def _world(self) -> dict[str, Any]:
        return {"time_s": round(self._now, 4), "robots": self._robots.round(4).tolist(),
                "objects": self._objects.round(4).tolist(), "stopped": self._stopped}

    # ------------------------------------------------------------------ fleet side
    @property
    def stopped(self) -> bool:
        return self._stopped

    def released(self, now: float) -> list[TaskRecord]:
        with self._cv:
            self._clock_to(now)
            out = self._scheduled.released(now)
            due = [t for t in self._posted if t.release_s <= now]
            if due:
                self._posted = [t for t in self._posted if t.release_s > now]
                out += due
            return sorted(out, key=lambda t: (t.release_s, t.id))

    def wait(self, now: float) -> float | None:
        with self._cv:
            self._clock_to(now)
            if self._stopped:
                return None
            if self._posted:
                return max(float(now), min(t.release_s for t in self._posted))
            due = self._scheduled.wait(now)
            if self._pace is None:
                if due is not None:
                    return due
                while not (self._stopped or self._posted):
                    self._cv.wait()
                return None if self._stopped else float(now)
            return self._idle(float(now), due)

    def _idle(self, now: float, due: float | None) -> float | None:
        """``wait`` at ``realtime > 0`` (lock held): the paced clock runs until a post, the
        next scene task, ``IDLE_S`` or a stop."""
        pace = self._pace
        assert pace is not None
        pace.anchor(now)
        end = now + min(IDLE_S * pace.factor, IDLE_STRETCH_S)
        if due is not None:
            end = min(end, due)
        while True:
            self._clock_to(min(max(pace.now(), now), end))
            if self._stopped:
                return None
            if self._posted or self._now >= end:
                return self._now
            self._cv.wait(max(min(FRAME_S, pace.wall_at(end) - self.wall()), 1e-3))

    def changed(self, task: TaskRecord) -> None:
        with self._cv:
            self._tasks[task.id] = task.to_dict()
            self.tasks_version += 1

    def moved(self, start_s: float, trace: Any) -> None:
        if trace is None or len(trace.times) == 0:
            return
        times = np.asarray(trace.times, float)
        end = float(start_s) + float(times[-1])
        with self._cv:
            if self._pace is not None and not self._stopped:
                self._paced(float(start_s), times, trace)
            self._show(trace, len(times) - 1, end)

    def _paced(self, start: float, times: np.ndarray, trace: Any) -> None:
        """Show ``trace`` row by row at the pace (lock held; returns at its end's wall
        time, or at once on a stop). Time the feed already lived through (an idle
        stretch ``wait`` paced) is not paced again."""
        pace = self._pace
        assert pace is not None
        begin, end = max(start, self._now), start + float(times[-1])
        if end <= begin:
            return
        pace.anchor(begin)
        while not self._stopped:
            t = min(max(pace.now(), begin), end)
            row = int(np.searchsorted(times, t - start, side="right")) - 1
            self._show(trace, max(row, 0), t)
            if t >= end:
                return
            self._cv.wait(max(min(FRAME_S, pace.wall_at(end) - self.wall()), 1e-3))

    def _show(self, trace: Any, row: int, t: float) -> None:
        """The snapshot shows ``trace``'s row ``row`` at simulated time ``t`` (lock held)."""
        self._robots = np.array(trace.robot_positions[row], float).reshape(-1, 2)
        self._objects = np.array(trace.object_poses[row], float).reshape(-1, 3)
        self._clock_to(t)
        self.world_version += 1

    def _clock_to(self, t: float) -> None:
        """The feed's clock moves on to ``t`` (never back; lock held)."""
        if t > self._now:
            self._now = float(t)
            self.world_version += 1


def _dumps(value: Any) -> bytes:
    return json.dumps(value, separators=(",", ":")).encode()
