"""The worker process of the local backend: runs jobs handed to it over a pipe, one at a time.

Started by :mod:`lamp.bench.pool` with the ``spawn`` context (a fresh interpreter: nothing
is inherited from the parent but the environment and ``sys.path``). It first makes itself
the leader of a new session, so the parent can kill it together with anything it started;
imports the job function and runs its ``warm_up`` (see :func:`serve`); then answers
``("ready",)`` and serves ``("job", job, log_path)`` messages with
``("done", (status, payload, traceback))`` until it gets ``("stop",)`` or its pipe closes.
While a job runs, file descriptors 1 and 2 point at that job's log file, so the job's
output (a Python traceback, a faulthandler dump on a segfault) is kept per job. A worker
whose parent has died exits within :data:`PARENT_CHECK_S` seconds, even mid-job.
"""

from __future__ import annotations

import contextlib
import faulthandler
import os
import sys
import threading
import time
import traceback
from typing import Any

#: How often a worker checks that the process that started it is still alive (seconds).
PARENT_CHECK_S = 0.5


def _watch_parent(parent_pid: int) -> None:
    while True:
        time.sleep(PARENT_CHECK_S)
        if os.getppid() != parent_pid:
            os._exit(1)


def _point_output_at(path: str) -> None:
    """Send fds 1 and 2 (and Python's sys.stdout/err, which sit on them) to ``path``."""
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    try:
        os.dup2(fd, 1)
        os.dup2(fd, 2)
    finally:
        os.close(fd)


def serve(conn: Any, spec: str, parent_pid: int, idle_log: str) -> None:
    """Serve jobs on ``conn`` (a ``multiprocessing`` connection) with job function ``spec``.

    ``spec`` names the job function (``"module:function"``); if that function has a
    callable ``warm_up`` attribute, it is called once here, before the worker reports
    ready, so its cost (imports, compiled kernels, model loading) is outside every job's
    cap. A failing warm-up is written to ``idle_log`` and otherwise ignored: the jobs then
    report the failure themselves. Output between jobs goes to ``idle_log``.
    """
    with contextlib.suppress(OSError):  # already a session leader
        os.setsid()
    threading.Thread(target=_watch_parent, args=(parent_pid,), daemon=True).start()
    _point_output_at(idle_log)
    faulthandler.enable()
    from lamp.bench.job_fn import call_job, resolve_job_fn

    fn = resolve_job_fn(spec)
    warm_up = getattr(fn, "warm_up", None)
    if callable(warm_up):
        try:
            warm_up()
        except Exception:  # the jobs will fail and say why; keep the worker usable
            traceback.print_exc()
    conn.send(("ready",))
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):  # the parent went away
            return
        if not message or message[0] != "job":
            return
        _, job, log_path = message
        _point_output_at(log_path)
        outcome = call_job(fn, job)
        _point_output_at(idle_log)
        try:
            conn.send(("done", outcome))
        except (EOFError, OSError):
            return
        except Exception as exc:  # the result cannot be pickled
            conn.send(("done", ("error", f"result cannot be sent back: {type(exc).__name__}: "
                                         f"{exc}", traceback.format_exc())))
