"""Who moves an object, and what it reports: the executor and object-runner protocols.

A run moves a scene's objects with one simulator (an :class:`Executor`); for each object the
run's scheduler asks an :class:`ObjectRunner` to move it and gets an :class:`ObjectOutcome`
back. LAMP's closed loop (``lamp.planners.runner.ClosedLoopRunner``) and the MAPush baseline
(``lamp.baselines.mapush.MapushRunner``) are the two object runners; the scheduler
(``lamp.pipeline.schedule``) does not know which one it drives.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:
    from lamp.contract.events import SegmentEvent
    from lamp.contract.result import ObjectResult

__all__ = ["ALONE", "Execution", "Executor", "LoopEnd", "LoopHooks", "ObjectOutcome",
           "ObjectRunner", "WorldExecutor"]


class Execution(Protocol):
    """What an executor reports after one segment (``lamp.sim.ExecutionResult`` is one)."""

    object_poses: np.ndarray  # (K, 3) every object's pose after the segment
    robot_positions: np.ndarray  # (N, 2)
    left_workspace: bool  # an object left the map during the segment
    trace: Any  # frames sampled every ``record_every`` physics steps, or None
    #: the physics step at which ``stop`` ended the paths early; None: they ran to the end
    stopped_at: int | None
    #: the segment was not run: the world changed around its plan (a shared executor's
    #: answer, ``LoopHooks``); the loop then ends with ``LoopEnd.WORLD_CHANGED``
    declined: bool


class Executor(Protocol):
    """Runs synchronised robot paths and reports the state they led to (``lamp.sim.Simulator``).
    What an executor shared with others adds is a loop's :class:`LoopHooks`."""

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


class WorldExecutor(Executor, Protocol):
    """The executor of a whole run, every robot and object (``lamp.sim.Simulator``,
    ``lamp.sim.disturbed.DisturbedExecutor``): what the schedulers and object runners
    are handed."""

    #: Whether the run may be disturbed (noisy readings, robots that fail): success is
    #: then judged on ``true_object_poses``, and a robot that fails ends its team's loop.
    disturbed: bool
    #: Whether objects are read exactly and move only as their pushers drive them (no
    #: sensing noise, actuation noise or knocks; failing robots merely stop): the fleet
    #: then bounds how far a pushed object can get (``lamp.fleet.spacetime``).
    pushes_tracked: bool

    @property
    def true_object_poses(self) -> np.ndarray:
        """(K, 3) the objects' true poses (``object_poses`` may be a noisy reading)."""
        ...

    @property
    def failed(self) -> Mapping[int, np.ndarray]:
        """The robots that stopped for good, and where (empty when none did)."""
        ...


class LoopEnd(StrEnum):
    """How one closed loop ended (``ObjectOutcome.end``): for good, or so that its runner
    plans anew."""

    #: At its goal, or stopped for good (its result says which, and why).
    FINISHED = "finished"
    #: Its planner found no plan (for good, under its policy).
    NO_PLAN = "no plan"
    #: The world changed around its plan: its segment was declined, or its planner found
    #: no plan while other objects moved (``LoopHooks.plan_failed``). Plan anew.
    WORLD_CHANGED = "world changed"
    #: A robot of its team failed, or robots joined it (``LoopHooks.team_changed``). Plan
    #: anew with the team as it is.
    TEAM_CHANGED = "team changed"


def _never() -> bool:
    return False


def _ignore(segment: np.ndarray, rest: np.ndarray) -> None:
    return None


@dataclass(frozen=True)
class LoopHooks:
    """What the world around one closed loop adds to its executor; ``ALONE``: nothing (a
    loop with the whole simulator to itself). A sub-team's view (``TeamView``,
    ``lamp.fleet.view.FleetView``) gives its own.

    - ``team_changed()``: asked after each segment; True ends the loop
      (``LoopEnd.TEAM_CHANGED``);
    - ``announce(segment, rest)``: told before each ``execute`` the object poses the
      segment plans to pass ((P, 3)) and those the plan goes on to ((R, 3)): the fleet
      schedule reserves space with them;
    - ``plan_failed()``: called when the planner found no plan; True ends the loop
      (``LoopEnd.WORLD_CHANGED``) so that its runner plans anew once the world changed;
      False: the loop goes on under its policy as if alone.
    """

    team_changed: Callable[[], bool] = _never
    announce: Callable[[np.ndarray, np.ndarray], None] = _ignore
    plan_failed: Callable[[], bool] = _never


#: The hooks of a loop alone in its world.
ALONE = LoopHooks()


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
    #: How its (last) closed loop ended.
    end: LoopEnd = LoopEnd.FINISHED


class ObjectRunner(Protocol):
    """Moves one object of a scene at a time on a shared executor."""

    #: Simulated seconds between the trace rows of its segments (the recording's rows).
    row_dt_s: float

    def run_object(self, index: int, executor: WorldExecutor,
                   observe: Callable[[SegmentEvent], None]) -> ObjectOutcome:
        """Move object ``index`` from where it is towards its goal; ``observe`` is called
        after every executed segment, in order."""
        ...

    def run_stats(self, outcomes: list[ObjectOutcome]) -> dict[str, Any]:
        """The run's ``stats`` of result.json, after every object was run."""
        ...
