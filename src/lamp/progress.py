"""Progress events of a run, for whoever shows them (``lamp run`` on a terminal).

``lamp.solve(..., progress=callback)`` calls ``callback(event)`` with a
:class:`ProgressEvent`; the library itself never prints. Events, in order:
``compiling`` (Numba kernels are being compiled, once per environment) and ``compiled``,
then for each object ``object`` (it starts), ``segment`` (after each executed segment) and
``object-done``. In the concurrent schedule the objects' events interleave; each event
also counts the objects done and moving so far, and its description names them when
several move at once.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

EventKind = Literal["compiling", "compiled", "object", "segment", "object-done"]


@dataclass(frozen=True)
class ProgressEvent:
    """One step of a run. Counts refer to the current object (``object_index`` of
    ``n_objects``, 0-based); ``seconds`` is the compile time of a ``compiled`` event;
    ``done`` and ``moving`` count the run's objects finished (placed or given up) and
    started but not finished, this event included."""

    kind: EventKind
    object_index: int = 0
    n_objects: int = 0
    segments: int = 0
    replans: int = 0
    success: bool | None = None
    seconds: float = 0.0
    done: int = 0
    moving: int = 0

    def describe(self) -> str:
        """A one-line human description (what ``lamp run --verbose`` prints); with several
        objects moving, or having moved, at once, followed by how many are done and
        moving."""
        obj = f"object {self.object_index + 1}/{self.n_objects}"
        if self.kind == "compiling":
            return "compiling Numba kernels (once per environment; see `lamp warmup`)..."
        if self.kind == "compiled":
            return f"compiled Numba kernels in {self.seconds:.1f} s (not counted as planning)"
        if self.kind == "object":
            text = f"{obj}: planning"
        elif self.kind == "segment":
            text = f"{obj}: segment {self.segments}, {self.replans} replans"
        else:
            verdict = "reached its goal" if self.success else "failed"
            text = f"{obj}: {verdict} after {self.segments} segments, {self.replans} replans"
        if self.moving > 1 or (self.kind == "object-done" and self.moving > 0):
            text += f"  ({self.done}/{self.n_objects} done, {self.moving} moving)"
        return text


ProgressCallback = Callable[[ProgressEvent], None]
