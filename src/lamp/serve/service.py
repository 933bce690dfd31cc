"""A running ``lamp serve``: the HTTP server and the fleet, each in its own thread.

:class:`Service` listens (``listen``: the socket is bound in the caller's thread, so a
port in use is an ``OSError`` there), serves the API (``serve.app``) with uvicorn in one
thread and runs the fleet (``lamp.pipeline.run`` with the concurrent schedule and the
:class:`~lamp.serve.feed.LiveFeed`) in another. :meth:`Service.finish` stops the feed
(the fleet ends at its next event: every task not done fails, ``stopped``) and returns
the run's ``RunResult``, result.json and recording included, as ``lamp run``'s; the
server keeps answering until :meth:`Service.close`. uvicorn runs off the main thread, so
it leaves the process's signal handlers alone: the caller decides what a signal does.
"""

from __future__ import annotations

import socket
import threading
import time
from typing import Any

from lamp.contract.result import RunResult
from lamp.pipeline.request import RunRequest
from lamp.serve.app import MAX_BODY, create_app
from lamp.serve.feed import LiveFeed

__all__ = ["Service", "is_loopback", "listen"]


def is_loopback(host: str) -> bool:
    """Whether ``host`` names this machine only (``localhost``, 127.0.0.0/8, ``::1``)."""
    import ipaddress

    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host``:``port`` (0: a free port); ``OSError`` if it
    cannot be had."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    # IPPROTO_TCP named: asyncio sets TCP_NODELAY on the accepted connections only then
    # (a proto of 0 costs every kept-alive answer a 40 ms delayed ACK)
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host.strip("[]"), port))
        sock.listen(128)
    except BaseException:
        sock.close()
        raise
    sock.set_inheritable(True)
    return sock


class Service:
    """``request`` (its scene, planner, seed; the concurrent schedule) served over HTTP with
    ``feed`` as its tasks, on the listening socket ``sock`` (module docstring)."""

    def __init__(self, request: RunRequest, feed: LiveFeed, sock: socket.socket,
                 token: str | None = None, max_body: int = MAX_BODY) -> None:
        import uvicorn

        self.request, self.feed, self.sock = request, feed, sock
        config = uvicorn.Config(create_app(feed, token, max_body), log_level="warning",
                                access_log=False, lifespan="off",
                                timeout_graceful_shutdown=2)
        self.server = uvicorn.Server(config)
        self.result: RunResult | None = None
        self.error: BaseException | None = None
        self._http = threading.Thread(target=self.server.run, kwargs={"sockets": [sock]},
                                      name="lamp-serve-http", daemon=True)
        self._fleet = threading.Thread(target=self._run_fleet, name="lamp-serve-fleet",
                                       daemon=True)

    @property
    def url(self) -> str:
        host, port = self.sock.getsockname()[:2]
        return f"http://{f'[{host}]' if ':' in host else host}:{port}/"

    def start(self, timeout: float = 60.0) -> None:
        """Start serving, then the fleet; RuntimeError if the server did not come up
        within ``timeout`` seconds."""
        self._http.start()
        end = time.monotonic() + timeout
        while not self.server.started:
            if not self._http.is_alive() or time.monotonic() > end:
                raise RuntimeError("the HTTP server did not start")
            time.sleep(0.01)
        self._fleet.start()

    @property
    def running(self) -> bool:
        """Whether the fleet still runs (False once it ended, stopped or failed)."""
        return self._fleet.is_alive()

    def _run_fleet(self) -> None:
        from lamp.pipeline import run

        try:
            self.result = run(self.request, feed=self.feed)
        except BaseException as exc:  # handed to finish()
            self.error = exc
        finally:
            self.feed.stop()

    def finish(self) -> RunResult:
        """Stop the fleet and wait for it; its result (the fleet's error re-raised)."""
        self.feed.stop()
        if self._fleet.is_alive() or self._fleet.ident is not None:
            self._fleet.join()
        if self.error is not None:
            raise self.error
        if self.result is None:
            raise RuntimeError("the fleet did not run")
        return self.result

    def close(self, timeout: float = 10.0) -> None:
        """Stop the HTTP server (open event streams end: the feed is stopped)."""
        self.feed.stop()
        self.server.should_exit = True
        if self._http.is_alive():
            self._http.join(timeout)
        self.sock.close()

    def __enter__(self) -> Service:
        self.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
