"""Observers of a run that are not the recording: the progress events of ``lamp.progress``."""

from __future__ import annotations

from lamp.contract.events import SegmentEvent
from lamp.contract.result import ObjectResult
from lamp.progress import ProgressCallback, ProgressEvent

__all__ = ["ProgressObserver"]


class ProgressObserver:
    """Turns a run's object and segment events into :class:`~lamp.progress.ProgressEvent`\\ s
    (``object``, ``segment``, ``object-done``) for ``callback``, each with the objects
    done and moving so far."""

    def __init__(self, callback: ProgressCallback) -> None:
        self.callback = callback
        self.n_objects = 0
        self.moving: set[int] = set()
        self.done = 0

    def object_started(self, index: int, n_objects: int) -> None:
        self.n_objects = n_objects
        self.moving.add(index)
        self.callback(ProgressEvent("object", object_index=index, n_objects=n_objects,
                                    done=self.done, moving=len(self.moving)))

    def segment(self, event: SegmentEvent) -> None:
        self.callback(ProgressEvent("segment", object_index=event.object_index,
                                    n_objects=self.n_objects, segments=event.segment + 1,
                                    replans=event.replans, done=self.done,
                                    moving=len(self.moving)))

    def object_finished(self, index: int, n_objects: int, result: ObjectResult) -> None:
        self.moving.discard(index)
        self.done += 1
        self.callback(ProgressEvent("object-done", object_index=index, n_objects=n_objects,
                                    segments=result.segments, replans=result.replans,
                                    success=result.success, done=self.done,
                                    moving=len(self.moving)))
