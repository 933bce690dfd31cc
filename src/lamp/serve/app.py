"""The HTTP API of ``lamp serve`` (FastAPI): tasks in, the world and the tasks out.

Routes (``docs/serve.md``):

- ``POST /tasks`` ``{"object": k, "goal": [x, y, theta]}`` -> 201 ``{"id", "status":
  "queued", ...}`` (the task as in ``result.json``); 400 for a body that is not JSON, 422
  for a task the scene's rules refuse (``serve.intake``), 413 for a body over
  ``max_body`` bytes, 503 once the service stops. Every error is ``{"detail": "<field>:
  <reason>", "field": "<field>"}``.
- ``GET /tasks`` (all, by number), ``GET /tasks/{id}`` (404 for an unknown one),
  ``GET /state`` ``{"time_s", "robots", "objects", "stopped", "tasks"}``.
- ``GET /events``: server-sent events, ``world`` (time, robots, objects, stopped) at most
  every ``EVENT_S`` seconds when it changed and ``tasks`` (the list) when they changed;
  the stream ends ``STOP_GRACE_S`` after the service stops.
- ``GET /``: the live page (``serve.page``).

With a ``token`` every request must carry it (``Authorization: Bearer T``, or
``?token=T`` for the page and its event stream): 401 otherwise, before anything else is
read. Handlers only read the feed's snapshot (``serve.feed``): they never wait for the
fleet.
"""

from __future__ import annotations

import asyncio
import hmac
import json
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any
from urllib.parse import parse_qs

from fastapi import FastAPI, Request
from fastapi.responses import HTMLResponse, JSONResponse, Response, StreamingResponse

from lamp.serve.feed import FeedStopped, LiveFeed
from lamp.serve.intake import BadTask, TaskIntake
from lamp.serve.page import live_page

__all__ = ["EVENT_S", "MAX_BODY", "STOP_GRACE_S", "create_app", "error"]

#: The largest request body accepted, bytes.
MAX_BODY = 16 * 1024
#: Seconds between two looks at the world for the event stream.
EVENT_S = 0.05
#: Seconds an event stream goes on after a stop (the last task moves), then ends.
STOP_GRACE_S = 1.0

Scope = dict[str, Any]
ASGIApp = Callable[[Scope, Callable[[], Awaitable[dict]], Callable[[dict], Awaitable[None]]],
                   Awaitable[None]]


def error(status: int, field: str, reason: str) -> JSONResponse:
    """An error answer: ``{"detail": "<field>: <reason>", "field": <field>}``."""
    return JSONResponse({"detail": f"{field}: {reason}", "field": field}, status_code=status)


class Guard:
    """ASGI middleware: the token rule, and bodies announced over ``max_body`` -> 413."""

    def __init__(self, app: ASGIApp, token: str | None, max_body: int) -> None:
        self.app, self.token, self.max_body = app, token, max_body

    async def __call__(self, scope: Scope, receive: Any, send: Any) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", [])}
        answer = None
        if self.token is not None and not self._authorised(scope, headers):
            answer = error(401, "token", "missing or wrong: send the header 'Authorization: "
                           "Bearer TOKEN' (or ?token=TOKEN for the page)")
        elif not (length := headers.get("content-length", "0") or "0").isdigit():
            answer = error(400, "content-length", f"not a byte count: {length!r}")
        elif int(length) > self.max_body:
            answer = error(413, "body", f"larger than {self.max_body} bytes")
        if answer is not None:
            await answer(scope, receive, send)
            return
        await self.app(scope, receive, send)

    def _authorised(self, scope: Scope, headers: dict[str, str]) -> bool:
        given = headers.get("authorization", "")
        if given.startswith("Bearer "):
            given = given[len("Bearer "):]
        else:
            query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
            given = (query.get("token") or [""])[0]
        return hmac.compare_digest(given.encode(), str(self.token).encode())


async def _body(request: Request, limit: int) -> bytes | None:
    """The request's body, None once it runs over ``limit`` bytes (chunked uploads too)."""
    chunks, size = [], 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > limit:
            return None
        chunks.append(chunk)
    return b"".join(chunks)


def create_app(feed: LiveFeed, token: str | None = None, max_body: int = MAX_BODY) -> Any:
    """The ASGI app of a service whose tasks and world are ``feed``'s."""
    app = FastAPI(title="lamp serve", summary="LAMP fleet as a service: post tasks, watch "
                  "the world", docs_url=None, redoc_url=None)
    intake = TaskIntake(feed.scene)
    page = live_page(feed.scene)

    @app.post("/tasks", status_code=201)
    async def post_task(request: Request) -> Any:
        raw = await _body(request, max_body)
        if raw is None:
            return error(413, "body", f"larger than {max_body} bytes")
        try:
            body = json.loads(raw)
        except ValueError as exc:
            return error(400, "body", f"not JSON: {exc}")
        try:
            obj, goal = intake.check(body)
            task = feed.post(obj, goal)
        except BadTask as exc:
            return error(422, exc.field, exc.reason)
        except FeedStopped as exc:
            return error(503, "service", str(exc))
        return JSONResponse(task, status_code=201, headers={"Location": f"tasks/{task['id']}"})

    @app.get("/tasks")
    async def all_tasks() -> Any:
        return JSONResponse(feed.tasks())

    @app.get("/tasks/{task_id}")
    async def one_task(task_id: str) -> Any:
        task = feed.task(int(task_id)) if task_id.isdigit() else None
        if task is None:
            return error(404, "id", f"no task {task_id!r}")
        return JSONResponse(task)

    @app.get("/state")
    async def state() -> Any:
        return Response(feed.state_json(), media_type="application/json")

    @app.get("/events")
    async def events(request: Request) -> Any:
        return StreamingResponse(_stream(feed, request), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store"})

    @app.get("/", response_class=HTMLResponse)
    async def index() -> Any:
        return HTMLResponse(page)

    return Guard(app, token, max_body)


async def _stream(feed: LiveFeed, request: Request) -> AsyncIterator[bytes]:
    """The event stream (module docstring); after a stop it goes on for ``STOP_GRACE_S``
    (the fleet fails the tasks not done meanwhile), then ends."""
    seen, left = (-1, -1), round(STOP_GRACE_S / EVENT_S)
    while left > 0:
        world, tasks = feed.world_version, feed.tasks_version
        if tasks != seen[1]:
            yield _event("tasks", feed.tasks())
        if world != seen[0]:
            yield _event("world", feed.world())
        seen = (world, tasks)
        left -= feed.stopped
        if await request.is_disconnected():
            return
        await asyncio.sleep(EVENT_S)


def _event(name: str, data: Any) -> bytes:
    return f"event: {name}\ndata: {json.dumps(data, separators=(',', ':'))}\n\n".encode()
