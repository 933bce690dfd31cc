"""Placed objects pushed off their goals are placed again.

A placed object stands as a body where it is; a later push that drifts (the learned
model's error) may touch it and shove it off its goal, which no plan intended and no
admission test can rule out. Success is judged on the final object poses
(``pipeline.execute.still_placed``), so such an object would fail at the run's end. The
schedule therefore looks, after each stretch of the shared clock, at every placed
object's pose as sensed (``executor.object_poses``; the true pose is the simulator's
alone): one outside the success tolerances of its goal gets its task again, queued at its
desk like any task (``desk.TaskDesk``), and is started, given robots and placed as any
object (its outcome merges both tasks', ``tasks.merged_tasks``; ``placed_at_s`` is the
later time). At most ``MAX_REPLACES`` times an object; in a lifelong run (tasks from a
scene's ``tasks`` or a live feed) the feed alone makes tasks, and nothing is re-placed.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lamp.contract.goals import SUCCESS_ORIENTATION_TOL, SUCCESS_POSITION_TOL, within_goal
from lamp.fleet.follow import Following
from lamp.fleet.state import ObjectStatus
from lamp.fleet.tasks import ScheduledFeed, TaskRecord

__all__ = ["MAX_REPLACES", "Knocks"]

#: How many times an object knocked off its goal is placed again.
MAX_REPLACES = 3


class Knocks(Following):
    """Re-placing knocked objects: the fleet schedule's writer's part (module docstring)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.knocks = [0] * len(self.objects)  # times each object was placed again
        self._looked = -1  # the stretch of the clock last looked after

    def reopen_knocked(self) -> list[int]:
        """Give every placed object sensed off its goal its task again (module docstring),
        once per stretch of the clock run; the objects reopened."""
        placed = [o for o in self.objects if o.status == ObjectStatus.PLACED
                  and self.knocks[o.index] < MAX_REPLACES]
        if (self._looked == self.events or not placed or self.scene.tasks
                or not isinstance(self.desk.feed, ScheduledFeed)):
            return []
        self._looked = self.events
        poses = np.asarray(self.executor.object_poses, float)
        out = []
        for o in placed:
            goal = np.asarray(self.scene.objects[o.index].goal, float)
            if within_goal(poses[o.index], goal, SUCCESS_POSITION_TOL, SUCCESS_ORIENTATION_TOL):
                continue
            task = TaskRecord(1 + max(t.id for t in self.desk.records), o.index,
                              tuple(float(v) for v in goal), self.clock)  # type: ignore[arg-type]
            self.desk.records.append(task)
            self.desk.queues[o.index].append(task)
            self.knocks[o.index] += 1
            self.stats.count("knocked")
            self.stats.note(self.clock, "knocked", o.index,
                            f"off its goal at {np.round(poses[o.index], 3).tolist()}")
            out.append(o.index)
        return out
