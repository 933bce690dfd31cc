"""``run(request, observers)``: the one entry to plan and execute a scene.

``lamp.solve``, ``lamp run``, ``lamp demo`` and the bench's jobs all come here with a
:class:`~lamp.pipeline.request.RunRequest`. The Numba kernels are compiled (or loaded from
their disk cache) once per process before the first run (``lamp.pipeline.warmup``), so
``planning_time_s`` never includes compilation.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from lamp.contract.events import RunObserver
from lamp.contract.result import RunResult
from lamp.pipeline.execute import execute
from lamp.pipeline.observers import ProgressObserver
from lamp.pipeline.request import RunRequest
from lamp.pipeline.warmup import ensure_warm
from lamp.progress import ProgressCallback

__all__ = ["run"]


def run(request: RunRequest, observers: Sequence[RunObserver] = (), *,
        progress: ProgressCallback | None = None, feed: Any = None) -> RunResult:
    """Plan and execute ``request``; ``result.to_dict()`` is result.json and
    ``result.recording`` the run's :class:`lamp.record.Recording`.

    ``observers`` watch every object and segment (``lamp.contract.events.RunObserver``);
    ``progress`` receives :class:`~lamp.progress.ProgressEvent`\\ s, the compilation notice
    included. Neither changes the run. ``feed``: where a lifelong run's tasks come from
    (``pipeline.execute.execute``).
    """
    ensure_warm(progress)
    watchers = list(observers)
    if progress is not None:
        watchers.append(ProgressObserver(progress))
    return execute(request, watchers, feed=feed)
