"""Which object moves when: the one place a run's objects are scheduled.

:func:`run_in_order` is the paper's schedule (``schedule: sequential`` of the scene
format): the objects are moved one after another, in the scene file's order, each by the
whole team, the others standing as physical bodies where they are.
:func:`run_concurrently` is the fleet schedule (``schedule: concurrent``): several objects
at once, each by a sub-team, in one simulator (``lamp.fleet``). Both drive the same
closed loops.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from lamp.contract.events import RunObserver, SegmentEvent
from lamp.contract.runner import Executor, LoopEnd, ObjectOutcome, ObjectRunner
from lamp.scene.model import Scene

__all__ = ["run_concurrently", "run_in_order"]


def _segments_to(observers: Sequence[RunObserver]) -> Callable[[SegmentEvent], None]:
    """The ``observe`` callback that hands each segment to every observer, in order."""

    def observe(event: SegmentEvent) -> None:
        for o in observers:
            o.segment(event)

    return observe


def run_in_order(scene: Scene, executor: Executor, runner: ObjectRunner,
                 observers: Sequence[RunObserver] = ()) -> list[ObjectOutcome]:
    """Move ``scene``'s objects in order with ``runner`` on ``executor``; returns their
    outcomes, in order. Every observer sees ``object_started``, the object's segments and
    ``object_finished`` for each object, in that order."""
    observe = _segments_to(observers)
    n_objects = len(scene.objects)
    outcomes = []
    for index in range(n_objects):
        for o in observers:
            o.object_started(index, n_objects)
        outcome = _blocker_named(scene, index, executor,
                                 runner.run_object(index, executor, observe))
        for o in observers:
            o.object_finished(index, n_objects, outcome.result)
        outcomes.append(outcome)
    return outcomes


def _blocker_named(scene: Scene, index: int, executor: Executor, outcome: ObjectOutcome
                   ) -> ObjectOutcome:
    """``outcome`` of object ``index``; when it failed for want of a plan and another
    object stands in its way (``fleet.makeway.standing_in_way``: nobody moves aside in
    this schedule), its failure reason says which, and what would move it."""
    r = outcome.result
    if r.success or outcome.end is not LoopEnd.NO_PLAN:
        return outcome
    from lamp.fleet.makeway import standing_in_way, way_of

    poses = np.asarray(executor.object_poses, float)
    j = standing_in_way(scene, index, way_of(scene, index, poses[index]), poses,
                        list(range(len(scene.objects))))
    if j is None:
        return outcome
    why = (f"{r.failure_reason} (object {j} stands in its way: this schedule moves the "
           f"objects one after another in the file's order; the concurrent one finds an "
           f"order or moves it aside)")
    return replace(outcome, result=replace(r, failure_reason=why))


def run_concurrently(scene: Scene, executor: Executor, runner: ObjectRunner, recorder: Any,
                     config: Any = None, observers: Sequence[RunObserver] = (),
                     feed: Any = None, serial: bool = False
                     ) -> tuple[list[ObjectOutcome], dict[str, Any], list[Any]]:
    """Move ``scene``'s objects several at once by sub-teams (``lamp.fleet.Fleet``, with
    ``config``: a ``FleetConfig``, default its defaults) with the closed loops of
    ``runner`` (a ``ClosedLoopRunner``); the recorder follows the shared clock. The tasks
    come from ``feed`` (a ``fleet.tasks.TaskFeed``; default: the scene's own,
    ``ScheduledFeed``); ``serial``: one at a time by the whole team, first come first
    served (a lifelong scene's sequential schedule). Returns the outcomes in object
    order, the schedule's figures and the task records (``fleet.tasks.TaskRecord``) in
    the order they were released."""
    from lamp.contract.trajectory import MAX_STEP
    from lamp.fleet.config import FleetConfig
    from lamp.fleet.coordinator import Fleet
    from lamp.fleet.objects import object_main

    config = FleetConfig() if config is None else config
    watchers = [recorder, *observers]
    fleet = Fleet(scene, executor, object_main(runner, _segments_to(watchers), config),
                  recorder.follow, watchers, row_step=MAX_STEP, config=config, feed=feed,
                  serial=serial)
    outcomes = fleet.run()
    return outcomes, fleet.report(), fleet.desk.records
