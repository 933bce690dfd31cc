"""Benchmarks: run planners over suites (``lamp bench``) and report (``lamp report``).

- :mod:`lamp.bench.jobs`: the job list, the append-only ``results.jsonl`` and resume;
- :mod:`lamp.bench.runner`: jobs in isolated processes under a wall-clock cap each, locally
  (:mod:`lamp.bench.pool`, warm worker processes) or on Ray;
- :mod:`lamp.bench.report`: the paper's Tables I-II, figures and ``report.md``;
- :mod:`lamp.bench.db`: the results as an SQLite database (``--db``, docs/bench-db.md);
- :mod:`lamp.bench.request`: one invocation's settings, checked (:class:`BenchRequest`).

The commands themselves are :mod:`lamp.cli.bench`.

Matplotlib, Ray and the planners are imported only where they are used (the planners
inside the job processes).
"""

from lamp.bench.jobs import (
    Job,
    ResultsFile,
    SuiteScene,
    enumerate_jobs,
    latest_by_key,
    load_suite,
    pending_jobs,
    read_records,
)
from lamp.bench.report import build_report
from lamp.bench.runner import DEFAULT_JOB_FN, execute, run_local, run_ray, solve_job

__all__ = [
    "DEFAULT_JOB_FN",
    "Job",
    "ResultsFile",
    "SuiteScene",
    "build_report",
    "enumerate_jobs",
    "execute",
    "latest_by_key",
    "load_suite",
    "pending_jobs",
    "read_records",
    "run_local",
    "run_ray",
    "solve_job",
]

