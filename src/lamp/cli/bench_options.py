"""The options of ``lamp bench``: their ``typer`` declarations, one constant each.

They live here so that :func:`lamp.cli.bench.bench_command` reads as what it does. What
the values may be is checked by :class:`lamp.bench.request.BenchRequest`, which the command
builds from them (bad input: exit status 2 and an ``error: --OPTION: ...`` line on stderr).
"""

from __future__ import annotations

import os

import typer

from lamp.bench.request import DEFAULT_PLANNING_LIMIT, DEFAULT_SUITES, DEFAULT_TIME_CAP
from lamp.bench.runner import DEFAULT_JOB_FN
from lamp.pipeline import registry

SUITES = typer.Option(DEFAULT_SUITES, "--suites", help="Comma-separated suites "
                      "(random, maze, tilt, warehouse, iros, warehouse-xl) or "
                      "folders of scene files.")
SUITE_ALIAS = typer.Option(None, "--suite", hidden=True, help="Old spelling of --suites.")
PLANNERS = typer.Option(",".join(registry.bench_defaults()), "--planners", "-p",
                        help="Comma-separated: " + ", ".join(registry.names()) + ".")
SEEDS = typer.Option(1, "--num-seeds", help="Number of seeds per scene: runs seeds 0..N-1.")
SEEDS_ALIAS = typer.Option(None, "--seeds", hidden=True, help="Old spelling of --num-seeds.")
WORKERS = typer.Option(os.cpu_count() or 1, "--workers", "-j",
                       help="Jobs run at the same time (one core each).")
OUT = typer.Option(..., "--out", "-o", help="Output folder (results.jsonl, "
                   "config.json, report.md, figures).")
RESUME = typer.Option(False, "--resume", help="Continue a run in --out: skip jobs "
                      "already recorded.")
TIME_CAP = typer.Option(DEFAULT_TIME_CAP, "--time-cap", help="Wall-clock cap per "
                        "job in seconds, per object of the scene; a job past it is "
                        "killed and recorded as a failure ('timeout').")
PLANNING_LIMIT = typer.Option(DEFAULT_PLANNING_LIMIT, "--planning-limit",
                              help="Cumulative planning limit per object for "
                                   f"{', '.join(registry.bench_limited())}, "
                                   "seconds. The paper uses 500 s for LAMP-A*; "
                                   "the default keeps a full run near 2 h on 2 "
                                   "cores.")
PLANNING_LIMIT_ALIAS = typer.Option(None, "--time-limit", hidden=True,
                                    help="Alias of --planning-limit (as in lamp run).")
MODEL = typer.Option("learned", "--model", "-m", help="Manipulation model: learned, "
                     "geometric, or a checkpoint file from `lamp model train`.")
BACKEND = typer.Option("local", "--backend", help="local (warm worker processes) or ray.")
RAY_ADDRESS = typer.Option(None, "--ray-address", help="Ray cluster address (e.g. "
                           "auto).", show_default="start a local Ray instance")
SCENES = typer.Option(None, "--scenes", help="Only the first N scenes of each suite "
                      "(quick runs).", show_default="all")
RECORD = typer.Option(False, "--record", help="Also save each job's recording "
                      "(lamp-recording/1) in DIR/recordings/SUITE/SCENE-PLANNER-sSEED/; "
                      "view it with `lamp render`.")
RENDER_IROS = typer.Option(False, "--render-iros", help="Also render the LAMP-Lazy "
                           "IROS run to DIR/iros.gif (needs --suites iros).")
RETRY_ERRORS = typer.Option(True, "--retry-errors/--keep-errors", help="On --resume, "
                            "re-run jobs that errored or crashed.")
RERUN = typer.Option("", "--rerun", help="With --resume: comma-separated planners "
                     "whose recorded jobs are run again (e.g. after a change to "
                     "them), except those already redone by a run of the current "
                     "commit; the new lines supersede the old ones in the report.")
REPORT = typer.Option(True, "--report/--no-report", help="Write DIR/report.md at the end.")
PROGRESS = typer.Option(True, "--progress/--no-progress", help="Progress bar.")
QUIET = typer.Option(False, "--quiet", "-q", help="Print nothing but errors: no progress "
                     "bar, no line per job (results.jsonl, config.json and report.md are "
                     "still written; --dry-run still lists the jobs).")
DRY_RUN = typer.Option(False, "--dry-run", help="List the jobs and exit.")
JOB_FN = typer.Option(DEFAULT_JOB_FN, "--job-fn", hidden=True,
                      help="module:function that runs one job (testing).")
JOBS_PER_WORKER = typer.Option(0, "--jobs-per-worker", min=0, show_default=True,
                               help="Local backend: retire a worker process after "
                                    "this many jobs (0: never; 1: a fresh process "
                                    "per job).")
PARAM = typer.Option(None, "--param", show_default=False,
                     help="Set a planner parameter for this run, PLANNER.NAME=VALUE "
                          "(repeatable; `lamp run --planner P --help-params` lists them), "
                          "e.g. lazy.max_plan_iterations=400.")
DISTURB = typer.Option("none", "--disturb", help="Disturbance preset of every job (a "
                       "robustness sweep runs one folder per preset): none, noise-low "
                       "(5 mm sensing, 5% actuation noise), noise-high (1 cm, 10%), "
                       "push-knocks (0.5 N s per segment), one-robot-fails.")
SCHEDULE = typer.Option(None, "--schedule", help="Object schedule of every job: "
                        "sequential (one object after another by the whole team, the "
                        "paper's) or concurrent (several at once by sub-teams).",
                        show_default="each scene's own")
DB = typer.Option(None, "--db", help="Also write the results as an SQLite "
                  "database at this path (schema: docs/bench-db.md); rebuilt "
                  "from DIR/results.jsonl.", show_default="no database")
