"""``lamp bench`` and ``lamp report``: run the paper's experiments and rebuild their report.

Registered by ``lamp.cli`` as ``app.command("bench")(bench_command)`` and
``app.command("report")(report_command)``. Exit status: 0 when the run finished (whatever
the planners' outcomes), 2 for bad input (unknown suite or planner, bad numbers, a non-empty
output folder without ``--resume``, caps differing from the run being resumed, Ray missing,
an unusable ``--db`` path, ``--rerun`` without ``--resume`` or naming a planner not run), 1 when no worker process can start, 130 when interrupted and 143
when terminated (``SIGTERM``); after either, no worker process is left running, the scratch
folder is removed, and the run continues with ``--resume``.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import shlex
import signal
import subprocess
import sys
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import typer

from lamp.bench.jobs import (
    RESULTS_FILE,
    Job,
    enumerate_jobs,
    load_suite,
    pending_jobs,
    planning_limit_applies,
    read_records,
)
from lamp.bench.runner import BACKENDS, DEFAULT_JOB_FN
from lamp.planners import registry

DEFAULT_SUITES = "random,maze,tilt,warehouse"
#: Default cumulative planning limit per object for LAMP-A* (the paper: 500 s). The paper's
#: LAMP-A* runs out of it in most cluttered scenes, so 100 scenes x 2 LAMP-A* variants at
#: 500 s would alone take ~28 h of CPU. A full run has about 2 h x 2 cores = 14,400 CPU-s;
#: leaving ~7,000 for LAMP-Lazy, the GCo baselines, IROS and per-job start-up gives ~35 s
#: per LAMP-A* run, hence 30 s. The value used is recorded in config.json, every results
#: line and report.md.
DEFAULT_PLANNING_LIMIT = 30.0
DEFAULT_TIME_CAP = 600.0
#: A rendering job gets this many times its usual cap (frame capture and GIF encoding).
RENDER_CAP_FACTOR = 2.0
CONFIG_FILE = "config.json"
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


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def known_planners() -> tuple[str, ...]:
    """The registered planner names (``lamp.planners.registry``)."""
    return registry.names()


def _split(value: str) -> list[str]:
    out: list[str] = []
    for item in value.split(","):
        item = item.strip()
        if item and item not in out:
            out.append(item)
    return out


def _git(*args: str) -> str | None:
    import lamp

    repo = Path(lamp.__file__).resolve().parents[2]
    try:
        res = subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True,
                             timeout=10, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    return res.stdout.strip() if res.returncode == 0 else None


def machine_info() -> dict[str, Any]:
    """CPU, memory, OS and Python of this machine (for config.json)."""
    cpu = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        mem = round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1)
    except (ValueError, OSError, AttributeError):
        mem = None
    return {"hostname": platform.node(), "platform": platform.platform(), "cpu": cpu,
            "cpu_count": os.cpu_count(), "memory_gb": mem,
            "python": platform.python_version()}


def _package_versions() -> dict[str, str]:
    from importlib import metadata

    out = {}
    for name in ("lamp", "numpy", "scipy", "shapely", "numba", "mujoco", "torch", "ray"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return out


def planner_limits(planners: list[str], planning_limit: float) -> dict[str, float]:
    """The cumulative planning limit per object each planner runs under."""
    out = {}
    for p in planners:
        if planning_limit_applies(p):
            out[p] = planning_limit
            continue
        try:
            from lamp.planners.run import default_config

            out[p] = float(default_config(p).planning_time_limit)
        except Exception:  # planners unavailable: leave it out rather than guess
            continue
    return out


def _code_version(out: Path) -> tuple[str | None, bool | None]:
    """(commit, uncommitted changes) of the running code; changes inside ``out`` do not count."""
    status = _git("status", "--porcelain", "--untracked-files=no")
    top = _git("rev-parse", "--show-toplevel")
    dirty = None
    if status is not None:
        # changes inside the output folder (earlier results of this run) do not count
        changed = [Path(top or ".", line[3:].split(" -> ")[-1]).resolve()
                   for line in status.splitlines() if line.strip()]
        dirty = any(not p.is_relative_to(out.resolve()) for p in changed)
    return _git("rev-parse", "HEAD"), dirty


def current_runs(previous: dict[str, Any], commit: str | None, dirty: bool | None) -> set[int]:
    """Indices of the recorded invocations that ran the code running now (``--rerun``).

    Those made at ``commit`` without uncommitted changes; none when the running code is
    itself uncommitted or its commit is unknown (then everything asked for is re-run).
    """
    if commit is None or dirty is not False:
        return set()
    return {i for i, s in enumerate(previous.get("sessions") or [])
            if isinstance(s, dict) and s.get("git_commit") == commit
            and s.get("git_dirty") is False}


def _session(command: str, out: Path) -> dict[str, Any]:
    commit, dirty = _code_version(out)
    return {
        "command": command, "argv": shlex.join(sys.argv),
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "git_commit": commit, "git_dirty": dirty,
        "packages": _package_versions(), "machine": machine_info(),
    }


def write_config(out: Path, previous: dict[str, Any], *, suites: list[str], planners: list[str],
                 seeds: list[int], workers: int, backend: str, model: str, time_cap: float,
                 planning_limit: float, scenes: int | None, job_fn: str, command: str
                 ) -> dict[str, Any]:
    """Write ``out/config.json``: this invocation's settings plus every session's provenance.

    The top-level ``machine`` is this invocation's; each session records its own as well.
    """
    from lamp.io import write_json_atomic

    def union(key: str, new: list) -> list:
        old = list(previous.get(key) or [])
        return old + [x for x in new if x not in old]

    all_planners = union("planners", planners)
    config = {
        "format": "lamp-bench/1",
        "suites": union("suites", suites), "planners": all_planners,
        "seeds": union("seeds", seeds), "scenes_per_suite": scenes,
        "workers": workers, "backend": backend, "model": model,
        "time_cap_s": time_cap, "time_cap_note": "per job, times the number of objects of the "
        "scene; a job past its cap is killed and recorded as a failure ('timeout')",
        "planning_limit_s": planning_limit,
        "planning_limit_note": "cumulative planning limit per object for "
        f"{', '.join(registry.bench_limited())}; the paper uses 500 s for LAMP-A*",
        "planner_planning_limits_s": planner_limits(all_planners, planning_limit),
        "job_fn": job_fn, "machine": machine_info(),
        "sessions": [*(previous.get("sessions") or []), _session(command, out)],
    }
    write_json_atomic(out / CONFIG_FILE, config)
    return config


def canonical_command(suites: list[str], planners: list[str], *, seeds: int, workers: int,
                      out: Path, time_cap: float, planning_limit: float, model: str,
                      backend: str, scenes: int | None, render_iros: bool, job_fn: str,
                      record: bool = False, jobs_per_worker: int = 0) -> str:
    """The ``lamp bench`` command line that reproduces this run, every setting explicit."""
    args = ["lamp", "bench", "--suites", ",".join(suites), "--planners", ",".join(planners),
            "--num-seeds", str(seeds), "--workers", str(workers), "--out", str(out),
            "--time-cap", f"{time_cap:g}", "--planning-limit", f"{planning_limit:g}",
            "--model", model, "--backend", backend]
    if scenes is not None:
        args += ["--scenes", str(scenes)]
    if render_iros:
        args.append("--render-iros")
    if record:
        args.append("--record")
    if jobs_per_worker:
        args += ["--jobs-per-worker", str(jobs_per_worker)]
    if job_fn != DEFAULT_JOB_FN:
        args += ["--job-fn", job_fn]
    return shlex.join(args)


def _check_resume_config(previous: dict[str, Any], *, time_cap: float, planning_limit: float,
                         model: str, job_fn: str) -> None:
    for key, given in (("time_cap_s", time_cap), ("planning_limit_s", planning_limit),
                       ("model", model), ("job_fn", job_fn)):
        if key in previous and previous[key] != given:
            _fail(f"resuming a run recorded with {key}={previous[key]!r} but given {given!r}: "
                  "the results would mix settings; pass the recorded value or use a new --out")


def _render_jobs(jobs: list[Job], pending: list[Job], out: Path, time_cap: float
                 ) -> list[Job]:
    """Pending jobs with the IROS animation requested (``--render-iros``).

    The first LAMP-Lazy IROS job renders while it runs; if it already ran (resume) and the
    GIF is missing, a render-only job (not recorded) re-runs it with the same seed.
    """
    from dataclasses import replace

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
    suite: str = typer.Option(DEFAULT_SUITES, "--suites", help="Comma-separated suites "
                              "(random, maze, tilt, warehouse, iros, warehouse-xl) or "
                              "folders of scene files."),
    suite_alias: str = typer.Option(None, "--suite", hidden=True,
                                    help="Old spelling of --suites."),
    planners: str = typer.Option(",".join(registry.bench_defaults()), "--planners",
                                 help="Comma-separated: " + ", ".join(registry.names()) + "."),
    seeds: int = typer.Option(1, "--num-seeds", help="Number of seeds per scene: runs seeds "
                              "0..N-1."),
    seeds_alias: int = typer.Option(None, "--seeds", hidden=True,
                                    help="Old spelling of --num-seeds."),
    workers: int = typer.Option(os.cpu_count() or 1, "--workers", "-j",
                                help="Jobs run at the same time (one core each)."),
    out: Path = typer.Option(..., "--out", "-o", help="Output folder (results.jsonl, "
                             "config.json, report.md, figures)."),
    resume: bool = typer.Option(False, "--resume", help="Continue a run in --out: skip jobs "
                                "already recorded."),
    time_cap: float = typer.Option(DEFAULT_TIME_CAP, "--time-cap", help="Wall-clock cap per "
                                   "job in seconds, per object of the scene; a job past it is "
                                   "killed and recorded as a failure ('timeout')."),
    planning_limit: float = typer.Option(DEFAULT_PLANNING_LIMIT, "--planning-limit",
                                         help="Cumulative planning limit per object for "
                                              f"{', '.join(registry.bench_limited())}, "
                                              "seconds. The paper uses 500 s for LAMP-A*; "
                                              "the default keeps a full run near 2 h on 2 "
                                              "cores."),
    planning_limit_alias: float = typer.Option(None, "--time-limit", hidden=True,
                                               help="Alias of --planning-limit (as in lamp run)."),
    model: str = typer.Option("learned", "--model", "-m", help="Manipulation model: learned, "
                              "geometric, or a checkpoint file from `lamp model train`."),
    backend: str = typer.Option("local", "--backend", help="local (warm worker processes) or ray."),
    ray_address: str = typer.Option(None, "--ray-address", help="Ray cluster address (e.g. "
                                    "auto).", show_default="start a local Ray instance"),
    scenes: int = typer.Option(None, "--scenes", help="Only the first N scenes of each suite "
                               "(quick runs).", show_default="all"),
    record: bool = typer.Option(False, "--record", help="Also save each job's recording "
                                "(lamp-recording/1) in DIR/recordings/SUITE/SCENE-PLANNER-sSEED/; "
                                "view it with `lamp render`."),
    render_iros: bool = typer.Option(False, "--render-iros", help="Also render the LAMP-Lazy "
                                     "IROS run to DIR/iros.gif (needs --suites iros)."),
    retry_errors: bool = typer.Option(True, "--retry-errors/--keep-errors", help="On --resume, "
                                      "re-run jobs that errored or crashed."),
    rerun: str = typer.Option("", "--rerun", help="With --resume: comma-separated planners "
                              "whose recorded jobs are run again (e.g. after a change to "
                              "them), except those already redone by a run of the current "
                              "commit; the new lines supersede the old ones in the report."),
    report: bool = typer.Option(True, "--report/--no-report", help="Write DIR/report.md at "
                                "the end."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar."),
    dry_run: bool = typer.Option(False, "--dry-run", help="List the jobs and exit."),
    job_fn: str = typer.Option(DEFAULT_JOB_FN, "--job-fn", hidden=True,
                               help="module:function that runs one job (testing)."),
    jobs_per_worker: int = typer.Option(0, "--jobs-per-worker", min=0, show_default=True,
                                        help="Local backend: retire a worker process after "
                                             "this many jobs (0: never; 1: a fresh process "
                                             "per job)."),
    db: Path = typer.Option(None, "--db", help="Also write the results as an SQLite "
                            "database at this path (schema: docs/bench-db.md); rebuilt "
                            "from DIR/results.jsonl.", show_default="no database"),
) -> None:
    """Run planners over benchmark suites; write results.jsonl, config.json and report.md."""
    from lamp.cli_support import check_model_option, did_you_mean

    suite = suite_alias if suite_alias is not None else suite
    seeds = seeds_alias if seeds_alias is not None else seeds
    if planning_limit_alias is not None:
        planning_limit = planning_limit_alias
    known = known_planners()
    planner_list = _split(planners)
    for p in planner_list:
        if p not in known:
            _fail(f"--planners: unknown planner {p!r}; expected one of: {', '.join(known)}"
                  + did_you_mean(p, known))
    if not planner_list:
        _fail("--planners: no planner given")
    rerun_list = _split(rerun)
    for p in rerun_list:
        if p not in planner_list:
            _fail(f"--rerun: planner {p!r} is not in --planners ({', '.join(planner_list)})")
    if rerun_list and not resume:
        _fail("--rerun needs --resume (it re-runs jobs recorded in --out)")
    suite_list = _split(suite)
    if not suite_list:
        _fail("--suites: no suite given")
    from lamp.bench.jobs import builtin_suites

    for name in suite_list:
        if name not in builtin_suites() and not Path(name).is_dir():
            _fail(f"--suites: unknown suite {name!r}; expected one of: "
                  f"{', '.join(builtin_suites())}, or a folder of scene files"
                  + did_you_mean(name, builtin_suites()))
    model = check_model_option(model)
    if backend not in BACKENDS:
        _fail(f"--backend: unknown backend {backend!r}; expected one of: {', '.join(BACKENDS)}")
    for name, value in (("--num-seeds", seeds), ("--workers", workers)):
        if value < 1:
            _fail(f"{name} must be at least 1, got {value}")
    for name, fvalue in (("--time-cap", time_cap), ("--planning-limit", planning_limit)):
        if not fvalue > 0:
            _fail(f"{name} must be positive, got {fvalue}")
    if scenes is not None and scenes < 1:
        _fail(f"--scenes must be at least 1, got {scenes}")
    try:
        from lamp.bench.job_fn import job_fn_spec

        job_fn_spec(job_fn)
    except ValueError as exc:
        _fail(f"--job-fn: {exc}")
    if db is not None:
        from lamp.bench.db import check_db_path

        try:
            check_db_path(db)
        except ValueError as exc:
            _fail(f"--db: {exc}")
    if backend == "ray" and not dry_run:
        try:
            from lamp.bench.runner import import_ray

            import_ray()
        except RuntimeError as exc:
            _fail(f"--backend ray: {exc}")

    previous: dict[str, Any] = {}
    if not dry_run and out.exists():
        if not out.is_dir():
            _fail(f"--out: {out} exists and is not a folder")
        if any(out.iterdir()) and not resume:
            _fail(f"--out: {out} is not empty; pass --resume to continue the run recorded "
                  "there, or choose a new folder")
    if resume and (out / CONFIG_FILE).exists():
        try:
            previous = json.loads((out / CONFIG_FILE).read_text())
        except json.JSONDecodeError:
            previous = {}
        _check_resume_config(previous, time_cap=time_cap, planning_limit=planning_limit,
                             model=model, job_fn=job_fn)

    try:
        loaded = [load_suite(name) for name in suite_list]
        seed_list = list(range(seeds))
        jobs = enumerate_jobs(loaded, planner_list, seed_list, scenes_per_suite=scenes,
                              model=model, time_cap_s=time_cap, planning_limit_s=planning_limit)
    except ValueError as exc:
        _fail(f"--suites: {exc}")
    except Exception as exc:  # a scene that fails to load is bad input too
        _fail(f"--suites: {type(exc).__name__}: {exc}")
    if render_iros and not any(j.suite == "iros" for j in jobs):
        _fail("--render-iros needs the iros suite in --suites")
    records = read_records(out / RESULTS_FILE) if resume else []
    current = current_runs(previous, *_code_version(out)) if rerun_list else set()
    pending = pending_jobs(jobs, records, retry_errors=retry_errors, rerun=rerun_list,
                           current_runs=current)
    if render_iros:
        pending = _render_jobs(jobs, pending, out, time_cap)
    if record:
        from dataclasses import replace

        pending = [replace(j, recording_to=str(out / "recordings" / j.suite /
                                               f"{j.scene_name}-{j.planner}-s{j.seed}"))
                   if j.record else j for j in pending]

    per = Counter((j.suite, j.planner) for j in pending if j.record)
    typer.echo(f"{len(jobs)} jobs ({len({(j.suite, j.scene_name) for j in jobs})} scenes x "
               f"{len(planner_list)} planners x {seeds} seeds); {len(pending)} to run"
               + (f", {len(jobs) - sum(per.values())} already recorded" if resume else "")
               + (f"; re-running {', '.join(rerun_list)}" if rerun_list else ""))
    if dry_run:
        for (s, p), n in sorted(per.items()):
            typer.echo(f"  {s:12s} {p:14s} {n}")
        for j in pending:
            if j.render_to:
                typer.echo(f"  renders {j.render_to} ({j.label})")
            if j.recording_to:
                typer.echo(f"  records into {j.recording_to} ({j.label})")
        return

    if pending:  # a resume with nothing to do records no new run
        _run_pending(pending, jobs, out, previous, suite_list=suite_list,
                     planner_list=planner_list, seeds=seeds, workers=workers,
                     time_cap=time_cap, planning_limit=planning_limit, model=model,
                     backend=backend, ray_address=ray_address, scenes=scenes,
                     render_iros=render_iros, job_fn=job_fn, record=record,
                     jobs_per_worker=jobs_per_worker, progress=progress)
    has_results = (out / RESULTS_FILE).exists()
    if report and has_results:
        _write_report(out)
    if db is not None and has_results:
        from lamp.bench.db import write_db

        typer.echo(f"wrote {write_db(out, db)}")


def _run_pending(pending: list[Job], jobs: list[Job], out: Path, previous: dict[str, Any], *,
                 suite_list: list[str], planner_list: list[str], seeds: int, workers: int,
                 time_cap: float, planning_limit: float, model: str, backend: str,
                 ray_address: str | None, scenes: int | None, render_iros: bool, job_fn: str,
                 record: bool, jobs_per_worker: int, progress: bool) -> None:
    """Record this invocation in config.json and run ``pending``; exit 130/143 if stopped."""
    command = canonical_command(
        suite_list, planner_list, seeds=seeds, workers=workers, out=out, time_cap=time_cap,
        planning_limit=planning_limit, model=model, backend=backend, scenes=scenes,
        render_iros=render_iros, job_fn=job_fn, record=record,
        jobs_per_worker=jobs_per_worker)
    out.mkdir(parents=True, exist_ok=True)
    run_id = len(previous.get("sessions") or [])
    write_config(out, previous, command=command, suites=list(dict.fromkeys(j.suite for j in jobs)),
                 planners=planner_list,
                 seeds=list(range(seeds)), workers=workers, backend=backend, model=model,
                 time_cap=time_cap, planning_limit=planning_limit, scenes=scenes, job_fn=job_fn)
    from lamp.bench.pool import WorkerStartError
    from lamp.bench.runner import execute

    stopped, code = "", 0
    try:
        with on_sigterm():
            summary = execute(pending, out, job_fn=job_fn, backend=backend, workers=workers,
                              ray_address=ray_address, progress=progress, log_dir=out / "logs",
                              jobs_per_worker=jobs_per_worker or None, run_id=run_id)
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
    typer.echo(f"ran {done} jobs in {summary.wall_time_s:.0f} s: {summary.successes} solved; "
               + ", ".join(f"{k} {v}" for k, v in sorted(summary.statuses.items())))
    for path in summary.rendered:
        typer.echo(f"wrote {path}")


def _write_report(run_dir: Path) -> None:
    from lamp.bench.report import build_report, family_records, load_results, success_table

    path = build_report(run_dir)
    records = load_results(run_dir)
    table = success_table(records)
    if family_records(records):
        typer.echo("success rate (Table I):")
        for p, row in table.items():
            typer.echo(f"  {p:14s} " + "  ".join(f"{f} {r.percent()}" for f, r in row.items()))
    typer.echo(f"wrote {path}")


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
