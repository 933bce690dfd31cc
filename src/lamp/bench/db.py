"""The benchmark results as an SQLite database (``lamp bench --db``, ``lamp report --db``).

Built from ``DIR/results.jsonl`` and ``DIR/config.json`` alone, like the report, so it can
be rebuilt at any time; the schema (:data:`SCHEMA`) is documented in ``docs/bench-db.md``:
one row per invocation of ``lamp bench`` (``runs``), per job (``jobs``: the latest line
of each (suite, scene, planner, seed), the one the report counts), per object of a job
(``objects``) and per executed segment (``segments``), plus ``meta`` (schema version and
the run's settings). Guarantees (tests/test_bench_db.py): the database is written under a
temporary name and renamed, so a reader never sees half of one and an error leaves any
previous file untouched; its counts equal the report's (:func:`lamp.bench.report.success_table`
and friends); every ``run_id`` and ``job_id`` reference resolves.
"""

from __future__ import annotations

import contextlib
import json
import os
import sqlite3
import tempfile
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from lamp.bench.jobs import RESULTS_FILE, latest_by_key, read_records, record_key

#: Version of the table layout below, stored in ``meta`` as ``schema_version``.
SCHEMA_VERSION = 1

SCHEMA = """
CREATE TABLE meta (
    key   TEXT PRIMARY KEY,
    value TEXT               -- JSON
);
CREATE TABLE runs (
    run_id     INTEGER PRIMARY KEY,  -- index of the invocation in config.json "sessions"
    command    TEXT,                 -- the canonical lamp bench command line
    argv       TEXT,
    date       TEXT,                 -- ISO 8601, UTC
    git_commit TEXT,
    git_dirty  INTEGER,              -- 0 / 1, NULL when unknown
    packages   TEXT                  -- JSON object: package -> version
);
CREATE TABLE jobs (
    job_id                      INTEGER PRIMARY KEY,
    run_id                      INTEGER REFERENCES runs (run_id),
    suite                       TEXT NOT NULL,
    scene                       TEXT NOT NULL,
    scene_file                  TEXT,
    planner                     TEXT NOT NULL,
    seed                        INTEGER NOT NULL,
    model                       TEXT,
    status                      TEXT NOT NULL,     -- ok | timeout | error | crashed
    success                     INTEGER NOT NULL,  -- 0 / 1
    failure_reason              TEXT,
    n_objects                   INTEGER NOT NULL,
    full_horizon_plan           INTEGER NOT NULL,  -- 1: every object had one
    segments                    INTEGER,
    total_planning_time_s       REAL,
    median_planning_time_s      REAL,
    planning_time_per_segment_s REAL,              -- total / segments; NULL without segments
    makespan                    INTEGER,
    replans                     INTEGER,
    wall_time_s                 REAL,
    job_wall_time_s             REAL,
    time_cap_s                  REAL,
    planning_limit_s            REAL,
    attempts                    INTEGER NOT NULL,  -- lines for this job in results.jsonl
    result_json                 TEXT NOT NULL,     -- the whole results line
    UNIQUE (suite, scene, planner, seed)
);
CREATE TABLE objects (
    job_id            INTEGER NOT NULL REFERENCES jobs (job_id),
    object_index      INTEGER NOT NULL,
    success           INTEGER NOT NULL,
    goal_x            REAL, goal_y  REAL, goal_theta  REAL,
    final_x           REAL, final_y REAL, final_theta REAL,
    position_error    REAL,
    orientation_error REAL,
    left_workspace    INTEGER,
    segments          INTEGER,
    full_horizon_plan INTEGER,
    replans           INTEGER,
    planning_time_s   REAL,
    failure_reason    TEXT,
    PRIMARY KEY (job_id, object_index)
);
CREATE TABLE segments (
    job_id          INTEGER NOT NULL REFERENCES jobs (job_id),
    segment_index   INTEGER NOT NULL,
    planning_time_s REAL NOT NULL,
    PRIMARY KEY (job_id, segment_index)
);
CREATE INDEX jobs_by_cell ON jobs (planner, suite);
"""

#: The first bytes of every SQLite 3 file.
SQLITE_HEADER = b"SQLite format 3\x00"


def check_db_path(path: str | Path) -> Path:
    """``path`` as a place the database can be written, or ``ValueError`` saying why not.

    Refused: a folder; an existing file that is not an SQLite database (it would be
    overwritten); a location whose nearest existing folder cannot be written.
    """
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{path} is a folder; give a file name such as {path / 'results.sqlite'}")
    if path.exists():
        try:
            with open(path, "rb") as f:
                head = f.read(len(SQLITE_HEADER))
        except OSError as exc:
            raise ValueError(f"{path} cannot be read: {exc.strerror}") from None
        if head and head != SQLITE_HEADER:
            raise ValueError(f"{path} exists and is not an SQLite database; refusing to "
                             "overwrite it")
    parent = path.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"{path}: cannot write in {parent}")
    return path


def _bool(v: Any) -> int | None:
    return None if v is None else int(bool(v))


def _num(v: Any) -> float | None:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else None


def _int(v: Any) -> int | None:
    return int(v) if isinstance(v, int | float) and not isinstance(v, bool) else None


def _pose(v: Any) -> tuple[float | None, float | None, float | None]:
    if isinstance(v, list | tuple) and len(v) == 3:
        return (_num(v[0]), _num(v[1]), _num(v[2]))
    return (None, None, None)


def job_row(rec: dict[str, Any], attempts: int) -> dict[str, Any]:
    """The ``jobs`` columns of one results line (``job_id`` left to SQLite)."""
    objects = [o for o in (rec.get("objects") or []) if isinstance(o, dict)]
    times = rec.get("planning_time_s") if isinstance(rec.get("planning_time_s"), list) else []
    segments = _int(rec.get("segments"))
    total = _num(rec.get("total_planning_time_s"))
    if total is None and times:
        total = float(sum(times))
    per_segment = total / segments if total is not None and segments else None
    return {
        "run_id": _int(rec.get("run_id")), "suite": str(rec["suite"]),
        "scene": str(rec["scene"]), "scene_file": rec.get("scene_file"),
        "planner": str(rec["planner"]), "seed": int(rec["seed"]), "model": rec.get("model"),
        "status": str(rec.get("status", "ok")), "success": int(bool(rec.get("success"))),
        "failure_reason": rec.get("failure_reason") or None, "n_objects": len(objects),
        "full_horizon_plan": int(bool(objects) and all(o.get("full_horizon_plan")
                                                        for o in objects)),
        "segments": segments, "total_planning_time_s": total,
        "median_planning_time_s": _num(rec.get("median_planning_time_s")),
        "planning_time_per_segment_s": per_segment, "makespan": _int(rec.get("makespan")),
        "replans": _int(rec.get("replans")), "wall_time_s": _num(rec.get("wall_time_s")),
        "job_wall_time_s": _num(rec.get("job_wall_time_s")),
        "time_cap_s": _num(rec.get("time_cap_s")),
        "planning_limit_s": _num(rec.get("planning_limit_s")), "attempts": int(attempts),
        "result_json": json.dumps(rec, sort_keys=True, separators=(",", ":")),
    }


def object_row(job_id: int, index: int, o: dict[str, Any]) -> dict[str, Any]:
    gx, gy, gt = _pose(o.get("goal"))
    fx, fy, ft = _pose(o.get("final_pose"))
    return {
        "job_id": job_id, "object_index": index, "success": int(bool(o.get("success"))),
        "goal_x": gx, "goal_y": gy, "goal_theta": gt, "final_x": fx, "final_y": fy,
        "final_theta": ft, "position_error": _num(o.get("position_error")),
        "orientation_error": _num(o.get("orientation_error")),
        "left_workspace": _bool(o.get("left_workspace")), "segments": _int(o.get("segments")),
        "full_horizon_plan": _bool(o.get("full_horizon_plan")),
        "replans": _int(o.get("replans")), "planning_time_s": _num(o.get("planning_time_s")),
        "failure_reason": o.get("failure_reason") or None,
    }


def _insert(con: sqlite3.Connection, table: str, row: dict[str, Any]) -> int:
    cols = ", ".join(row)
    marks = ", ".join(f":{k}" for k in row)
    return int(con.execute(f"INSERT INTO {table} ({cols}) VALUES ({marks})", row).lastrowid)


def fill(con: sqlite3.Connection, records: Sequence[dict[str, Any]], config: dict[str, Any]
         ) -> None:
    """Create the tables in the empty database ``con`` and insert ``records`` and ``config``.

    ``records`` are results lines in file order; the last line per job key wins and
    ``attempts`` counts them all. A ``run_id`` naming no recorded run is stored as NULL.
    """
    con.executescript(SCHEMA)
    meta = {"schema_version": SCHEMA_VERSION, "format": config.get("format")}
    meta.update({k: v for k, v in config.items() if k != "sessions"})
    for key, value in meta.items():
        con.execute("INSERT INTO meta (key, value) VALUES (?, ?)", (key, json.dumps(value)))
    sessions = [s for s in (config.get("sessions") or []) if isinstance(s, dict)]
    for run_id, s in enumerate(sessions):
        _insert(con, "runs", {
            "run_id": run_id, "command": s.get("command"), "argv": s.get("argv"),
            "date": s.get("date"), "git_commit": s.get("git_commit"),
            "git_dirty": _bool(s.get("git_dirty")),
            "packages": json.dumps(s.get("packages") or {}, sort_keys=True)})
    attempts: Counter = Counter()
    for rec in records:
        with contextlib.suppress(KeyError, TypeError, ValueError):
            attempts[record_key(rec)] += 1
    for key, rec in latest_by_key(records).items():
        row = job_row(rec, attempts[key])
        if row["run_id"] is not None and not 0 <= row["run_id"] < len(sessions):
            row["run_id"] = None
        job_id = _insert(con, "jobs", row)
        for i, o in enumerate(rec.get("objects") or []):
            if isinstance(o, dict):
                _insert(con, "objects", object_row(job_id, i, o))
        times = rec.get("planning_time_s")
        if isinstance(times, list):
            con.executemany(
                "INSERT INTO segments (job_id, segment_index, planning_time_s) VALUES (?, ?, ?)",
                [(job_id, i, float(t)) for i, t in enumerate(times) if _num(t) is not None])


def write_db(run_dir: str | Path, path: str | Path) -> Path:
    """Write the database of ``run_dir`` to ``path`` (replacing it atomically); return ``path``."""
    run_dir, path = Path(run_dir), check_db_path(path)
    from lamp.bench.report import load_config

    records = read_records(run_dir / RESULTS_FILE)
    config = load_config(run_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".partial", dir=path.parent)
    os.close(fd)
    try:
        con = sqlite3.connect(tmp)
        try:
            with con:
                fill(con, records, config)
        finally:
            con.close()
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path
