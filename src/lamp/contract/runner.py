"""Who moves an object, and what it reports: the executor and object-runner protocols.

A run moves a scene's objects with one simulator (an :class:`Executor`); for each object the
run's scheduler asks an :class:`ObjectRunner` to move it and gets an :class:`ObjectOutcome`
back. LAMP's closed loop (``lamp.planners.runner.ClosedLoopRunner``) and the MAPush baseline
(``lamp.baselines.mapush.MapushRunner``) are the two object runners; the scheduler
(``lamp.pipeline.schedule``) does not know which one it drives.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:
    from lamp.contract.events import SegmentEvent
    from lamp.contract.result import ObjectResult

__all__ = ["Execution", "Executor", "ObjectOutcome", "ObjectRunner"]


class Execution(Protocol):
    """What an executor reports after one segment (``lamp.sim.ExecutionResult`` is one)."""

    object_poses: np.ndarray  # (K, 3) every object's pose after the segment
    robot_positions: np.ndarray  # (N, 2)
    left_workspace: bool  # an object left the map during the segment
    trace: Any  # frames sampled every ``record_every`` physics steps, or None


class Executor(Protocol):
    """Runs synchronised robot paths and reports the state they led to (``lamp.sim.Simulator``).

    An executor shared with other moving objects (the fleet schedule's
    ``lamp.fleet.view.FleetView``) may also offer, and the closed loop then uses:

    - ``announce(segment, rest)``: told before each ``execute`` the object poses the
      segment plans to pass ((P, 3)) and those the plan goes on to ((R, 3));
    - ``plan_failed() -> bool``: called when the planner found no plan; True stops the
      loop (``WORLD_CHANGED``) so that its runner plans anew once the world has changed;
    - an ``Execution`` with ``declined = True``: the segment was not run (the world changed
      around its plan); the loop stops with ``WORLD_CHANGED`` and counts nothing.
    """

    @property
    def object_poses(self) -> np.ndarray:
        """(K, 3) the objects' poses now."""
        ...

    @property
    def robot_positions(self) -> np.ndarray:
        """(N, 2) the robots' centres now."""
        ...

    def execute(self, robot_paths: np.ndarray, record_every: int | None = None,
                stop: Callable[[np.ndarray], bool] | None = None) -> Execution:
        """Drive the robots along ``robot_paths`` (N, T, 2) and report the outcome; ``stop``
        (given the (K, 3) object poses now and then) may end the paths early, the robots
        then holding where they are (``Simulator.execute``)."""
        ...


@dataclass
class ObjectOutcome:
    """What moving one object measured: its result, the planning time charged to each of
    its executed segments (in order), its makespan (synchronised trajectory rows) and the
    planning time after its last executed segment."""

    result: ObjectResult
    planning_time_s: list[float] = field(default_factory=list)
    makespan: int = 0
    unexecuted_planning_s: float = 0.0
    #: Runner-specific figures of this object (MAPush's own criterion, say).
    extra: dict[str, Any] = field(default_factory=dict)


class ObjectRunner(Protocol):
    """Moves one object of a scene at a time on a shared executor."""

    #: Simulated seconds between the trace rows of its segments (the recording's rows).
    row_dt_s: float

    def run_object(self, index: int, executor: Executor,
                   observe: Callable[[SegmentEvent], None]) -> ObjectOutcome:
        """Move object ``index`` from where it is towards its goal; ``observe`` is called
        after every executed segment, in order."""
        ...

    def run_stats(self, outcomes: list[ObjectOutcome]) -> dict[str, Any]:
        """The run's ``stats`` of result.json, after every object was run."""
        ...
