"""``lamp serve``: the fleet as a service, tasks posted over HTTP while it works.

- :mod:`lamp.serve.feed`: :class:`LiveFeed`, the ``fleet.tasks.TaskFeed`` that takes
  posted tasks and keeps the snapshot the HTTP side reads;
- :mod:`lamp.serve.pace`: simulated time against wall time (``--realtime F``);
- :mod:`lamp.serve.intake`: what ``POST /tasks`` accepts (the scene format's rules);
- :mod:`lamp.serve.app`: the HTTP API (FastAPI), the token rule and the body limit;
- :mod:`lamp.serve.page`: the live page (``GET /``);
- :mod:`lamp.serve.service`: the server and the fleet in their threads.

The API, the token and the feed: ``docs/serve.md``. FastAPI and uvicorn load on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from lamp.lazy_exports import lazy_getattr

_LAZY = {"LiveFeed": "lamp.serve.feed", "Service": "lamp.serve.service",
         "create_app": "lamp.serve.app"}

if TYPE_CHECKING:
    from lamp.serve.app import create_app
    from lamp.serve.feed import LiveFeed
    from lamp.serve.service import Service

__getattr__ = lazy_getattr("lamp.serve", _LAZY, globals())

__all__ = ["LiveFeed", "Service", "create_app"]
