"""One benchmark invocation, settled and checked: :class:`BenchRequest`.

``lamp bench`` (:mod:`lamp.cli.bench`) builds one from its options and hands it to each
step of the run (the check of the output folder, the job list, ``config.json``, the
runner), so that none of them takes the settings one by one. The fields are the command's
options, and a bad value is an :class:`~lamp.errors.InputError` naming the option
(``--planners: unknown planner 'lazzy'; ...``), raised when the request is built, before
anything is run or written; the output folder itself is checked by the command, which
knows whether the run resumes.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

from lamp.bench.runner import BACKENDS, DEFAULT_JOB_FN
from lamp.errors import InputError
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

#: A planner's parameter overrides, ``((name, value), ...)`` sorted by name.
Overrides = tuple[tuple[str, str], ...]


def _fail(message: str) -> NoReturn:
    raise InputError(message)


def _closest(value: str, choices: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest of ``choices``, or ``""``."""
    hint = difflib.get_close_matches(str(value), list(choices), n=1)
    return f"; did you mean {hint[0]!r}?" if hint else ""


def _unique(items: Iterable[str]) -> tuple[str, ...]:
    """``items`` stripped, empty ones and repeats dropped, in their order."""
    out: list[str] = []
    for item in items:
        item = str(item).strip()
        if item and item not in out:
            out.append(item)
    return tuple(out)


@dataclass(frozen=True)
class BenchRequest:
    """A ``lamp bench`` run: which jobs, how they run, what is written.

    Jobs: every scene of ``suites`` (built-in names or folders of scene files; the first
    ``scenes`` of each when given) x ``planners`` x seeds ``0..seeds-1``, with ``model``,
    the per-planner ``params`` (``PLANNER.NAME=VALUE``), the ``disturb`` preset and the
    ``schedule`` (None: each scene's own). Caps: ``time_cap`` seconds of wall clock per job
    and object, ``planning_limit`` seconds of planning per object for the planners that
    take one. Running: ``workers`` at a time on ``backend`` (``ray_address``: a Ray
    cluster), a local worker retired after ``jobs_per_worker`` jobs (0: never), each job
    run by ``job_fn``. Output in ``out``: ``resume`` continues a run recorded there,
    re-running errored jobs (``retry_errors``) and the recorded jobs of ``rerun``;
    ``record`` saves each job's recording, ``render_iros`` the IROS animation, ``report``
    writes report.md, ``db`` an SQLite copy; ``dry_run`` lists the jobs only. Console:
    ``progress`` shows a progress bar; ``quiet`` prints nothing but errors.

    The lists are stored as tuples, stripped, without empty items or repeats; ``model`` in
    its canonical form (``lamp.manip.models.check_model``); ``params`` as sorted canonical
    texts.
    """

    out: Path
    suites: tuple[str, ...] = tuple(DEFAULT_SUITES.split(","))
    planners: tuple[str, ...] = tuple(registry.bench_defaults())
    seeds: int = 1
    scenes: int | None = None
    model: str = "learned"
    time_cap: float = DEFAULT_TIME_CAP
    planning_limit: float = DEFAULT_PLANNING_LIMIT
    params: tuple[str, ...] = ()
    disturb: str = "none"
    schedule: str | None = None
    workers: int = 1
    backend: str = "local"
    ray_address: str | None = None
    jobs_per_worker: int = 0
    job_fn: str = DEFAULT_JOB_FN
    resume: bool = False
    retry_errors: bool = True
    rerun: tuple[str, ...] = ()
    record: bool = False
    render_iros: bool = False
    report: bool = True
    db: Path | None = None
    dry_run: bool = False
    progress: bool = True
    quiet: bool = False

    def __post_init__(self) -> None:
        """Normalise and check every field, in the order ``lamp bench`` reports them."""
        for name in ("suites", "planners", "rerun", "params"):
            object.__setattr__(self, name, _unique(getattr(self, name)))
        object.__setattr__(self, "out", Path(self.out))
        if self.db is not None:
            object.__setattr__(self, "db", Path(self.db))
        self._check_planners()
        self._check_suites()
        self._check_model()
        if self.backend not in BACKENDS:
            _fail(f"--backend: unknown backend {self.backend!r}; expected one of: "
                  f"{', '.join(BACKENDS)}")
        self._check_numbers()
        self._check_machinery()
        self._check_params()
        self._check_disturb()
        self._check_schedule()

    # ------------------------------------------------------------------------- derived
    @property
    def seed_list(self) -> list[int]:
        """The seeds each scene runs with: ``0..seeds-1``."""
        return list(range(self.seeds))

    @property
    def planner_params(self) -> dict[str, Overrides]:
        """``params`` by planner: planner -> its ``(name, value)`` overrides, sorted."""
        from lamp.contract.params import parse_assignments

        by_planner: dict[str, dict[str, str]] = {}
        for planner, name, value in parse_assignments(self.params):
            by_planner.setdefault(planner, {})[name] = value
        return {p: tuple(sorted(kv.items())) for p, kv in by_planner.items()}

    @property
    def show_progress(self) -> bool:
        """Whether to show the progress bar (``progress``, unless ``quiet``)."""
        return self.progress and not self.quiet

    def command_line(self) -> str:
        """The ``lamp bench`` command line that reproduces this run, every setting explicit
        (:func:`lamp.bench.provenance.canonical_command`)."""
        from lamp.bench.provenance import canonical_command

        return canonical_command(
            list(self.suites), list(self.planners), seeds=self.seeds, workers=self.workers,
            out=self.out, time_cap=self.time_cap, planning_limit=self.planning_limit,
            model=self.model, backend=self.backend, scenes=self.scenes,
            render_iros=self.render_iros, job_fn=self.job_fn, record=self.record,
            jobs_per_worker=self.jobs_per_worker, params=list(self.params),
            disturb=self.disturb, schedule=self.schedule)

    def check_resumable(self, previous: dict[str, Any]) -> None:
        """Raise ``InputError`` unless this request keeps the settings of the run it resumes
        (``previous``: that run's config.json): its cap, planning limit, model, job
        function, parameters, disturbances and schedule, so that results never mix them."""
        for key, given in (("time_cap_s", self.time_cap),
                           ("planning_limit_s", self.planning_limit), ("model", self.model),
                           ("job_fn", self.job_fn), ("params", list(self.params)),
                           ("disturb", self.disturb), ("schedule", self.schedule)):
            if key in previous and previous[key] != given:
                _fail(f"resuming a run recorded with {key}={previous[key]!r} but given "
                      f"{given!r}: the results would mix settings; pass the recorded value "
                      "or use a new --out")

    # -------------------------------------------------------------------------- checks
    def _check_planners(self) -> None:
        """Every planner registered, at least one; ``rerun`` among them, and only on a
        resume."""
        known = registry.names()
        for p in self.planners:
            if p not in known:
                _fail(f"--planners: unknown planner {p!r}; expected one of: {', '.join(known)}"
                      + _closest(p, known))
        if not self.planners:
            _fail("--planners: no planner given")
        for p in self.rerun:
            if p not in self.planners:
                _fail(f"--rerun: planner {p!r} is not in --planners "
                      f"({', '.join(self.planners)})")
        if self.rerun and not self.resume:
            _fail("--rerun needs --resume (it re-runs jobs recorded in --out)")

    def _check_suites(self) -> None:
        """At least one suite; each a built-in suite or an existing folder."""
        from lamp.bench.jobs import builtin_suites

        if not self.suites:
            _fail("--suites: no suite given")
        for name in self.suites:
            if name not in builtin_suites() and not Path(name).is_dir():
                _fail(f"--suites: unknown suite {name!r}; expected one of: "
                      f"{', '.join(builtin_suites())}, or a folder of scene files"
                      + _closest(name, builtin_suites()))

    def _check_model(self) -> None:
        from lamp.manip.models import ModelError, check_model

        try:
            object.__setattr__(self, "model", check_model(self.model))
        except ModelError as exc:
            _fail(f"--model: {exc}")

    def _check_numbers(self) -> None:
        """Counts at least 1 (``jobs_per_worker`` at least 0), durations positive."""
        for name, value in (("--num-seeds", self.seeds), ("--workers", self.workers)):
            if value < 1:
                _fail(f"{name} must be at least 1, got {value}")
        for name, fvalue in (("--time-cap", self.time_cap),
                             ("--planning-limit", self.planning_limit)):
            if not fvalue > 0:
                _fail(f"{name} must be positive, got {fvalue}")
        if self.scenes is not None and self.scenes < 1:
            _fail(f"--scenes must be at least 1, got {self.scenes}")
        if self.jobs_per_worker < 0:
            _fail(f"--jobs-per-worker must be at least 0, got {self.jobs_per_worker}")

    def _check_machinery(self) -> None:
        """The job function importable by name, the ``--db`` path usable, Ray importable
        when the backend is ``ray`` and jobs will run."""
        from lamp.bench.job_fn import job_fn_spec

        try:
            job_fn_spec(self.job_fn)
        except ValueError as exc:
            _fail(f"--job-fn: {exc}")
        if self.db is not None:
            from lamp.bench.db import check_db_path

            try:
                check_db_path(self.db)
            except ValueError as exc:
                _fail(f"--db: {exc}")
        if self.backend == "ray" and not self.dry_run:
            from lamp.bench.runner import import_ray

            try:
                import_ray()
            except RuntimeError as exc:
                _fail(f"--backend ray: {exc}")

    def _check_params(self) -> None:
        """Each ``--param`` names a planner of the run and one of its declared parameters,
        with a valid value; stored as sorted canonical texts."""
        from lamp.contract.params import parse_assignments
        from lamp.pipeline.request import configure

        by_planner: dict[str, dict[str, str]] = {}
        for planner, name, value in parse_assignments(self.params):
            if planner not in self.planners:
                _fail(f"--param {planner}.{name}={value}: planner {planner!r} is not among "
                      f"--planners ({', '.join(self.planners)})")
            spec = registry.get(planner)
            configure(spec, {name: value})  # its own and, closed-loop, the fleet's
            by_planner.setdefault(planner, {})[name] = value
        object.__setattr__(self, "params", tuple(
            f"{p}.{n}={v}" for p in sorted(by_planner) for n, v in sorted(by_planner[p].items())))

    def _check_disturb(self) -> None:
        """A known preset, and only for closed-loop planners when not ``none``."""
        from lamp.bench.disturb import DISTURB_PRESETS

        if self.disturb not in DISTURB_PRESETS:
            _fail(f"--disturb: unknown preset {self.disturb!r}; expected one of: "
                  f"{', '.join(DISTURB_PRESETS)}")
        open_loop = [p for p in self.planners if not registry.get(p).closed_loop]
        if self.disturb != "none" and open_loop:
            _fail(f"--disturb {self.disturb}: planners {', '.join(open_loop)} run no closed "
                  "loop; disturbances are for the closed-loop planners")

    def _check_schedule(self) -> None:
        from lamp.scene.model import SCHEDULES

        if self.schedule is not None and self.schedule not in SCHEDULES:
            _fail(f"--schedule: unknown schedule {self.schedule!r}; expected one of: "
                  f"{', '.join(SCHEDULES)}")
