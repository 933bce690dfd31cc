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
from lamp.contract.plan import PlanStatus
from lamp.contract.runner import Executor, ObjectOutcome, ObjectRunner

__all__ = ["run_concurrently", "run_in_order"]


def _segments_to(observers: Sequence[RunObserver]) -> Callable[[SegmentEvent], None]:
    """The ``observe`` callback that hands each segment to every observer, in order."""

    def observe(event: SegmentEvent) -> None:
        for o in observers:
            o.segment(event)

    return observe


def run_in_order(n_objects: int, executor: Executor, runner: ObjectRunner,
                 observers: Sequence[RunObserver] = ()) -> list[ObjectOutcome]:
    """Move objects ``0 .. n_objects - 1`` in order with ``runner`` on ``executor``;
    returns their outcomes, in order. Every observer sees ``object_started``, the object's
    segments and ``object_finished`` for each object, in that order."""
    observe = _segments_to(observers)
    outcomes = []
    for index in range(n_objects):
        for o in observers:
            o.object_started(index, n_objects)
        outcome = _blocker_named(getattr(runner, "scene", None), index, executor,
                                 runner.run_object(index, executor, observe))
        for o in observers:
            o.object_finished(index, n_objects, outcome.result)
        outcomes.append(outcome)
    return outcomes


def _blocker_named(scene: Any, index: int, executor: Executor, outcome: ObjectOutcome
                   ) -> ObjectOutcome:
    """``outcome`` of object ``index``; when it failed for want of a plan and another
    object stands in its way (``fleet.makeway.standing_in_way``: nobody moves aside in
    this schedule), its failure reason says which, and what would move it."""
    r = outcome.result
    if scene is None or r.success or not r.failure_reason.startswith(PlanStatus.NO_PATH.reason):
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


def run_concurrently(scene: Any, executor: Executor, runner: ObjectRunner, recorder: Any,
                     observers: Sequence[RunObserver] = ()) -> tuple[list[ObjectOutcome],
                                                                     dict[str, Any]]:
    """Move ``scene``'s objects several at once by sub-teams (``lamp.fleet.Fleet``) with
    the closed loops of ``runner`` (a ``ClosedLoopRunner``); the recorder follows the
    shared clock. Returns the outcomes in object order and the schedule's figures."""
    from lamp.contract.trajectory import MAX_STEP
    from lamp.fleet.coordinator import Fleet
    from lamp.fleet.objects import object_main

    watchers = [recorder, *observers]
    fleet = Fleet(scene, executor, object_main(runner, _segments_to(watchers)),
                  recorder.follow, watchers, row_step=MAX_STEP,
                  reinforce_reach=runner.config.fleet_reinforce_reach,
                  cross_near=runner.config.fleet_cross_near,
                  cross_waiting=runner.config.fleet_cross_waiting,
                  pass_margin=runner.config.fleet_pass_margin,
                  rejoin_limit=runner.config.fleet_rejoin_limit,
                  rejoin_slack=runner.config.fleet_rejoin_slack)
    outcomes = fleet.run()
    return outcomes, fleet.stats()
