"""What a run tells its observers: one :class:`SegmentEvent` per executed segment, and the
start and end of each object.

An observer only watches: a run is the same with or without it (tested). The recorder
(``lamp.record.Recorder``), the progress display and the bench's counters are observers;
every picture of a run is drawn from its recording, never from a side channel.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from lamp.contract.result import ObjectResult
    from lamp.contract.transition import Transition

__all__ = ["TRACE_EVERY", "RunObserver", "SegmentEvent"]

#: Physics steps between the trace rows an executed segment hands its observers (the
#: recording's time resolution; 40 steps of 2 ms: 0.08 s).
TRACE_EVERY = 40


@dataclass(frozen=True)
class SegmentEvent:
    """One executed segment, handed to the observers right after it ran.

    ``execution`` is the simulator's result, with a ``trace`` sampled every
    ``TRACE_EVERY`` physics steps (its row 0 is the state before the segment);
    ``transition`` the (robot-adapted) transition that was executed; ``plan`` the plan in
    force (``object_path``, ``verified_edges``, ``penalised_edges``) or None;
    ``planning_time_s`` the planning time charged to this segment; ``replanned`` whether a
    plan call preceded it; ``drift`` the (position, orientation) miss of the reached pose
    against ``transition.q_to``; ``outcome`` what the loop did next: ``"continue"``,
    ``"drift"`` (replan), ``"stalled"`` (push reported failed, replan), ``"left"`` or
    ``"team"`` (a robot failed during the segment: planning starts anew with the rest).
    """

    object_index: int
    segment: int
    transition: Transition | Any
    execution: Any
    plan: Any
    planning_time_s: float
    replanned: bool
    drift: tuple[float, float]
    outcome: str
    #: Replans of this object so far (the first plan is not a replan).
    replans: int = 0


class RunObserver(Protocol):
    """Watches a run: called in order, from the thread that runs it."""

    def object_started(self, index: int, n_objects: int) -> None:
        """Object ``index`` (of ``n_objects``) is about to be planned for."""
        ...

    def segment(self, event: SegmentEvent) -> None:
        """A segment was executed."""
        ...

    def object_finished(self, index: int, n_objects: int, result: ObjectResult) -> None:
        """Object ``index`` is done (placed or given up)."""
        ...
