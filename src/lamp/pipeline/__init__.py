"""The run pipeline: request -> schedule -> object runners -> observers.

- ``request``: :class:`RunRequest`, frozen and validated, built once by every entry point;
- ``run``: :func:`run`, warm-up then :func:`~lamp.pipeline.execute.execute`;
- ``schedule``: which object moves when (one place);
- ``observers``: progress events (the recorder is ``lamp.record.Recorder``);
- ``registry``: one :class:`~lamp.pipeline.registry.PlannerSpec` per planner;
- ``warmup``: compiling the Numba kernels ahead of planning.

``RunRequest`` and ``run`` load on first use, so reading the registry (the CLI's help)
stays cheap.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from lamp.lazy_exports import lazy_getattr

if TYPE_CHECKING:
    from lamp.pipeline.request import RunRequest
    from lamp.pipeline.run import run

__all__ = ["RunRequest", "run"]

__getattr__ = lazy_getattr("lamp.pipeline", {"RunRequest": "lamp.pipeline.request",
                                             "run": "lamp.pipeline.run"}, globals())
