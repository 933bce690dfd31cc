"""The options of ``lamp bench`` and their checks, before anything is run or written.

The ``typer`` declarations live here so that :func:`lamp.cli.bench.bench_command` reads as
what it does. :func:`check_options` accepts the command's values or exits with status 2 and
an ``error: --OPTION: ...`` line on stderr (:func:`fail`); it never touches the output folder.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import typer

from lamp.bench.runner import BACKENDS, DEFAULT_JOB_FN
from lamp.cli.support import fail_input
from lamp.pipeline import registry

DEFAULT_SUITES = "random,maze,tilt,warehouse"
#: Default cumulative planning limit per object for LAMP-A* (the paper: 500 s). The paper's
#: LAMP-A* runs out of it in most cluttered scenes, so 100 scenes x 2 LAMP-A* variants at
#: 500 s would alone take ~28 h of CPU. A full run has about 2 h x 2 cores = 14,400 CPU-s;
#: leaving ~7,000 for LAMP-Lazy, the GCo baselines, IROS and per-job start-up gives ~35 s
#: per LAMP-A* run, hence 30 s. The value used is recorded in config.json, every results
#: line and report.md.
DEFAULT_PLANNING_LIMIT = 30.0
DEFAULT_TIME_CAP = 600.0


#: Bad input: an ``InputError``, reported by the command group (exit 2).
fail = fail_input


def known_planners() -> tuple[str, ...]:
    """The registered planner names (``lamp.pipeline.registry``)."""
    return registry.names()


def split_list(value: str) -> list[str]:
    """The items of a comma-separated option, stripped, empty ones and repeats dropped."""
    out: list[str] = []
    for item in value.split(","):
        item = item.strip()
        if item and item not in out:
            out.append(item)
    return out


# ------------------------------------------------------------------ the option declarations
SUITES = typer.Option(DEFAULT_SUITES, "--suites", help="Comma-separated suites "
                      "(random, maze, tilt, warehouse, iros, warehouse-xl) or "
                      "folders of scene files.")
SUITE_ALIAS = typer.Option(None, "--suite", hidden=True, help="Old spelling of --suites.")
PLANNERS = typer.Option(",".join(registry.bench_defaults()), "--planners",
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


# ------------------------------------------------------------------------------ the checks
def check_planners(planners: str, rerun: str, resume: bool) -> tuple[list[str], list[str]]:
    """``--planners`` and ``--rerun`` as lists, every name registered and rerun a subset."""
    from lamp.cli.support import did_you_mean

    known = known_planners()
    planner_list = split_list(planners)
    for p in planner_list:
        if p not in known:
            fail(f"--planners: unknown planner {p!r}; expected one of: {', '.join(known)}"
                 + did_you_mean(p, known))
    if not planner_list:
        fail("--planners: no planner given")
    rerun_list = split_list(rerun)
    for p in rerun_list:
        if p not in planner_list:
            fail(f"--rerun: planner {p!r} is not in --planners ({', '.join(planner_list)})")
    if rerun_list and not resume:
        fail("--rerun needs --resume (it re-runs jobs recorded in --out)")
    return planner_list, rerun_list


def check_suites(suite: str) -> list[str]:
    """``--suites`` as a list of built-in suite names or existing folders."""
    from lamp.bench.jobs import builtin_suites
    from lamp.cli.support import did_you_mean

    suite_list = split_list(suite)
    if not suite_list:
        fail("--suites: no suite given")
    for name in suite_list:
        if name not in builtin_suites() and not Path(name).is_dir():
            fail(f"--suites: unknown suite {name!r}; expected one of: "
                 f"{', '.join(builtin_suites())}, or a folder of scene files"
                 + did_you_mean(name, builtin_suites()))
    return suite_list


def check_numbers(*, seeds: int, workers: int, time_cap: float, planning_limit: float,
                  scenes: int | None) -> None:
    """Counts at least 1, durations positive."""
    for name, value in (("--num-seeds", seeds), ("--workers", workers)):
        if value < 1:
            fail(f"{name} must be at least 1, got {value}")
    for name, fvalue in (("--time-cap", time_cap), ("--planning-limit", planning_limit)):
        if not fvalue > 0:
            fail(f"{name} must be positive, got {fvalue}")
    if scenes is not None and scenes < 1:
        fail(f"--scenes must be at least 1, got {scenes}")


def check_machinery(*, backend: str, job_fn: str, db: Path | None, dry_run: bool) -> None:
    """The job function importable by name, the ``--db`` path usable, Ray importable when
    the (known) backend is ``ray`` and jobs will run."""
    try:
        from lamp.bench.job_fn import job_fn_spec

        job_fn_spec(job_fn)
    except ValueError as exc:
        fail(f"--job-fn: {exc}")
    if db is not None:
        from lamp.bench.db import check_db_path

        try:
            check_db_path(db)
        except ValueError as exc:
            fail(f"--db: {exc}")
    if backend == "ray" and not dry_run:
        try:
            from lamp.bench.runner import import_ray

            import_ray()
        except RuntimeError as exc:
            fail(f"--backend ray: {exc}")


def check_options(*, planners: str, rerun: str, resume: bool, suite: str, model: str,
                  backend: str, seeds: int, workers: int, time_cap: float,
                  planning_limit: float, scenes: int | None, job_fn: str, db: Path | None,
                  dry_run: bool) -> tuple[list[str], list[str], list[str], str]:
    """``(planners, rerun, suites, model)`` checked, in the order ``lamp bench`` reports them."""
    from lamp.cli.support import check_model_option

    planner_list, rerun_list = check_planners(planners, rerun, resume)
    suite_list = check_suites(suite)
    model = check_model_option(model)
    if backend not in BACKENDS:
        fail(f"--backend: unknown backend {backend!r}; expected one of: {', '.join(BACKENDS)}")
    check_numbers(seeds=seeds, workers=workers, time_cap=time_cap,
                  planning_limit=planning_limit, scenes=scenes)
    check_machinery(backend=backend, job_fn=job_fn, db=db, dry_run=dry_run)
    return planner_list, rerun_list, suite_list, model


def check_params(params: list[str] | None, planners: list[str]
                 ) -> tuple[dict[str, tuple[tuple[str, str], ...]], list[str]]:
    """``--param`` checked against the run's planners and their declared parameters:
    (planner -> its (name, value) overrides, the assignments as canonical texts)."""
    from lamp.contract.params import apply_overrides, parse_assignments

    by_planner: dict[str, dict[str, str]] = {}
    for planner, name, value in parse_assignments(params or ()):
        if planner not in planners:
            fail(f"--param {planner}.{name}={value}: planner {planner!r} is not among "
                 f"--planners ({', '.join(planners)})")
        spec = registry.get(planner)
        apply_overrides(spec.default_config(), spec.params, {name: value}, planner)
        by_planner.setdefault(planner, {})[name] = value
    texts = [f"{p}.{n}={v}" for p in sorted(by_planner) for n, v in sorted(by_planner[p].items())]
    return {p: tuple(sorted(kv.items())) for p, kv in by_planner.items()}, texts


def check_schedule(schedule: str | None) -> str | None:
    """``--schedule``: None or one of the scene format's schedules."""
    from lamp.scene.model import SCHEDULES

    if schedule is not None and schedule not in SCHEDULES:
        fail(f"--schedule: unknown schedule {schedule!r}; expected one of: "
             f"{', '.join(SCHEDULES)}")
    return schedule


def check_disturb(disturb: str, planners: list[str]) -> str:
    """``--disturb``: a known preset, and only for closed-loop planners when not none."""
    from lamp.bench.disturb import DISTURB_PRESETS

    if disturb not in DISTURB_PRESETS:
        fail(f"--disturb: unknown preset {disturb!r}; expected one of: "
             f"{', '.join(DISTURB_PRESETS)}")
    open_loop = [p for p in planners if not registry.get(p).closed_loop]
    if disturb != "none" and open_loop:
        fail(f"--disturb {disturb}: planners {', '.join(open_loop)} run no closed loop; "
             "disturbances are for the closed-loop planners")
    return disturb


def check_resume_config(previous: dict[str, Any], *, time_cap: float, planning_limit: float,
                        model: str, job_fn: str, params: list[str] | None = None,
                        disturb: str = "none", schedule: str | None = None) -> None:
    """A resumed run keeps its recorded cap, planning limit, model, job function and
    parameters."""
    for key, given in (("time_cap_s", time_cap), ("planning_limit_s", planning_limit),
                       ("model", model), ("job_fn", job_fn), ("params", params or []),
                       ("disturb", disturb), ("schedule", schedule)):
        if key in previous and previous[key] != given:
            fail(f"resuming a run recorded with {key}={previous[key]!r} but given {given!r}: "
                 "the results would mix settings; pass the recorded value or use a new --out")
