"""Run benchmark jobs, each in its own process under a wall-clock cap, and record the results.

Two backends share one contract: every job runs in a fresh process; a job still running at
its cap is killed and recorded as a failure with reason ``"timeout"`` (its planning time is
the cap); an exception in the job becomes status ``"error"`` and a dead process status
``"crashed"``. The parent process alone writes ``results.jsonl`` (through
:class:`lamp.bench.jobs.ResultsFile`, which is also safe for several writers).

- ``local``: a pool of ``workers`` slots on this machine; each job is a fresh
  ``python -m lamp.bench.worker`` process in its own session (no inherited threads, locks or
  state; a kill takes its whole process group).
- ``ray``: the same jobs as Ray tasks with ``max_calls=1`` (a fresh worker process per job)
  on a local or remote Ray cluster; Ray is an optional extra (``pip install lamp[ray]``).

The function that runs one job is injectable (``job_fn``: a ``"module:function"`` string or
an importable top-level function taking a :class:`~lamp.bench.jobs.Job` and returning a
result.json ``dict``), so the machinery can be tested without the planners
(:mod:`lamp.bench.fake`).
"""

from __future__ import annotations

import importlib
import logging
import os
import pickle
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from collections import Counter, deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from lamp.bench.jobs import Job, ResultsFile, failure_result, make_record

log = logging.getLogger(__name__)

#: The production job function: plan and execute with ``lamp.planners.run``.
DEFAULT_JOB_FN = "lamp.bench.runner:solve_job"

BACKENDS = ("local", "ray")

JobFn = Callable[[Job], dict[str, Any]]

#: Thread-count variables set (if unset) for job processes: one job, one core.
THREAD_ENV = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")

#: Longest traceback kept in a results line.
MAX_TRACEBACK = 4000


def solve_job(job: Job) -> dict[str, Any]:
    """Run one job with the real planners; write ``job.render_to`` when rendering is asked
    and save the recording into ``job.recording_to`` when recording is.

    A failure to write the animation (recording) is reported on stderr (kept in the job's
    log) and in the result's ``render_error`` (``recording_error``) key; it never costs the
    run's result.
    """
    from lamp.planners.run import solve_with_frames

    render = job.render_to is not None
    solution = solve_with_frames(job.scene, job.planner, job.seed, model=job.model,
                                 render=render, time_limit=job.time_limit)
    result = solution.result.to_dict()
    if render:
        target = Path(str(job.render_to))
        partial = target.with_name(f".{target.stem}.partial{target.suffix}")
        try:
            from lamp.viz.animation import write_animation

            write_animation(job.scene, solution.frames, partial)
            os.replace(partial, target)
        except Exception as exc:  # the run itself is still a valid result
            traceback.print_exc()
            result["render_error"] = f"{type(exc).__name__}: {exc}"
    if job.recording_to is not None:
        try:
            from lamp.record import save_recording

            if solution.recording is None:
                raise ValueError("the run returned no recording")
            save_recording(solution.recording, job.recording_to)
        except Exception as exc:  # as for the animation: the result stands
            traceback.print_exc()
            result["recording_error"] = f"{type(exc).__name__}: {exc}"
    return result


def resolve_job_fn(spec: str | JobFn) -> JobFn:
    """A job function from ``"package.module:function"`` (or the callable itself)."""
    if callable(spec):
        return spec
    if not isinstance(spec, str) or ":" not in spec:
        raise ValueError(f"job_fn must be 'module:function' or a callable, got {spec!r}")
    module, _, name = spec.partition(":")
    try:
        fn = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"job_fn {spec!r} cannot be imported: {exc}") from exc
    if not callable(fn):
        raise ValueError(f"job_fn {spec!r} is not callable")
    return fn


def job_fn_spec(fn: str | JobFn) -> str:
    """``"module:function"`` for ``fn``; job processes import the job function by this name.

    Raises ``ValueError`` for a callable that cannot be imported by name (a lambda, a
    nested function, one defined in ``__main__``).
    """
    if isinstance(fn, str):
        resolve_job_fn(fn)  # fail early, in the parent, with a clear message
        return fn
    module, qual = getattr(fn, "__module__", None), getattr(fn, "__qualname__", "")
    if not module or module == "__main__" or "<" in qual or "." in qual:
        raise ValueError(f"job_fn {fn!r} must be a top-level function of an importable module")
    spec = f"{module}:{qual}"
    resolve_job_fn(spec)
    return spec


def call_job(spec: str | JobFn, job: Job) -> tuple[str, Any, str]:
    """Run the job; ``("ok", result, "")`` or ``("error", message, traceback)``."""
    try:
        result = resolve_job_fn(spec)(job)
        if not isinstance(result, dict):
            raise TypeError(f"job function returned {type(result).__name__}, expected dict")
        return ("ok", result, "")
    except Exception as exc:  # recorded as status "error", never lost
        return ("error", f"{type(exc).__name__}: {exc}", traceback.format_exc()[-MAX_TRACEBACK:])


@dataclass
class JobOutcome:
    """How one job ended, as observed by the parent."""

    job: Job
    status: str  # ok | timeout | error | crashed
    result: dict[str, Any] | None
    wall_time_s: float
    detail: str = ""  # error message / traceback / tail of the job's output


def outcome_record(outcome: JobOutcome) -> dict[str, Any]:
    """The results line for an outcome (see :mod:`lamp.bench.jobs`)."""
    job, wall = outcome.job, outcome.wall_time_s
    if outcome.status == "ok":
        return make_record(job, outcome.result or {}, status="ok", job_wall_time_s=wall)
    if outcome.status == "timeout":
        res = failure_result(job, "timeout", planning_time_s=job.time_cap_s, wall_time_s=wall)
    else:
        reason = outcome.detail.splitlines()[0] if outcome.detail else outcome.status
        res = failure_result(job, f"{outcome.status}: {reason}", planning_time_s=wall,
                             wall_time_s=wall)
    rec = make_record(job, res, status=outcome.status, job_wall_time_s=wall)
    if outcome.status != "timeout" and outcome.detail:
        rec["error_detail"] = outcome.detail[-MAX_TRACEBACK:]
    return rec


def limit_threads(threads: int = 1) -> None:
    """Set the thread-count variables job processes inherit, where the user has not."""
    for var in THREAD_ENV:
        os.environ.setdefault(var, str(threads))


# --------------------------------------------------------------------------- local backend
#: How often the local backend looks at its job processes (seconds).
POLL_INTERVAL = 0.05


@dataclass
class _Running:
    job: Job
    proc: subprocess.Popen
    out_path: Path
    log_path: Path
    log_file: Any
    start: float

    @property
    def deadline(self) -> float:
        return self.start + self.job.time_cap_s


def _kill(proc: subprocess.Popen) -> None:
    """Kill a job process we started and its process group (it runs in its own session)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        proc.kill()
    proc.wait()


def _log_name(job: Job) -> str:
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in job.label.replace(" ", "-"))
    return f"{job.suite}-{safe}.log"


def run_local(jobs: Sequence[Job], job_fn: str | JobFn, workers: int,
              on_done: Callable[[JobOutcome], None], *, log_dir: str | Path | None = None,
              on_start: Callable[[Job], None] | None = None) -> None:
    """Run ``jobs`` with at most ``workers`` concurrent job processes; ``on_done`` per job.

    Each job is ``python -m lamp.bench.worker`` in a new session; its cap is
    ``job.time_cap_s`` seconds of wall clock from its start, after which its process group
    is killed. A job's stdout/stderr go to a log file, kept in ``log_dir`` (when given) if
    the job wrote anything. On ``KeyboardInterrupt`` every running job is killed first.
    """
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers!r}")
    spec = job_fn_spec(job_fn)
    queue = deque(jobs)
    running: list[_Running] = []
    with tempfile.TemporaryDirectory(prefix="lamp-bench-") as scratch:
        try:
            n = 0
            while queue or running:
                while queue and len(running) < workers:
                    job = queue.popleft()
                    n += 1
                    job_path = Path(scratch) / f"{n}.job"
                    with open(job_path, "wb") as f:
                        pickle.dump((spec, job), f)
                    out_path = Path(scratch) / f"{n}.out"
                    log_path = Path(scratch) / f"{n}.log"
                    log_file = open(log_path, "wb")  # noqa: SIM115 - closed in _finish
                    proc = subprocess.Popen(
                        [sys.executable, "-m", "lamp.bench.worker", str(job_path), str(out_path)],
                        stdin=subprocess.DEVNULL, stdout=log_file, stderr=subprocess.STDOUT,
                        start_new_session=True)
                    running.append(_Running(job, proc, out_path, log_path, log_file,
                                            time.monotonic()))
                    if on_start is not None:
                        on_start(job)
                time.sleep(POLL_INTERVAL)
                still: list[_Running] = []
                for r in running:
                    outcome = _poll(r)
                    if outcome is None:
                        still.append(r)
                        continue
                    _keep_log(r, outcome, log_dir)
                    on_done(outcome)
                running = still
        except BaseException:
            for r in running:
                _kill(r.proc)
                r.log_file.close()
            raise


def _poll(r: _Running) -> JobOutcome | None:
    """The outcome of a running job if it has one now (finished, died or reached its cap)."""
    now = time.monotonic()
    code = r.proc.poll()
    if code is None:
        if now < r.deadline:
            return None
        _kill(r.proc)
        r.log_file.close()
        return JobOutcome(r.job, "timeout", None, now - r.start)
    r.log_file.close()
    if code == 0 and r.out_path.exists():
        with open(r.out_path, "rb") as f:
            status, payload, tb = pickle.load(f)
        if status == "ok":
            return JobOutcome(r.job, "ok", payload, now - r.start)
        return JobOutcome(r.job, "error", None, now - r.start, detail=f"{payload}\n{tb}")
    tail = _tail(r.log_path)
    return JobOutcome(r.job, "crashed", None, now - r.start,
                      detail=f"process exited with code {code} without a result\n{tail}")


def _tail(path: Path, n: int = 2000) -> str:
    try:
        data = path.read_bytes()
    except OSError:
        return ""
    return data[-n:].decode(errors="replace")


def _keep_log(r: _Running, outcome: JobOutcome, log_dir: str | Path | None) -> None:
    if log_dir is None or not r.log_path.exists() or r.log_path.stat().st_size == 0:
        return
    dest = Path(log_dir)
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(r.log_path, dest / _log_name(r.job))


# ----------------------------------------------------------------------------- ray backend
#: Added to a Ray task's cap: worker start-up and imports happen after submission.
RAY_START_GRACE_S = 30.0


def _ray_task(spec: str, job: Job) -> tuple[str, Any, str]:
    return call_job(spec, job)


def import_ray():
    """``ray``, or a ``RuntimeError`` saying how to install it."""
    try:
        import ray
    except ImportError as exc:
        raise RuntimeError("the ray backend needs Ray: pip install 'lamp[ray]' "
                           "(or pip install ray)") from exc
    return ray


def run_ray(jobs: Sequence[Job], job_fn: str | JobFn, workers: int | None,
            on_done: Callable[[JobOutcome], None], *, address: str | None = None,
            on_start: Callable[[Job], None] | None = None,
            start_grace_s: float = RAY_START_GRACE_S) -> None:
    """Run ``jobs`` as Ray tasks, at most ``workers`` at a time (default: the cluster's CPUs).

    Connects to ``address`` (e.g. ``"auto"`` or ``"ray://head:10001"``) when given, else
    starts a private local cluster of ``workers`` CPUs and shuts it down afterwards. Each
    task runs in a fresh worker process (``max_calls=1``); a task past its cap is cancelled
    with ``force=True``, which kills its worker. The cap counts from submission plus
    ``start_grace_s`` (a fresh Ray worker takes seconds to start and import); at most as
    many tasks as there are slots are in flight, so queueing does not eat into it.
    """
    ray = import_ray()
    spec = job_fn_spec(job_fn)
    started_here = False
    if not ray.is_initialized():
        env = {var: os.environ.get(var, "1") for var in THREAD_ENV}
        kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                  "logging_level": logging.WARNING,
                                  "runtime_env": {"env_vars": env}}
        if address:
            ray.init(address=address, **kwargs)
        else:  # a private single-machine instance, shut down when the run ends
            ray.init(num_cpus=workers or os.cpu_count() or 1, **kwargs)
        started_here = True
    try:
        slots = workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
        task = ray.remote(num_cpus=1, max_calls=1, max_retries=0)(_ray_task)
        queue = deque(jobs)
        running: dict[Any, tuple[Job, float]] = {}
        while queue or running:
            while queue and len(running) < slots:
                job = queue.popleft()
                running[task.remote(spec, job)] = (job, time.monotonic())
                if on_start is not None:
                    on_start(job)
            now = time.monotonic()
            timeout = max(0.0, min(t0 + j.time_cap_s + start_grace_s
                                   for j, t0 in running.values()) - now)
            ready, _ = ray.wait(list(running), num_returns=1, timeout=timeout)
            now = time.monotonic()
            for ref in ready:
                job, t0 = running.pop(ref)
                on_done(_ray_outcome(ray, ref, job, now - t0))
            for ref, (job, t0) in list(running.items()):
                if now >= t0 + job.time_cap_s + start_grace_s:
                    ray.cancel(ref, force=True)
                    del running[ref]
                    on_done(JobOutcome(job, "timeout", None, now - t0))
    finally:
        if started_here:
            ray.shutdown()


def _ray_outcome(ray, ref, job: Job, wall: float) -> JobOutcome:
    try:
        status, payload, tb = ray.get(ref)
    except Exception as exc:  # worker died (OOM, segfault) or the task could not run
        return JobOutcome(job, "crashed", None, wall, detail=f"{type(exc).__name__}: {exc}")
    if status == "ok":
        return JobOutcome(job, "ok", payload, wall)
    return JobOutcome(job, "error", None, wall, detail=f"{payload}\n{tb}")


# ------------------------------------------------------------------------ orchestration
@dataclass
class BenchSummary:
    """What a benchmark invocation did."""

    jobs: int = 0
    statuses: Counter = field(default_factory=Counter)
    successes: int = 0
    wall_time_s: float = 0.0
    rendered: list[str] = field(default_factory=list)


def execute(jobs: Sequence[Job], out_dir: str | Path, *, job_fn: str | JobFn = DEFAULT_JOB_FN,
            backend: str = "local", workers: int = 1, ray_address: str | None = None,
            progress: bool = True, echo: Callable[[str], None] | None = None,
            threads_per_job: int = 1, log_dir: str | Path | None = None) -> BenchSummary:
    """Run ``jobs`` and append one line per recorded job to ``out_dir/results.jsonl``.

    ``progress`` shows a rich progress bar with an ETA; ``echo`` (default: the progress
    console) receives one line per finished job.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    from lamp.bench.jobs import RESULTS_FILE

    results = ResultsFile(Path(out_dir) / RESULTS_FILE)
    limit_threads(threads_per_job)
    summary = BenchSummary(jobs=len(jobs))
    t_start = time.monotonic()
    bar = _ProgressBar(len(jobs), enabled=progress)
    say = echo or bar.print

    def on_done(outcome: JobOutcome) -> None:
        job = outcome.job
        if job.record:
            rec = outcome_record(outcome)
            results.append(rec)
            summary.statuses[outcome.status] += 1
            summary.successes += bool(rec.get("success"))
            verdict = "success" if rec.get("success") else f"failed ({rec['failure_reason']})"
        else:
            verdict = "rendered" if outcome.status == "ok" else f"render {outcome.status}"
        if outcome.status == "ok" and job.render_to:
            summary.rendered.append(job.render_to)
        say(f"{job.suite}/{job.label}: {verdict} in {outcome.wall_time_s:.1f} s")
        bar.advance(summary)

    with bar:
        if backend == "local":
            run_local(jobs, job_fn, workers, on_done, log_dir=log_dir)
        else:
            run_ray(jobs, job_fn, workers, on_done, address=ray_address)
    summary.wall_time_s = time.monotonic() - t_start
    return summary


class _ProgressBar:
    """A rich progress bar with an ETA, or nothing (plain lines) when disabled."""

    def __init__(self, total: int, enabled: bool):
        self.total = total
        self.enabled = enabled
        self._progress = None
        self._task = None

    def __enter__(self) -> _ProgressBar:
        if self.enabled:
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._progress = Progress(
                TextColumn("[bold]lamp bench"), BarColumn(), MofNCompleteColumn(),
                TextColumn("{task.fields[stats]}"), TimeElapsedColumn(), TextColumn("ETA"),
                TimeRemainingColumn(), speed_estimate_period=24 * 3600.0)
            self._progress.start()
            self._task = self._progress.add_task("jobs", total=self.total, stats="")
        return self

    def __exit__(self, *exc) -> None:
        if self._progress is not None:
            self._progress.stop()

    def print(self, line: str) -> None:
        if self._progress is not None:
            self._progress.console.print(line, markup=False, highlight=False)
        else:
            print(line, flush=True)

    def advance(self, summary: BenchSummary) -> None:
        if self._progress is not None:
            done = sum(summary.statuses.values())
            stats = f"{summary.successes}/{done} solved"
            bad = {k: v for k, v in summary.statuses.items() if k != "ok"}
            if bad:
                stats += " " + " ".join(f"{k} {v}" for k, v in sorted(bad.items()))
            self._progress.update(self._task, advance=1, stats=stats)
