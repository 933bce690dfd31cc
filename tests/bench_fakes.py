"""Stand-in job functions: exercise the benchmark machinery without running the planners.

``lamp bench --job-fn bench_fakes:synthetic_job ...`` produces plausible, deterministic
result.json objects in milliseconds (a dry run of the whole pipeline, report included); the
others model the ways a real job ends badly.

Job processes import a job function by its ``"module:function"`` name, so this module must
be importable in every one of them: a local pool's spawned workers inherit ``sys.path``,
but a ``lamp bench`` subprocess and Ray's workers do not. ``conftest.py`` therefore puts
this folder on ``PYTHONPATH`` for the whole test session; outside the tests, run
``PYTHONPATH=tests lamp bench --job-fn bench_fakes:synthetic_job ...``.
"""

from __future__ import annotations

import os
import time
import zlib
from typing import Any

import numpy as np

from lamp.bench.jobs import Job

#: Success probability per planner in :func:`synthetic_job` (roughly the paper's ordering).
SYNTHETIC_SUCCESS = {"lazy": 0.95, "astar": 0.3, "astar-replan": 0.4, "gco-ori": 0.05,
                     "gco-var": 0.4}


def _rng(job: Job) -> np.random.Generator:
    return np.random.default_rng(zlib.crc32(f"{job.suite}|{job.label}".encode()))


def synthetic_job(job: Job) -> dict[str, Any]:
    """A deterministic, made-up result.json for ``job`` (same job, same result)."""
    rng = _rng(job)
    p = SYNTHETIC_SUCCESS.get(job.planner, 0.5)
    objects, times = [], []
    makespan = 0
    for obj in job.scene.objects:
        ok = bool(rng.random() < p)
        n_seg = int(rng.integers(3, 30))
        seg_times = rng.lognormal(mean=1.0 if job.planner == "lazy" else 2.0, sigma=0.8,
                                  size=n_seg)
        times.extend(float(t) for t in seg_times)
        makespan += int(rng.integers(200, 2000)) * n_seg // 10
        goal = [float(v) for v in obj.goal]
        err = 0.03 if ok else 0.5
        objects.append({
            "success": ok, "final_pose": [goal[0] + err, goal[1], goal[2]], "goal": goal,
            "position_error": err, "orientation_error": 0.01, "left_workspace": False,
            "segments": n_seg, "full_horizon_plan": bool(ok or rng.random() < 0.3),
            "failure_reason": "" if ok else "no plan found", "replans": int(rng.integers(0, 4)),
            "planning_time_s": float(seg_times.sum()),
        })
    return {
        "scene": job.scene_name, "planner": job.planner, "seed": job.seed,
        "success": all(o["success"] for o in objects), "objects": objects,
        "segments": len(times), "planning_time_s": times,
        "total_planning_time_s": float(sum(times)),
        "median_planning_time_s": float(np.median(times)) if times else None,
        "makespan": makespan, "replans": sum(o["replans"] for o in objects),
        "wall_time_s": float(sum(times)) * 1.2, "stats": {"fake": True},
    }


def render_job(job: Job) -> dict[str, Any]:
    """:func:`synthetic_job`, plus a placeholder file at ``job.render_to`` when asked."""
    if job.render_to:
        with open(job.render_to, "wb") as f:
            f.write(b"GIF89a")
    return synthetic_job(job)


def slow_job(job: Job) -> dict[str, Any]:
    """Never finishes within a test's cap (sleeps a minute)."""
    time.sleep(60.0)
    return synthetic_job(job)


def slow_for_lazy_job(job: Job) -> dict[str, Any]:
    """:func:`slow_job` for LAMP-Lazy, :func:`synthetic_job` for the other planners."""
    return slow_job(job) if job.planner == "lazy" else synthetic_job(job)


def error_job(job: Job) -> dict[str, Any]:
    """Raises, as a broken planner would."""
    raise RuntimeError(f"planner exploded on {job.label}")


def crash_job(job: Job) -> dict[str, Any]:
    """Kills its own process without a result, as a segfault or the OOM killer would."""
    os._exit(3)


def mixed_job(job: Job) -> dict[str, Any]:
    """One way to end per planner: ``lazy`` never finishes, ``astar`` raises,
    ``astar-replan`` crashes, every other planner returns :func:`pid_job`."""
    if job.planner == "lazy":
        return slow_job(job)
    if job.planner == "astar":
        return error_job(job)
    if job.planner == "astar-replan":
        return crash_job(job)
    return pid_job(job)


def pid_job(job: Job) -> dict[str, Any]:
    """:func:`synthetic_job` with the id of the process that ran it in ``stats["pid"]``."""
    result = synthetic_job(job)
    result["stats"] = {**result["stats"], "pid": os.getpid()}
    return result


def announce_and_sleep_job(job: Job) -> dict[str, Any]:
    """Prints ``pid <id>`` (to the job's log) and then never finishes within a test's cap."""
    print(f"pid {os.getpid()}", flush=True)
    return slow_job(job)
