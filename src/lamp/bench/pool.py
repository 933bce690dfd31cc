"""The local backend: a pool of warm worker processes, each running many jobs under one cap each.

``run_local`` keeps at most ``workers`` worker processes (:mod:`lamp.bench.worker`, started
with the ``spawn`` context). A worker imports the job function and warms it up once, then
runs one job at a time, so the interpreter start-up, imports and first-call costs are paid
once per worker rather than once per job. What a job may rely on (and the tests check):

- its cap, ``job.time_cap_s`` seconds of wall clock, counts from the moment it is handed to
  a ready worker; a job still running then is recorded as ``"timeout"``, and its worker,
  with its whole process group, is killed and replaced;
- a worker that dies during a job (a segfault, the OOM killer, ``os._exit``) records the
  job as ``"crashed"`` with the tail of the job's output and is replaced; an exception in a
  job is ``"error"`` and the worker carries on;
- a worker retires after ``jobs_per_worker`` jobs (``1``: a fresh process per job;
  ``None``: never), which bounds what a leaking job can pass on to later ones;
- whenever ``run_local`` returns or raises (``KeyboardInterrupt``, the ``SIGTERM``
  handler of ``lamp bench``), no worker it started is left running and its scratch
  folder (``lamp-bench-*`` in the temporary directory) is gone.
"""

from __future__ import annotations

import contextlib
import itertools
import multiprocessing as mp
import os
import shutil
import signal
import tempfile
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from multiprocessing.connection import wait as wait_any
from pathlib import Path
from typing import Any

from lamp.bench.jobs import Job

#: Longest a worker may take from its start to ``ready`` (imports, Numba compilation on a
#: fresh installation, the job function's warm-up) before the run is aborted.
WORKER_START_TIMEOUT_S = 600.0
#: How long a retiring worker may take to exit before it is killed (seconds).
STOP_GRACE_S = 5.0


class WorkerStartError(RuntimeError):
    """A worker process died or hung before it could run a job (nothing would ever run)."""


@dataclass
class _Worker:
    """One worker process and the job it is running (``job is None``: idle)."""

    proc: Any  # multiprocessing.context.SpawnProcess
    conn: Any  # multiprocessing.connection.Connection, the parent's end
    idle_log: Path
    born: float
    ready: bool = False
    job: Job | None = None
    log_path: Path | None = None
    started: float = 0.0
    jobs_done: int = 0

    @property
    def deadline(self) -> float:
        if self.job is not None:
            return self.started + self.job.time_cap_s
        return self.born + WORKER_START_TIMEOUT_S if not self.ready else float("inf")


@dataclass
class JobOutcome:
    """How one job ended, as observed by the parent."""

    job: Job
    status: str  # ok | timeout | error | crashed
    result: dict[str, Any] | None
    wall_time_s: float
    detail: str = ""  # error message / traceback / tail of the job's output


def _log_name(job: Job) -> str:
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in job.label.replace(" ", "-"))
    return f"{job.suite}-{safe}.log"


def _tail(path: Path | None, n: int = 2000) -> str:
    if path is None:
        return ""
    try:
        data = path.read_bytes()
    except OSError:
        return ""
    return data[-n:].decode(errors="replace")


def _kill(w: _Worker) -> None:
    """Kill a worker we started and its process group (it leads its own session)."""
    pid = w.proc.pid
    if pid is not None:
        try:
            os.killpg(pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):  # before its setsid: just the process
            w.proc.kill()
    w.proc.join()
    w.conn.close()


def _stop(w: _Worker) -> None:
    """Ask an idle worker to exit; kill it if it does not within :data:`STOP_GRACE_S`."""
    with contextlib.suppress(OSError, ValueError):
        w.conn.send(("stop",))
    w.proc.join(STOP_GRACE_S)
    if w.proc.is_alive():
        _kill(w)
    else:
        w.conn.close()


def run_local(jobs: Sequence[Job], job_fn: str | Callable, workers: int,
              on_done: Callable[[JobOutcome], None], *, log_dir: str | Path | None = None,
              on_start: Callable[[Job], None] | None = None,
              jobs_per_worker: int | None = None) -> None:
    """Run ``jobs`` on at most ``workers`` warm worker processes; ``on_done`` once per job.

    ``on_done`` is called in the calling process, in completion order. A job's output goes
    to a log file, kept in ``log_dir`` (as ``SUITE-SCENE-PLANNER-sSEED.log``) when the job
    wrote anything. Raises :class:`WorkerStartError` when a worker dies before its first
    job (e.g. the job function's module fails to import there).
    """
    from lamp.bench.job_fn import job_fn_spec

    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers!r}")
    if jobs_per_worker is not None and jobs_per_worker < 1:
        raise ValueError(f"jobs_per_worker must be >= 1 or None, got {jobs_per_worker!r}")
    spec = job_fn_spec(job_fn)
    queue = deque(jobs)
    if not queue:
        return
    ctx = mp.get_context("spawn")
    pool: list[_Worker] = []
    with tempfile.TemporaryDirectory(prefix="lamp-bench-") as tmp:
        scratch = Path(tmp)
        job_numbers, worker_numbers = itertools.count(1), itertools.count(1)

        def spawn() -> None:
            from lamp.bench.worker import serve

            k = next(worker_numbers)
            idle_log = scratch / f"worker-{k}.log"
            parent_end, child_end = ctx.Pipe(duplex=True)
            proc = ctx.Process(target=serve, name=f"lamp-bench-worker-{k}",
                               args=(child_end, spec, os.getpid(), str(idle_log)))
            proc.start()
            child_end.close()
            pool.append(_Worker(proc, parent_end, idle_log, time.monotonic()))

        def finish(w: _Worker, outcome: JobOutcome) -> None:
            if log_dir is not None and w.log_path is not None and w.log_path.exists() \
                    and w.log_path.stat().st_size > 0:
                dest = Path(log_dir)
                dest.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(w.log_path, dest / _log_name(outcome.job))
            w.job, w.log_path = None, None
            on_done(outcome)

        try:
            while queue or any(w.job is not None for w in pool):
                busy = sum(w.job is not None for w in pool)
                while len(pool) < min(workers, busy + len(queue)):
                    spawn()
                for w in pool:
                    if queue and w.ready and w.job is None:
                        job, log_path = queue.popleft(), scratch / f"{next(job_numbers)}.log"
                        try:
                            w.conn.send(("job", job, str(log_path)))
                        except OSError:  # it died while idle; the job goes to another
                            queue.appendleft(job)
                            continue
                        w.job, w.log_path, w.started = job, log_path, time.monotonic()
                        if on_start is not None:
                            on_start(job)
                timeout = max(0.0, min(w.deadline for w in pool) - time.monotonic())
                wait_any([w.conn for w in pool] + [w.proc.sentinel for w in pool],
                         timeout=min(timeout, 3600.0))
                for w in list(pool):
                    _service(w, pool, finish, jobs_per_worker)
        except BaseException:
            for w in pool:
                _kill(w)
            raise
        for w in pool:
            _stop(w)


def _service(w: _Worker, pool: list[_Worker], finish: Callable[[_Worker, JobOutcome], None],
             jobs_per_worker: int | None) -> None:
    """Act on whatever happened to worker ``w``: a message, its death, or a passed deadline."""
    now = time.monotonic()
    message = None
    try:
        if w.conn.poll():
            message = w.conn.recv()
    except (EOFError, OSError):
        message = None  # it died; its sentinel tells below
    if message is not None:
        if message[0] == "ready":
            w.ready = True
        elif message[0] == "done" and w.job is not None:
            status, payload, tb = message[1]
            job, wall = w.job, now - w.started
            w.jobs_done += 1
            if status == "ok":
                finish(w, JobOutcome(job, "ok", payload, wall))
            else:
                finish(w, JobOutcome(job, "error", None, wall, detail=f"{payload}\n{tb}"))
            if jobs_per_worker is not None and w.jobs_done >= jobs_per_worker:
                pool.remove(w)
                _stop(w)
        return
    if not w.proc.is_alive():
        w.proc.join()
        pool.remove(w)
        w.conn.close()
        if w.job is not None:
            code = w.proc.exitcode
            finish(w, JobOutcome(w.job, "crashed", None, now - w.started,
                                 detail=f"process exited with code {code} without a result\n"
                                        f"{_tail(w.log_path)}"))
        elif not w.ready:
            raise WorkerStartError(f"a benchmark worker exited with code {w.proc.exitcode} "
                                   f"before its first job:\n{_tail(w.idle_log)}")
        return
    if now >= w.deadline:
        pool.remove(w)
        _kill(w)
        if w.job is None:
            raise WorkerStartError(f"a benchmark worker was not ready after "
                                   f"{WORKER_START_TIMEOUT_S:g} s:\n{_tail(w.idle_log)}")
        finish(w, JobOutcome(w.job, "timeout", None, now - w.started))
