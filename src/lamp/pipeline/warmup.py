"""Compiling the Numba kernels ahead of planning (``lamp warmup``).

The planners' kernels (``lamp.geometry``, ``lamp.mrmp``, ``lamp.search``) are compiled
with ``cache=True``: the first run in a fresh environment compiles them (20-30 s) and
stores the machine code on disk, later processes load it in well under a second.
:func:`warm_up` runs a tiny built-in scene through LAMP-Lazy with the geometric model,
which exercises every planning kernel; ``lamp.pipeline.run`` calls it before its planning clock
starts, so compilation never counts as planning time.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from numba.core import event as nb_event

from lamp.progress import ProgressCallback, ProgressEvent

#: A one-object scene small enough to plan in a fraction of a second once compiled.
WARMUP_SCENE: dict[str, Any] = {
    "format": "lamp-scene/1", "name": "warmup", "workspace": [1.6, 1.2],
    "robots": {"radius": 0.05, "starts": [[0.15, 0.2], [0.15, 0.45], [0.15, 0.7]]},
    "obstacles": [{"type": "circle", "center": [1.3, 1.0], "radius": 0.08}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.5, 0.5, 0.0],
                 "goal": [0.9, 0.6, 0.3]}],
}


@dataclass(frozen=True)
class WarmupReport:
    """``seconds``: wall time of the warm-up; ``compiled``: kernel compilations it caused
    (0 when every kernel came from the on-disk cache); ``compile_s``: time spent compiling."""

    seconds: float
    compiled: int
    compile_s: float


class _CompileWatch(nb_event.Listener):
    """Counts Numba compilations and announces the first one through ``progress``."""

    def __init__(self, progress: ProgressCallback | None) -> None:
        self.progress = progress
        self.count = 0
        self.started: float | None = None
        self.ended: float | None = None

    def on_start(self, event: nb_event.Event) -> None:
        if self.started is None:
            self.started = time.perf_counter()
            if self.progress is not None:
                self.progress(ProgressEvent("compiling"))

    def on_end(self, event: nb_event.Event) -> None:
        self.count += 1
        self.ended = time.perf_counter()


def warm_up(progress: ProgressCallback | None = None) -> WarmupReport:
    """Compile (or load from the disk cache) every planning kernel; see the module docstring.

    ``progress`` receives ``compiling`` before the first compilation and ``compiled`` after
    the last one; with a warm cache it receives nothing.
    """
    from lamp.pipeline.execute import execute
    from lamp.pipeline.request import RunRequest
    from lamp.scene.loader import scene_from_dict

    watch = _CompileWatch(progress)
    t0 = time.perf_counter()
    nb_event.register("numba:compile", watch)
    try:
        execute(RunRequest(scene_from_dict(WARMUP_SCENE, source="<warmup>"), "lazy", 0,
                           "geometric"))
    finally:
        nb_event.unregister("numba:compile", watch)
    seconds = time.perf_counter() - t0
    compile_s = 0.0 if watch.started is None else (watch.ended or t0) - watch.started
    if watch.count and progress is not None:
        progress(ProgressEvent("compiled", seconds=compile_s))
    return WarmupReport(seconds=seconds, compiled=watch.count, compile_s=compile_s)


_WARMED: list[WarmupReport] = []  # process state: kernels are loaded once per process


def ensure_warm(progress: ProgressCallback | None = None) -> WarmupReport:
    """:func:`warm_up` on the first call in this process; later calls return at once with a
    zero report (the kernels are already in memory)."""
    if _WARMED:
        return WarmupReport(seconds=0.0, compiled=0, compile_s=0.0)
    report = warm_up(progress)
    _WARMED.append(report)
    return report
