"""``lamp bench`` and ``lamp report``: run the paper's experiments and rebuild their report.

Exit status: 0 when the run finished (whatever the planners' outcomes), 2 for bad input
(unknown suite or planner, bad numbers, a non-empty output folder without ``--resume``,
caps differing from the run being resumed, Ray missing, an unusable ``--db`` path,
``--rerun`` without ``--resume`` or naming a planner not run), 1 when no worker process can
start, 130 when interrupted and 143 when terminated (``SIGTERM``); after either, no worker
process is left running, the scratch folder is removed, and the run continues with
``--resume``.

The options are declared in :mod:`lamp.cli.bench_options`; :func:`bench_command` turns
them into one :class:`~lamp.bench.request.BenchRequest`, which checks them, and hands it to
:func:`run_bench`. What ``config.json`` records is :mod:`lamp.bench.provenance`.
"""

from __future__ import annotations

import json
import signal
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Any

import typer

import lamp.cli.bench_options as opt
from lamp.bench import provenance
from lamp.bench.jobs import (
    RESULTS_FILE,
    Job,
    enumerate_jobs,
    load_suite,
    pending_jobs,
    read_records,
)
from lamp.bench.provenance import CONFIG_FILE, current_runs, write_config
from lamp.bench.request import BenchRequest
from lamp.cli.support import fail_input as _fail

#: A rendering job gets this many times its usual cap (frame capture and GIF encoding).
RENDER_CAP_FACTOR = 2.0
IROS_GIF = "iros.gif"


class Terminated(BaseException):
    """Raised in the main thread by ``SIGTERM`` while a benchmark runs (see :func:`on_sigterm`).

    A ``BaseException``, like ``KeyboardInterrupt``, so that only the clean-up code that
    must run (killing workers, removing the scratch folder) sees it on its way out.
    """


@contextmanager
def on_sigterm() -> Iterator[None]:
    """Turn ``SIGTERM`` into :class:`Terminated` inside the block (main thread only)."""
    def handler(signum, _frame):
        raise Terminated(signum)

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread: leave the default (terminate)
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _render_jobs(jobs: list[Job], pending: list[Job], out: Path, time_cap: float
                 ) -> list[Job]:
    """Pending jobs with the IROS animation requested (``--render-iros``).

    The first LAMP-Lazy IROS job renders while it runs; if it already ran (resume) and the
    GIF is missing, a render-only job (not recorded) re-runs it with the same seed.
    """
    gif = out / IROS_GIF
    if gif.exists():
        return pending
    iros = [j for j in jobs if j.suite == "iros" and j.planner == "lazy"]
    target = min(iros, key=lambda j: j.seed) if iros else None
    if target is not None and target in pending:
        return [replace(j, render_to=str(gif), time_cap_s=j.time_cap_s * RENDER_CAP_FACTOR)
                if j == target else j for j in pending]
    base = target or next((j for j in jobs if j.suite == "iros"), None)
    if base is None:
        return pending
    render = replace(base, planner="lazy", render_to=str(gif), record=False,
                     time_cap_s=time_cap * len(base.scene.objects) * RENDER_CAP_FACTOR)
    return [*pending, render]


def bench_command(
    suite: str = opt.SUITES,
    suite_alias: str = opt.SUITE_ALIAS,
    planners: str = opt.PLANNERS,
    seeds: int = opt.SEEDS,
    seeds_alias: int = opt.SEEDS_ALIAS,
    workers: int = opt.WORKERS,
    out: Path = opt.OUT,
    resume: bool = opt.RESUME,
    time_cap: float = opt.TIME_CAP,
    planning_limit: float = opt.PLANNING_LIMIT,
    planning_limit_alias: float = opt.PLANNING_LIMIT_ALIAS,
    model: str = opt.MODEL,
    backend: str = opt.BACKEND,
    ray_address: str = opt.RAY_ADDRESS,
    scenes: int = opt.SCENES,
    record: bool = opt.RECORD,
    render_iros: bool = opt.RENDER_IROS,
    retry_errors: bool = opt.RETRY_ERRORS,
    rerun: str = opt.RERUN,
    report: bool = opt.REPORT,
    progress: bool = opt.PROGRESS,
    quiet: bool = opt.QUIET,
    dry_run: bool = opt.DRY_RUN,
    job_fn: str = opt.JOB_FN,
    jobs_per_worker: int = opt.JOBS_PER_WORKER,
    db: Path = opt.DB,
    param: list[str] = opt.PARAM,
    disturb: str = opt.DISTURB,
    schedule: str = opt.SCHEDULE,
) -> None:
    """Run planners over benchmark suites; write results.jsonl, config.json and report.md."""
    if suite_alias is not None:  # the old spellings
        suite = suite_alias
    if seeds_alias is not None:
        seeds = seeds_alias
    if planning_limit_alias is not None:
        planning_limit = planning_limit_alias
    request = BenchRequest(  # checks every value (bad input: exit 2)
        out=out, suites=tuple(suite.split(",")), planners=tuple(planners.split(",")),
        seeds=seeds, scenes=scenes, model=model, time_cap=time_cap,
        planning_limit=planning_limit, params=tuple(param or ()), disturb=disturb,
        schedule=schedule, workers=workers, backend=backend, ray_address=ray_address,
        jobs_per_worker=jobs_per_worker, job_fn=job_fn, resume=resume,
        retry_errors=retry_errors, rerun=tuple(rerun.split(",")), record=record,
        render_iros=render_iros, report=report, db=db, dry_run=dry_run, progress=progress,
        quiet=quiet)
    run_bench(request)


def run_bench(request: BenchRequest) -> None:
    """Run ``request``: check the output folder, list the jobs, run those pending, write the
    report (and the database); exit status as the module says."""
    out, say = request.out, _say(request)
    previous = _previous_config(request)
    jobs = _load_jobs(request)
    if request.render_iros and not any(j.suite == "iros" for j in jobs):
        _fail("--render-iros needs the iros suite in --suites")
    records = read_records(out / RESULTS_FILE) if request.resume else []
    current = (current_runs(previous, *provenance.code_version(out)) if request.rerun
               else set())
    pending = pending_jobs(jobs, records, retry_errors=request.retry_errors,
                           rerun=list(request.rerun), current_runs=current)
    if request.render_iros:
        pending = _render_jobs(jobs, pending, out, request.time_cap)
    if request.record:
        pending = _with_recordings(pending, out)
    _print_plan(jobs, pending, request)
    if request.dry_run:
        return

    if pending:  # a resume with nothing to do records no new run
        _run_pending(pending, jobs, previous, request)
    has_results = (out / RESULTS_FILE).exists()
    if request.report and has_results:
        _write_report(out, say)
    if request.db is not None and has_results:
        from lamp.bench.db import write_db

        say(f"wrote {write_db(out, request.db)}")


def _say(request: BenchRequest) -> Callable[[str], None]:
    """What prints a line of the run's chatter on stdout: ``typer.echo``, or nothing when
    ``--quiet``."""
    return (lambda _line: None) if request.quiet else typer.echo


def _previous_config(request: BenchRequest) -> dict[str, Any]:
    """The config.json of the run resumed in ``--out`` ({} if none); exits 2 when the
    folder is not a folder, is not empty without ``--resume``, or was run with other
    settings."""
    out = request.out
    previous: dict[str, Any] = {}
    if not request.dry_run and out.exists():
        if not out.is_dir():
            _fail(f"--out: {out} exists and is not a folder")
        if any(out.iterdir()) and not request.resume:
            _fail(f"--out: {out} is not empty; pass --resume to continue the run recorded "
                  "there, or choose a new folder")
    if request.resume and (out / CONFIG_FILE).exists():
        try:
            previous = json.loads((out / CONFIG_FILE).read_text())
        except json.JSONDecodeError:
            previous = {}
        request.check_resumable(previous)
    return previous


def _load_jobs(request: BenchRequest) -> list[Job]:
    """Every job of the run (see :func:`lamp.bench.jobs.enumerate_jobs`); a suite that
    fails to load exits 2."""
    try:
        loaded = [load_suite(name) for name in request.suites]
        return enumerate_jobs(loaded, list(request.planners), request.seed_list,
                              scenes_per_suite=request.scenes, model=request.model,
                              time_cap_s=request.time_cap,
                              planning_limit_s=request.planning_limit,
                              params=request.planner_params, disturb=request.disturb,
                              schedule=request.schedule)
    except ValueError as exc:
        _fail(f"--suites: {exc}")
    except Exception as exc:  # a scene that fails to load is bad input too
        _fail(f"--suites: {type(exc).__name__}: {exc}")


def _with_recordings(pending: list[Job], out: Path) -> list[Job]:
    """``pending`` with each recorded job saving its recording under ``out/recordings``."""
    return [replace(j, recording_to=str(out / "recordings" / j.suite /
                                        f"{j.scene_name}-{j.planner}-s{j.seed}"))
            if j.record else j for j in pending]


def _print_plan(jobs: list[Job], pending: list[Job], request: BenchRequest) -> None:
    """Say how many jobs there are and how many will run; with ``--dry-run``, which (even
    when ``--quiet``: the list is what a dry run is for)."""
    say = typer.echo if request.dry_run else _say(request)
    per = Counter((j.suite, j.planner) for j in pending if j.record)
    say(f"{len(jobs)} jobs ({len({(j.suite, j.scene_name) for j in jobs})} scenes x "
        f"{len(request.planners)} planners x {request.seeds} seeds); {len(pending)} to run"
        + (f", {len(jobs) - sum(per.values())} already recorded" if request.resume else "")
        + (f"; re-running {', '.join(request.rerun)}" if request.rerun else ""))
    if request.dry_run:
        for (s, p), n in sorted(per.items()):
            say(f"  {s:12s} {p:14s} {n}")
        for j in pending:
            if j.render_to:
                say(f"  renders {j.render_to} ({j.label})")
            if j.recording_to:
                say(f"  records into {j.recording_to} ({j.label})")


def _run_pending(pending: list[Job], jobs: list[Job], previous: dict[str, Any],
                 request: BenchRequest) -> None:
    """Record this invocation in config.json and run ``pending``; exit 130/143 if stopped."""
    out, say = request.out, _say(request)
    out.mkdir(parents=True, exist_ok=True)
    run_id = len(previous.get("sessions") or [])
    write_config(out, previous, command=request.command_line(),
                 suites=list(dict.fromkeys(j.suite for j in jobs)),
                 planners=list(request.planners), seeds=request.seed_list,
                 workers=request.workers, backend=request.backend, model=request.model,
                 time_cap=request.time_cap, planning_limit=request.planning_limit,
                 scenes=request.scenes, job_fn=request.job_fn, params=list(request.params),
                 disturb=request.disturb, schedule=request.schedule)
    from lamp.bench.pool import WorkerStartError
    from lamp.bench.runner import execute

    stopped, code = "", 0
    try:
        with on_sigterm():
            summary = execute(pending, out, job_fn=request.job_fn, backend=request.backend,
                              workers=request.workers, ray_address=request.ray_address,
                              progress=request.show_progress,
                              echo=(lambda _line: None) if request.quiet else None,
                              log_dir=out / "logs",
                              jobs_per_worker=request.jobs_per_worker or None, run_id=run_id)
    except KeyboardInterrupt:
        stopped, code = "interrupted", 130
    except Terminated:
        stopped, code = "terminated", 143
    except WorkerStartError as exc:  # nothing can run here; finished jobs are kept
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(code=1) from None
    if stopped:
        typer.echo(f"\n{stopped}: finished jobs are in {out / RESULTS_FILE}; continue with "
                   "the same command plus --resume", err=True)
        raise typer.Exit(code=code)
    done = sum(summary.statuses.values())
    say(f"ran {done} jobs in {summary.wall_time_s:.0f} s: {summary.successes} solved; "
        + ", ".join(f"{k} {v}" for k, v in sorted(summary.statuses.items())))
    for path in summary.rendered:
        say(f"wrote {path}")


def _write_report(run_dir: Path, say: Callable[[str], None] = typer.echo) -> None:
    """Write ``run_dir/report.md``; ``say`` the success rates (Table I) and where it went."""
    from lamp.bench.report import build_report, family_records, load_results, success_table

    path = build_report(run_dir)
    records = load_results(run_dir)
    table = success_table(records)
    if family_records(records):
        say("success rate (Table I):")
        for p, row in table.items():
            say(f"  {p:14s} " + "  ".join(f"{f} {r.percent()}" for f, r in row.items()))
    say(f"wrote {path}")


def report_command(
    run_dir: Path = typer.Argument(..., help="A folder written by lamp bench."),
    db: Path = typer.Option(None, "--db", help="Also (re)write the results as an SQLite "
                            "database at this path (schema: docs/bench-db.md).",
                            show_default="no database"),
) -> None:
    """Rebuild DIR/report.md and its figures from DIR/results.jsonl (no rerun)."""
    if not (run_dir / RESULTS_FILE).exists():
        _fail(f"{run_dir}: no {RESULTS_FILE} here (is it a lamp bench output folder?)")
    if db is not None:
        from lamp.bench.db import check_db_path, write_db

        try:
            check_db_path(db)
        except ValueError as exc:
            _fail(f"--db: {exc}")
    _write_report(run_dir)
    if db is not None:
        typer.echo(f"wrote {write_db(run_dir, db)}")
