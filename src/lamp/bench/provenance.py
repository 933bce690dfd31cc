"""What a benchmark run records about itself in ``config.json``: settings and provenance.

:func:`write_config` merges this invocation's settings into those of the run being resumed
and appends a session (the command, the time, the commit and whether it had uncommitted
changes outside the output folder, package versions, the machine);
:func:`canonical_command` is the ``lamp bench`` line that reproduces the run;
:func:`current_runs` says which recorded sessions ran the code running now (``--rerun``).
Git, ``/proc`` and package metadata are read best-effort: what cannot be read is ``None``.
"""

from __future__ import annotations

import datetime as _dt
import os
import platform
import shlex
import subprocess
import sys
from pathlib import Path
from typing import Any

from lamp.bench.jobs import planning_limit_applies
from lamp.bench.runner import DEFAULT_JOB_FN
from lamp.pipeline import registry

CONFIG_FILE = "config.json"


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
    from lamp.pipeline import registry

    return {p: planning_limit if planning_limit_applies(p)
            else float(registry.get(p).default_config().loop.planning_time_limit)
            for p in planners}


def code_version(out: Path) -> tuple[str | None, bool | None]:
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
    commit, dirty = code_version(out)
    return {
        "command": command, "argv": shlex.join(sys.argv),
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "git_commit": commit, "git_dirty": dirty,
        "packages": _package_versions(), "machine": machine_info(),
    }


def write_config(out: Path, previous: dict[str, Any], *, suites: list[str], planners: list[str],
                 seeds: list[int], workers: int, backend: str, model: str, time_cap: float,
                 planning_limit: float, scenes: int | None, job_fn: str, command: str,
                 params: list[str] | None = None, disturb: str = "none",
                 schedule: str | None = None) -> dict[str, Any]:
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
        "params": list(params or []),
        "disturb": disturb,
        "schedule": schedule,
        "schedule_note": "the object schedule of every job (sequential or concurrent); null: "
        "each scene's own",
        "params_note": "planner parameters set with --param (PLANNER.NAME=VALUE); the rest "
        "are the planners' defaults, listed per run in results.jsonl's params",
        "job_fn": job_fn, "machine": machine_info(),
        "sessions": [*(previous.get("sessions") or []), _session(command, out)],
    }
    write_json_atomic(out / CONFIG_FILE, config)
    return config


def canonical_command(suites: list[str], planners: list[str], *, seeds: int, workers: int,
                      out: Path, time_cap: float, planning_limit: float, model: str,
                      backend: str, scenes: int | None, render_iros: bool, job_fn: str,
                      record: bool = False, jobs_per_worker: int = 0,
                      params: list[str] | None = None, disturb: str = "none",
                      schedule: str | None = None) -> str:
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
    for text in params or ():
        args += ["--param", text]
    if disturb != "none":
        args += ["--disturb", disturb]
    if schedule is not None:
        args += ["--schedule", schedule]
    if job_fn != DEFAULT_JOB_FN:
        args += ["--job-fn", job_fn]
    return shlex.join(args)
