"""Per-job overhead of ``lamp bench``'s local backend: warm workers against a process per job.

Run: ``python benchmarks/bench_bench.py [--jobs 8] [--workers 1]``. Runs the same jobs (the
real ``solve_job``, LAMP-Lazy on a one-object 2 m scene that solves in about 0.2 s) twice:
with ``jobs_per_worker=1`` (a fresh process per job, the former behaviour) and with warm
workers (``jobs_per_worker=None``). Prints, per mode, the whole run's wall time; the median
interval between consecutive results (with one worker: what one job costs, process
start-up included, the first job's excluded); the median of the jobs' own ``wall_time_s``
(inside ``solve``) and planning time; and the per-job overhead, interval minus solve.
Against a checkout without warm workers (no ``jobs_per_worker``) run it with ``--only fresh``.
"""

from __future__ import annotations

import argparse
import inspect
import time

import numpy as np

from lamp.bench.jobs import SuiteScene, enumerate_jobs
from lamp.bench.runner import run_local
from lamp.scene import scene_from_dict

SCENE = {"format": "lamp-scene/1", "name": "tiny", "workspace": [2.0, 2.0],
         "robots": {"starts": [[0.2, 0.2], [0.4, 0.2], [1.8, 1.8]]},
         "objects": [{"type": "circle", "radius": 0.1, "start": [0.8, 0.8, 0.0],
                      "goal": [1.2, 1.0, 0.0]}]}


def measure(n_jobs: int, workers: int, jobs_per_worker: int | None) -> dict[str, float]:
    scene = scene_from_dict(SCENE)
    jobs = enumerate_jobs([[SuiteScene("tiny", scene, "tiny.yaml")]], ["lazy"],
                          list(range(n_jobs)), time_cap_s=120.0)
    outcomes, done_at = [], []

    def on_done(outcome) -> None:
        outcomes.append(outcome)
        done_at.append(time.perf_counter())

    kwargs = {}
    if "jobs_per_worker" in inspect.signature(run_local).parameters:
        kwargs["jobs_per_worker"] = jobs_per_worker
    elif jobs_per_worker != 1:
        raise SystemExit("this version of run_local has no warm workers")
    t0 = time.perf_counter()
    run_local(jobs, "lamp.bench.runner:solve_job", workers, on_done, **kwargs)
    total = time.perf_counter() - t0
    bad = [o.status for o in outcomes if o.status != "ok"]
    if bad:
        raise SystemExit(f"jobs failed: {bad}")
    inside = np.array([o.result["wall_time_s"] for o in outcomes])
    gaps = np.diff(np.array(done_at))  # one worker: the cost of one job after the first
    planning = np.array([o.result["total_planning_time_s"] for o in outcomes])
    return {"total": total, "gap": float(np.median(gaps)), "solve": float(np.median(inside)),
            "planning": float(np.median(planning)),
            "overhead": float(np.median(gaps) - np.median(inside))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=8)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--only", choices=("fresh", "warm"), default=None)
    args = ap.parse_args()
    modes = [("fresh process per job", 1), ("warm workers", None)]
    if args.only:
        modes = [modes[0] if args.only == "fresh" else modes[1]]
    for label, jpw in modes:
        m = measure(args.jobs, args.workers, jpw)
        print(f"{label:22s}: {args.jobs} jobs on {args.workers} worker(s) in {m['total']:.1f} s; "
              f"median interval between results {m['gap']:.2f} s, median solve {m['solve']:.2f} s"
              f" (planning {m['planning']:.3f} s), per-job overhead {m['overhead']:.2f} s")


if __name__ == "__main__":
    main()
