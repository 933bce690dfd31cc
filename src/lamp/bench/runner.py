"""Run benchmark jobs under a wall-clock cap each, in isolated processes, and record the results.

Two backends share one contract: a job still running at its cap is killed and recorded as
a failure with reason ``"timeout"`` (its planning time is the cap); an exception in the job
becomes status ``"error"`` and a dead process status ``"crashed"``; neither affects any
other job. The parent process alone writes ``results.jsonl`` (through
:class:`lamp.bench.jobs.ResultsFile`, which is also safe for several writers).

- ``local``: a pool of ``workers`` warm worker processes on this machine
  (:mod:`lamp.bench.pool`): each imports and warms up the planners once and then runs one
  job at a time; a worker past a job's cap or dead is replaced by a fresh one.
- ``ray``: the same jobs as Ray tasks with ``max_calls=1`` (a fresh worker process per job)
  on a local or remote Ray cluster; Ray is an optional extra (``pip install lamp[ray]``).

The function that runs one job is injectable (``job_fn``: a ``"module:function"`` string or
an importable top-level function taking a :class:`~lamp.bench.jobs.Job` and returning a
result.json ``dict``), so the machinery can be tested without the planners (the tests'
stand-ins, ``tests/bench_fakes.py``). Every job process imports it by that name: its module
must be importable there too (the tests put their folder on ``PYTHONPATH``).
"""

from __future__ import annotations

import logging
import os
import time
import traceback
from collections import Counter, deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from lamp.bench.job_fn import MAX_TRACEBACK, JobFn, call_job, job_fn_spec
from lamp.bench.jobs import Job, ResultsFile, failure_result, make_record
from lamp.bench.pool import JobOutcome, run_local

log = logging.getLogger(__name__)

#: The production job function: plan and execute with ``lamp.pipeline.run``.
DEFAULT_JOB_FN = "lamp.bench.runner:solve_job"

BACKENDS = ("local", "ray")

#: Thread-count variables set (if unset) for job processes: one job, one core.
THREAD_ENV = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")


def solve_job(job: Job) -> dict[str, Any]:
    """Run one job with the real planners; write ``job.render_to`` when rendering is asked
    and save the recording into ``job.recording_to`` when recording is, with the
    recording's re-check (:func:`audit_summary`) in the result's ``audit`` key.

    A failure to write the animation (recording) is reported on stderr (kept in the job's
    log) and in the result's ``render_error`` (``recording_error``) key; it never costs the
    run's result.
    """
    from lamp.bench.disturb import disturbances_for
    from lamp.pipeline import RunRequest, run

    request = RunRequest.build(job.scene, job.planner, job.seed, model=job.model,
                               params=dict(job.params), planning_limit=job.time_limit,
                               max_segments=job.max_segments,
                               disturbances=disturbances_for(job.disturb, job.scene, job.seed))
    result_obj = run(request)
    recording = result_obj.recording
    result = result_obj.to_dict()
    if job.render_to is not None:  # drawn from the recording, as `lamp render` does
        target = Path(str(job.render_to))
        partial = target.with_name(f".{target.stem}.partial{target.suffix}")
        try:
            from lamp.viz.replay import render

            render(recording, partial)
            os.replace(partial, target)
        except Exception as exc:  # the run itself is still a valid result
            traceback.print_exc()
            result["render_error"] = f"{type(exc).__name__}: {exc}"
    if job.recording_to is not None:
        try:
            from lamp.record import save_recording

            save_recording(recording, job.recording_to)
        except Exception as exc:  # as for the animation: the result stands
            traceback.print_exc()
            result["recording_error"] = f"{type(exc).__name__}: {exc}"
        result["audit"] = audit_summary(recording)
    return result


def audit_summary(recording) -> dict[str, Any]:
    """A recorded run re-checked as ``lamp check`` does (``lamp.record.audit``): its
    collisions, whether its push lead was judged, the lead and the verdict; ``error``
    instead when the check itself failed (the run's result stands)."""
    from lamp.fleet.spacetime import PUSH_LEAD, PUSH_SPEEDUP
    from lamp.record.audit import ReachBound, audit_recording

    try:
        audit = audit_recording(recording, ReachBound(PUSH_SPEEDUP, PUSH_LEAD))
    except Exception as exc:
        traceback.print_exc()
        return {"error": f"{type(exc).__name__}: {exc}"}
    lead = audit.reach.lead if audit.reach is not None and audit.reach.object >= 0 else None
    return {"ok": audit.ok, "collisions": len(audit.safety.violations),
            "push_lead_m": lead, "push_lead_judged": not audit.not_judged}


def warm_up_solver() -> None:
    """Load every planning kernel and the shipped model once, before a worker's first job.

    Called by each local worker process (see :mod:`lamp.bench.worker`), so neither a job's
    cap nor its wall time includes imports, cached-kernel loading or (on a fresh
    installation) Numba compilation (:func:`lamp.pipeline.warmup.ensure_warm`). Plans are
    deterministic per scene, planner and seed, so a job's result does not depend on
    whether this ran before it.
    """
    from lamp.manip.models import load_proposer
    from lamp.pipeline.warmup import ensure_warm

    ensure_warm()
    load_proposer("learned")


solve_job.warm_up = warm_up_solver  # type: ignore[attr-defined]  # see lamp.bench.worker


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
            threads_per_job: int = 1, log_dir: str | Path | None = None,
            jobs_per_worker: int | None = None, run_id: int | None = None) -> BenchSummary:
    """Run ``jobs`` and append one line per recorded job to ``out_dir/results.jsonl``.

    ``progress`` shows a rich progress bar with an ETA; ``echo`` (default: the progress
    console) receives one line per finished job. ``jobs_per_worker`` retires a local worker
    after that many jobs (``None``: never). ``run_id``, when given, is stored in every line
    as ``"run_id"`` (the index of this invocation in ``config.json``'s ``sessions``).
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
            if run_id is not None:
                rec["run_id"] = int(run_id)
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
            run_local(jobs, job_fn, workers, on_done, log_dir=log_dir,
                      jobs_per_worker=jobs_per_worker)
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
