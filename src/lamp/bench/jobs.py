"""Benchmark jobs: what to run, where the results go, and what a resumed run may skip.

A *job* is one (suite, scene, planner, seed) run. Its result is one line of
``DIR/results.jsonl``: the scene's ``result.json`` object (interfaces spec) plus the keys
``suite``, ``scene_file``, ``status`` (``ok`` | ``timeout`` | ``error`` | ``crashed``) and the
caps it ran under. The file is append-only; every line is written with one ``write`` under an
exclusive ``flock`` and ``fsync``-ed, so concurrent writers never interleave and a crash can
leave at most one unterminated last line, which :func:`read_records` skips (and
:meth:`ResultsFile.append` terminates before writing after it).

When a key occurs more than once (an errored job that was retried on resume), the last
line wins: see :func:`latest_by_key`.
"""

from __future__ import annotations

import fcntl
import json
import logging
import os
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from lamp.planners.config import PAPER_MAX_SEGMENTS
from lamp.scene.model import Scene

log = logging.getLogger(__name__)

#: Name of the results file inside a benchmark folder.
RESULTS_FILE = "results.jsonl"

def planning_limit_applies(planner: str) -> bool:
    """Whether ``--planning-limit`` sets ``planner``'s limit (``PlannerSpec.bench_limited``:
    the paper gives LAMP-A* a 500 s limit; the others stop after 100 execution iterations)."""
    from lamp.pipeline import registry

    return planner in registry.bench_limited()

#: Job outcomes. ``error`` and ``crashed`` are re-run by a resumed benchmark by default.
STATUSES = ("ok", "timeout", "error", "crashed")
RETRYABLE = ("error", "crashed")

#: (suite, scene name, planner, seed): identifies a job and its result line.
JobKey = tuple[str, str, str, int]


@dataclass(frozen=True)
class Job:
    """One benchmark run: plan and execute ``scene`` with ``planner`` under ``seed``.

    ``time_cap_s`` is the wall-clock cap of the whole job (the process is killed after it);
    ``planning_limit_s`` is the cumulative planning limit handed to the planner when it is
    one that ``planning_limit_applies`` to (``None``: the planner's default). ``render_to`` asks the
    job function to also write an animation there; ``record`` is False for a render-only
    re-run whose result is already in the results file; ``recording_to`` (``--record``) is
    a folder where the job function saves the run's recording (``lamp-recording/1``).
    """

    suite: str
    scene_name: str
    scene_file: str
    scene: Scene = field(compare=False, repr=False)
    planner: str
    seed: int
    model: str = "learned"
    time_cap_s: float = 600.0
    planning_limit_s: float | None = None
    #: Executed-segment limit per object: the paper's 100 on the built-in suites, None
    #: (scaled with the task, ``lamp.planners.config.segment_limit``) on scene folders.
    max_segments: int | None = None
    render_to: str | None = None
    record: bool = True
    recording_to: str | None = None
    #: Overrides of the planner's declared parameters (``--param PLANNER.NAME=VALUE``):
    #: (name, value text) pairs for this job's planner.
    params: tuple[tuple[str, str], ...] = ()
    #: Disturbance preset of the run (``lamp bench --disturb``; ``lamp.bench.disturb``).
    disturb: str = "none"

    @property
    def key(self) -> JobKey:
        return (self.suite, self.scene_name, self.planner, int(self.seed))

    @property
    def label(self) -> str:
        return f"{self.scene_name} {self.planner} s{self.seed}"

    @property
    def time_limit(self) -> float | None:
        """The planning limit of the run (``RunRequest.build(planning_limit=...)``)."""
        return self.planning_limit_s if planning_limit_applies(self.planner) else None


@dataclass(frozen=True)
class SuiteScene:
    """A scene of a suite with the file it comes from (or would be exported to)."""

    suite: str
    scene: Scene
    scene_file: str
    #: A scene of one of the paper's built-in suites (``SuiteInfo.paper``): the paper's
    #: settings hold (``PAPER_MAX_SEGMENTS``). False for scene folders and for built-in
    #: suites beyond the paper (``warehouse-xl``), whose limit scales with the task.
    builtin: bool = False


def enumerate_jobs(
    suites: Sequence[Sequence[SuiteScene]],
    planners: Sequence[str],
    seeds: Sequence[int],
    *,
    scenes_per_suite: int | None = None,
    model: str = "learned",
    time_cap_s: float = 600.0,
    planning_limit_s: float | None = None,
    scale_cap_by_objects: bool = True,
    params: Mapping[str, Sequence[tuple[str, str]]] | None = None,
    disturb: str = "none",
    schedule: str | None = None,
) -> list[Job]:
    """All jobs in a deterministic order: suite, scene, seed, then planner.

    ``suites`` holds each suite's scenes in suite order (see :func:`load_suite`);
    ``scenes_per_suite`` keeps the first N of each. With ``scale_cap_by_objects`` a K-object scene gets a cap of
    ``K * time_cap_s`` (a single-object scene exactly ``time_cap_s``), so the 9-object IROS
    job is not cut off by a per-object budget. ``params`` maps a planner name to the
    overrides of its parameters (``Job.params``); ``schedule`` replaces every scene's
    (None: each keeps its own).
    """
    if scenes_per_suite is not None and scenes_per_suite < 1:
        raise ValueError(f"scenes_per_suite must be >= 1 or None, got {scenes_per_suite!r}")
    if time_cap_s <= 0:
        raise ValueError(f"time_cap_s must be positive, got {time_cap_s!r}")
    jobs: list[Job] = []
    for scenes in suites:
        chosen = list(scenes)[:scenes_per_suite] if scenes_per_suite else list(scenes)
        for entry in chosen:
            if schedule is not None:
                entry = replace(entry, scene=replace(entry.scene, schedule=schedule))
            n_obj = max(1, len(entry.scene.objects))
            cap = time_cap_s * (n_obj if scale_cap_by_objects else 1)
            for seed in seeds:
                for planner in planners:
                    jobs.append(Job(suite=entry.suite, scene_name=entry.scene.name,
                                    scene_file=entry.scene_file, scene=entry.scene,
                                    planner=planner, seed=int(seed), model=model,
                                    time_cap_s=float(cap), planning_limit_s=planning_limit_s,
                                    max_segments=PAPER_MAX_SEGMENTS if entry.builtin else None,
                                    params=tuple((params or {}).get(planner, ())),
                                    disturb=disturb))
    keys = [j.key for j in jobs]
    if len(set(keys)) != len(keys):
        dup = next(k for k in keys if keys.count(k) > 1)
        raise ValueError(f"duplicate job {dup}: scene names must be unique within a suite")
    return jobs


def record_key(record: dict[str, Any]) -> JobKey:
    """The job key of a results line."""
    return (str(record["suite"]), str(record["scene"]), str(record["planner"]),
            int(record["seed"]))


def pending_jobs(jobs: Iterable[Job], records: Iterable[dict[str, Any]], *,
                 retry_errors: bool = True, rerun: Collection[str] = (),
                 current_runs: Collection[int] = ()) -> list[Job]:
    """Jobs without a recorded result (``--resume``); errored/crashed ones too if asked.

    A job of a planner in ``rerun`` (``--rerun``) is pending as well unless its latest
    record carries a ``run_id`` in ``current_runs`` (the invocations made with the code
    that runs now), so an interrupted re-run, resumed, only runs what it has not redone.
    """
    latest = latest_by_key(records)
    out = []
    for job in jobs:
        rec = latest.get(job.key)
        if (rec is None or (retry_errors and rec.get("status") in RETRYABLE)
                or (job.planner in rerun and rec.get("run_id") not in current_runs)):
            out.append(job)
    return out


def latest_by_key(records: Iterable[dict[str, Any]]) -> dict[JobKey, dict[str, Any]]:
    """One record per job key, the last one in file order."""
    out: dict[JobKey, dict[str, Any]] = {}
    for rec in records:
        try:
            out[record_key(rec)] = rec
        except (KeyError, TypeError, ValueError):
            log.warning("skipping a results line without suite/scene/planner/seed")
    return out


def read_records(path: str | Path, *, on_skip: Callable[[int, str], None] | None = None
                 ) -> list[dict[str, Any]]:
    """Parse a results file, skipping malformed lines (e.g. a crash's unterminated last line).

    Returns the records in file order; ``on_skip(line_number, reason)`` is called per skipped
    line (default: a logged warning). A missing file reads as no records.
    """
    path = Path(path)
    if not path.exists():
        return []
    records: list[dict[str, Any]] = []
    with open(path, "rb") as f:
        data = f.read()
    lines = data.split(b"\n")
    for i, raw in enumerate(lines, start=1):
        if not raw.strip():
            continue
        reason = ""
        try:
            rec = json.loads(raw)
            if not isinstance(rec, dict):
                reason = "not a JSON object"
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            reason = f"malformed JSON ({exc.msg if hasattr(exc, 'msg') else exc})"
        if reason:
            (on_skip or _warn_skip)(i, reason)
            continue
        records.append(rec)
    return records


def _warn_skip(line: int, reason: str) -> None:
    log.warning("results file line %d skipped: %s", line, reason)


class ResultsFile:
    """Append-only JSON-lines file, safe under concurrent writers and crashes."""

    def __init__(self, path: str | Path):
        self.path = Path(path)

    def append(self, record: dict[str, Any]) -> None:
        """Append ``record`` as one line: one ``write`` under ``flock``, then ``fsync``.

        If the file does not end with a newline (a writer died mid-line), a newline is
        written first so the broken fragment stays a line of its own that readers skip.
        """
        line = (json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n").encode()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            try:
                size = os.fstat(fd).st_size
                if size > 0:
                    with open(self.path, "rb") as r:
                        r.seek(size - 1)
                        if r.read(1) != b"\n":
                            line = b"\n" + line
                _write_all(fd, line)
                os.fsync(fd)
            finally:
                fcntl.flock(fd, fcntl.LOCK_UN)
        finally:
            os.close(fd)

    def read(self) -> list[dict[str, Any]]:
        return read_records(self.path)


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def _sanitize(value: Any) -> Any:
    """JSON-safe copy: NaN/inf floats become None (``allow_nan=False`` rejects them)."""
    if isinstance(value, float):
        return value if value == value and abs(value) != float("inf") else None
    if isinstance(value, dict):
        return {str(k): _sanitize(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_sanitize(v) for v in value]
    return value


def make_record(job: Job, result: dict[str, Any], *, status: str, job_wall_time_s: float
                ) -> dict[str, Any]:
    """A results line: ``result`` (result.json) plus the job's suite, scene file and caps."""
    if status not in STATUSES:
        raise ValueError(f"status must be one of {STATUSES}, got {status!r}")
    rec = dict(_sanitize(result))
    rec.update({
        "scene": job.scene_name,
        "planner": job.planner,
        "seed": int(job.seed),
        "suite": job.suite,
        "scene_file": job.scene_file,
        "status": status,
        "model": job.model,
        "time_cap_s": job.time_cap_s,
        "planning_limit_s": job.time_limit,
        "max_segments": job.max_segments,
        "disturb": job.disturb,
        "schedule": job.scene.schedule,
        "job_wall_time_s": round(float(job_wall_time_s), 3),
    })
    rec.setdefault("failure_reason", _failure_reason(rec))
    return rec


def _failure_reason(rec: dict[str, Any]) -> str:
    if rec.get("success"):
        return ""
    reasons = [o.get("failure_reason", "") for o in rec.get("objects", []) if not o.get("success")]
    return next((r for r in reasons if r), "failed")


def failure_result(job: Job, reason: str, *, planning_time_s: float, wall_time_s: float
                   ) -> dict[str, Any]:
    """A result.json-shaped failure for a job that produced none (timeout, error, crash).

    Every object is marked failed with ``reason``; the job's planning time is
    ``planning_time_s`` (the cap, for a timeout) and it executed no segment.
    """
    objects = [{
        "success": False, "final_pose": None, "goal": [float(v) for v in o.goal],
        "position_error": None, "orientation_error": None, "left_workspace": False,
        "segments": 0, "full_horizon_plan": False, "failure_reason": reason, "replans": 0,
        "planning_time_s": None,
    } for o in job.scene.objects]
    return {
        "scene": job.scene_name, "planner": job.planner, "seed": int(job.seed),
        "success": False, "objects": objects, "segments": 0, "planning_time_s": [],
        "total_planning_time_s": float(planning_time_s), "median_planning_time_s": None,
        "makespan": 0, "replans": 0, "wall_time_s": round(float(wall_time_s), 3),
        "stats": {}, "failure_reason": reason,
    }


def builtin_suites() -> list[str]:
    """Names of the suites shipped with the package (empty while ``lamp.suites`` lacks them)."""
    try:
        from lamp.suites import registry
    except ImportError:
        return []
    return list(registry.list_suites())


def load_suite(name: str) -> list[SuiteScene]:
    """The scenes of suite ``name``: a built-in suite, or a folder of scene files.

    A folder's ``*.yaml``, ``*.yml`` and ``*.json`` files are loaded in name order with the
    validating loader; its suite (family) name is the folder name. Raises ``ValueError``
    naming the suite and the valid choices when it is neither.
    """
    known = builtin_suites()
    if name in known:
        from lamp.suites import registry

        scenes = registry.suite_scenes(name)
        if not scenes:
            raise ValueError(f"built-in suite {name!r} has no scene files in this installation")
        # a portable name (suite/file), not the path inside this installation
        paper = registry.suite_info(name).paper
        return [SuiteScene(name, sc, f"{name}/{Path(sc.source).name}" if sc.source
                           else f"{name}/{sc.name}.yaml", builtin=paper) for sc in scenes]
    path = Path(name)
    if path.is_dir():
        from lamp.scene import load_scene

        files = sorted(p for p in path.iterdir()
                       if p.suffix.lower() in (".yaml", ".yml", ".json") and p.is_file())
        if not files:
            raise ValueError(f"suite folder {name!r} holds no scene files (*.yaml, *.json)")
        return [SuiteScene(path.name, load_scene(p), str(p)) for p in files]
    choices = ", ".join(known) if known else "(no built-in suites installed)"
    raise ValueError(f"unknown suite {name!r}; expected one of: {choices}, or a folder of "
                     f"scene files")
