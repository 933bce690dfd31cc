"""``lamp bench --db`` / ``lamp report --db``: the SQLite database of a benchmark folder.

The queries of docs/bench-db.md are run against databases built from random results and
compared with the report's own tables; the documented columns are the real ones; bad
``--db`` paths exit 2 before anything runs; a failed write leaves the old file alone.
"""

from __future__ import annotations

import json
import re
import sqlite3
from collections import Counter
from pathlib import Path

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from lamp.bench import db as bench_db
from lamp.bench.jobs import ResultsFile, latest_by_key
from lamp.bench.report import (
    full_horizon_table,
    median_planning_time_table,
    path_cost_comparison,
    success_table,
)
from lamp.cli import app

runner = CliRunner()
DOC = Path(__file__).resolve().parents[1] / "docs" / "bench-db.md"


def documented_queries() -> dict[str, str]:
    text = DOC.read_text()
    blocks = re.findall(r"```sql\n(.*?)```", text, flags=re.S)
    out = {}
    for block in blocks:
        name = re.match(r"-- query: (\w+)\n", block)
        assert name, f"every SQL example is named: {block[:40]!r}"
        out[name.group(1)] = block
    return out


def record(suite, scene, planner, seed, success, seg_times, makespan, fh, n_obj=1, run_id=0,
           status="ok"):
    objects = [{"success": success, "goal": [1.0, 2.0, 0.5], "final_pose": [1.01, 2.0, 0.5],
                "position_error": 0.01, "orientation_error": 0.0, "left_workspace": False,
                "segments": len(seg_times), "full_horizon_plan": fh, "replans": 1,
                "planning_time_s": float(sum(seg_times)) / n_obj,
                "failure_reason": "" if success else f"{planner} gave up"}
               for _ in range(n_obj)]
    return {"suite": suite, "scene": scene, "planner": planner, "seed": seed, "status": status,
            "success": success, "objects": objects, "segments": len(seg_times),
            "planning_time_s": seg_times, "total_planning_time_s": float(sum(seg_times)),
            "makespan": makespan, "replans": n_obj, "wall_time_s": 1.0, "run_id": run_id,
            "failure_reason": "" if success else f"{planner} gave up", "time_cap_s": 60.0}


def build(tmp: Path, records: list[dict], n_runs: int = 1) -> sqlite3.Connection:
    tmp.mkdir(parents=True, exist_ok=True)
    rf = ResultsFile(tmp / "results.jsonl")
    for rec in records:
        rf.append(rec)
    sessions = [{"command": f"lamp bench #{i}", "git_commit": f"c{i}", "date": "2026-01-01"}
                for i in range(n_runs)]
    (tmp / "config.json").write_text(json.dumps({"format": "lamp-bench/1", "time_cap_s": 60.0,
                                                 "sessions": sessions}))
    path = bench_db.write_db(tmp, tmp / "results.sqlite")
    con = sqlite3.connect(path)
    con.execute("PRAGMA foreign_keys = ON")
    return con


records_strategy = st.lists(
    st.tuples(st.sampled_from(["random", "maze", "iros"]), st.integers(0, 2),
              st.sampled_from(["lazy", "astar", "gco-var"]), st.integers(0, 1), st.booleans(),
              st.lists(st.floats(0.01, 10.0), max_size=4), st.integers(1, 500), st.booleans(),
              st.integers(1, 3), st.integers(0, 1)),
    max_size=30)


@settings(max_examples=40, deadline=None)
@given(rows=records_strategy)
def test_documented_queries_equal_the_report(tmp_path_factory, rows):
    records = [record(f, f"{f}-{i}", p, seed, ok, times, ms, fh, n_obj=n, run_id=run)
               for f, i, p, seed, ok, times, ms, fh, n, run in rows]
    latest = list(latest_by_key(records).values())
    con = build(tmp_path_factory.mktemp("db"), records, n_runs=2)
    q = documented_queries()
    assert con.execute("PRAGMA foreign_key_check").fetchall() == []
    assert con.execute("SELECT COUNT(*) FROM jobs").fetchone()[0] == len(latest)
    assert con.execute("SELECT COUNT(*) FROM objects").fetchone()[0] == sum(
        len(r["objects"]) for r in latest)
    assert con.execute("SELECT COUNT(*) FROM segments").fetchone()[0] == sum(
        len(r["planning_time_s"]) for r in latest)
    assert con.execute("SELECT SUM(attempts) FROM jobs").fetchone()[0] == (len(records) or None)

    t1 = success_table(latest)  # the report counts the latest line per job, as load_results
    got = {(p, s): (k, n) for p, s, k, n, _ in con.execute(q["success_rate"])}
    assert got == {(p, s): (r.k, r.n) for p, row in t1.items() for s, r in row.items()
                   if s != "all" and r.n}
    t2 = full_horizon_table(latest)
    got = {(p, s): (k, n) for p, s, k, n in con.execute(q["full_horizon_rate"])}
    assert got == {(p, s): (r.k, r.n) for p, row in t2.items() for s, r in row.items()
                   if s != "all" and r.n}
    med = median_planning_time_table(latest)
    got = {(p, s): (m, n) for p, s, m, n in con.execute(q["median_planning_time"])}
    want = {(p, s): v for p, row in med.items() for s, v in row.items()
            if s != "all" and v[1]}
    assert got.keys() == want.keys()
    for key, (m, n) in got.items():
        assert n == want[key][1] and m == pytest.approx(want[key][0])
    costs = path_cost_comparison(latest)
    got = {b: (n, r) for b, n, r in con.execute(q["path_cost"])}
    assert got.keys() == {b for b, c in costs.items() if c.n}
    for b, (n, ratio) in got.items():
        assert n == costs[b].n and ratio == pytest.approx(costs[b].mean_ratio)
    want_fail = Counter((r["planner"], o["failure_reason"]) for r in latest
                        for o in r["objects"] if not o["success"])
    assert {(p, f): n for p, f, n in con.execute(q["object_failures"])} == want_fail
    prov = con.execute(q["provenance"]).fetchall()
    assert [(s, sc, p, seed, commit) for s, sc, p, seed, commit, _ in prov] == [
        (r["suite"], r["scene"], r["planner"], r["seed"], f"c{r['run_id']}") for r in latest]


def test_documented_columns_are_the_real_ones(tmp_path):
    con = build(tmp_path, [record("maze", "m", "lazy", 0, True, [1.0], 10, True)])
    text = DOC.read_text()
    tables = [t for (t,) in con.execute("SELECT name FROM sqlite_master WHERE type='table'")]
    assert sorted(tables) == ["jobs", "meta", "objects", "runs", "segments"]
    for table in tables:
        section = text.split(f"### `{table}`")[1].split("\n## ")[0].split("\n### ")[0]
        documented = set(re.findall(r"`(\w+)`", section))
        columns = {c[1] for c in con.execute(f"PRAGMA table_info({table})")}
        assert columns <= documented, (table, columns - documented)
    version = con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
    assert json.loads(version[0]) == bench_db.SCHEMA_VERSION
    assert f"Schema version {bench_db.SCHEMA_VERSION}" in text


def test_latest_line_wins_and_attempts_count_them(tmp_path):
    stale = record("random", "r", "lazy", 0, False, [], 0, False, status="error")
    fresh = record("random", "r", "lazy", 0, True, [2.0, 4.0], 90, True, run_id=1)
    con = build(tmp_path, [stale, fresh], n_runs=2)
    row = con.execute("SELECT status, success, attempts, run_id, segments, "
                      "planning_time_per_segment_s, full_horizon_plan FROM jobs").fetchall()
    assert row == [("ok", 1, 2, 1, 2, 3.0, 1)]
    obj = con.execute("SELECT goal_x, goal_y, goal_theta, final_x, failure_reason "
                      "FROM objects").fetchall()
    assert obj == [(1.0, 2.0, 0.5, 1.01, None)]
    assert json.loads(con.execute("SELECT result_json FROM jobs").fetchone()[0]) == fresh


def test_unknown_run_ids_and_missing_fields_become_null(tmp_path):
    rec = record("tilt", "t", "gco-var", 0, False, [], 0, False, run_id=7)
    del rec["makespan"], rec["objects"][0]["final_pose"]
    con = build(tmp_path, [rec], n_runs=1)
    assert con.execute("SELECT run_id, makespan FROM jobs").fetchall() == [(None, None)]
    assert con.execute("SELECT final_x FROM objects").fetchall() == [(None,)]
    assert con.execute("PRAGMA foreign_key_check").fetchall() == []


def test_a_failed_write_leaves_the_previous_database(tmp_path, monkeypatch):
    con = build(tmp_path, [record("maze", "m", "lazy", 0, True, [1.0], 10, True)])
    con.close()
    before = (tmp_path / "results.sqlite").read_bytes()

    def broken(con, records, config):
        con.execute("CREATE TABLE half (x)")
        raise RuntimeError("disk full")

    monkeypatch.setattr(bench_db, "fill", broken)
    with pytest.raises(RuntimeError, match="disk full"):
        bench_db.write_db(tmp_path, tmp_path / "results.sqlite")
    assert (tmp_path / "results.sqlite").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["config.json", "results.jsonl",
                                                         "results.sqlite"]


def write_suite(root: Path, name: str, n: int) -> Path:
    folder = root / name
    folder.mkdir(parents=True)
    for i in range(n):
        (folder / f"{name}-{i:02d}.yaml").write_text(yaml.safe_dump({
            "format": "lamp-scene/1", "name": f"{name}-{i:02d}", "workspace": [2.0, 2.0],
            "robots": {"starts": [[0.2, 0.2], [0.4, 0.2], [1.8, 1.8]]},
            "objects": [{"type": "circle", "radius": 0.1, "start": [0.8, 0.8, 0.0],
                         "goal": [1.2, 1.0, 0.0]}, {"type": "circle", "radius": 0.1,
                                                     "start": [0.5, 1.5, 0.0],
                                                     "goal": [1.5, 1.5, 0.0]}]}))
    return folder


def test_bench_and_report_write_the_database(tmp_path):
    folder = write_suite(tmp_path, "random", 2)
    out, db = tmp_path / "run", tmp_path / "dbs" / "results.sqlite"
    res = runner.invoke(app, ["bench", "--suites", str(folder), "--planners", "lazy,gco-var",
                              "--num-seeds", "2", "--out", str(out), "--db", str(db),
                              "--job-fn", "bench_fakes:synthetic_job", "--no-progress",
                              "--no-report"])
    assert res.exit_code == 0, res.output
    assert f"wrote {db}" in res.output
    con = sqlite3.connect(db)
    assert con.execute("SELECT COUNT(*), COUNT(DISTINCT run_id) FROM jobs").fetchone() == (8, 1)
    assert con.execute("SELECT COUNT(*) FROM objects").fetchone() == (16,)
    assert con.execute("SELECT command FROM runs").fetchone()[0].startswith("lamp bench")
    solved = con.execute("SELECT COUNT(*) FROM jobs WHERE success = 1").fetchone()[0]
    lines = [json.loads(x) for x in (out / "results.jsonl").read_text().splitlines()]
    assert solved == sum(r["success"] for r in lines)
    con.close()
    res = runner.invoke(app, ["report", str(out), "--db", str(tmp_path / "again.sqlite")])
    assert res.exit_code == 0, res.output
    again = sqlite3.connect(tmp_path / "again.sqlite")
    assert again.execute("SELECT * FROM jobs").fetchall() == sqlite3.connect(db).execute(
        "SELECT * FROM jobs").fetchall()


@pytest.mark.parametrize("kind", ["folder", "not-sqlite", "unwritable"])
def test_a_bad_db_path_is_refused_before_running(tmp_path, kind):
    folder = write_suite(tmp_path, "maze", 1)
    target = tmp_path / "target"
    if kind == "folder":
        target.mkdir()
        message = "is a folder"
    elif kind == "not-sqlite":
        target.write_text("my notes")
        message = "not an SQLite database"
    else:
        blocker = tmp_path / "file"
        blocker.write_text("x")
        target = blocker / "results.sqlite"
        message = "cannot write in"
    res = runner.invoke(app, ["bench", "--suites", str(folder), "--out", str(tmp_path / "run"),
                              "--db", str(target), "--job-fn", "bench_fakes:synthetic_job",
                              "--no-progress"])
    assert res.exit_code == 2, res.output
    assert "--db" in res.output and message in res.output and str(target) in res.output
    assert not (tmp_path / "run").exists()
    if kind == "not-sqlite":
        assert target.read_text() == "my notes"
