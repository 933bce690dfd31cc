"""Tests of ``lamp bench`` / ``lamp report``: jobs, resume, caps, the results file, the report.

The planners are replaced by the stand-ins of ``bench_fakes.py`` in this folder (job
processes import them by name; ``conftest.py`` puts this folder on their path), so these tests exercise the machinery, not the planners, and run in seconds.
"""

from __future__ import annotations

import dataclasses
import json
import multiprocessing as mp
import os
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

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
from lamp.bench.report import (
    full_horizon_table,
    median_planning_time_table,
    path_cost_comparison,
    planning_time_points,
    success_table,
)
from lamp.bench.runner import outcome_record, run_local
from lamp.cli import app
from lamp.scene import scene_from_dict

runner = CliRunner()


def scene_dict(name: str, n_objects: int = 1) -> dict:
    objects = [{"type": "circle", "radius": 0.1, "start": [0.5 + 0.3 * i, 0.5, 0.0],
                "goal": [0.5 + 0.3 * i, 1.5, 0.0]} for i in range(n_objects)]
    return {"format": "lamp-scene/1", "name": name, "workspace": [4.0, 4.0],
            "robots": {"starts": [[0.1, 0.1], [0.3, 0.1], [3.9, 3.9]]}, "objects": objects}


def suite(name: str, n: int, n_objects: int = 1) -> list[SuiteScene]:
    return [SuiteScene(name, scene_from_dict(scene_dict(f"{name}-{i:02d}", n_objects)),
                       f"{name}/{name}-{i:02d}.yaml") for i in range(n)]


def write_suite(root: Path, name: str, n: int, n_objects: int = 1) -> Path:
    folder = root / name
    folder.mkdir(parents=True)
    for i in range(n):
        (folder / f"{name}-{i:02d}.yaml").write_text(
            yaml.safe_dump(scene_dict(f"{name}-{i:02d}", n_objects)))
    return folder


# --------------------------------------------------------------------------------- jobs
def test_jobs_enumerated_in_order_with_caps():
    suites = [suite("random", 3), suite("iros", 1, n_objects=4)]
    jobs = enumerate_jobs(suites, ["lazy", "astar"], [0, 1], time_cap_s=10.0,
                          planning_limit_s=7.0)
    assert len(jobs) == (3 + 1) * 2 * 2
    assert len({j.key for j in jobs}) == len(jobs)
    assert [j.key for j in jobs[:4]] == [("random", "random-00", "lazy", 0),
                                         ("random", "random-00", "astar", 0),
                                         ("random", "random-00", "lazy", 1),
                                         ("random", "random-00", "astar", 1)]
    # the cap scales with the objects of the scene; the planning limit reaches LAMP-A* only
    assert {j.time_cap_s for j in jobs if j.suite == "random"} == {10.0}
    assert {j.time_cap_s for j in jobs if j.suite == "iros"} == {40.0}
    assert {j.time_limit for j in jobs if j.planner == "astar"} == {7.0}
    assert {j.time_limit for j in jobs if j.planner == "lazy"} == {None}
    first = enumerate_jobs(suites, ["lazy"], [0], scenes_per_suite=2)
    assert [j.scene_name for j in first] == ["random-00", "random-01", "iros-00"]


def test_duplicate_scene_names_rejected():
    dup = suite("random", 1) * 2
    with pytest.raises(ValueError, match="duplicate job"):
        enumerate_jobs([dup], ["lazy"], [0])


def test_unknown_suite_names_the_choices(tmp_path):
    with pytest.raises(ValueError, match="unknown suite 'nonsense'"):
        load_suite("nonsense")
    folder = write_suite(tmp_path, "maze", 2)
    scenes = load_suite(str(folder))
    assert [s.scene.name for s in scenes] == ["maze-00", "maze-01"]
    assert {s.suite for s in scenes} == {"maze"}


def _record(suite_name, scene, planner, seed=0, status="ok", **extra):
    return {"suite": suite_name, "scene": scene, "planner": planner, "seed": seed,
            "status": status, **extra}


def test_resume_skips_recorded_jobs_and_retries_errors():
    jobs = enumerate_jobs([suite("random", 2)], ["lazy", "astar"], [0])
    records = [_record("random", "random-00", "lazy"),
               _record("random", "random-00", "astar", status="timeout"),
               _record("random", "random-01", "lazy", status="error")]
    todo = {j.key for j in pending_jobs(jobs, records)}
    assert todo == {("random", "random-01", "lazy", 0), ("random", "random-01", "astar", 0)}
    todo = {j.key for j in pending_jobs(jobs, records, retry_errors=False)}
    assert todo == {("random", "random-01", "astar", 0)}
    # a retried job's newer line wins
    records.append(_record("random", "random-01", "lazy", status="ok"))
    assert latest_by_key(records)[("random", "random-01", "lazy", 0)]["status"] == "ok"
    assert {j.key for j in pending_jobs(jobs, records)} == {("random", "random-01", "astar", 0)}


def test_rerun_repeats_a_planners_jobs_unless_redone_by_the_current_code():
    jobs = enumerate_jobs([suite("random", 2)], ["lazy", "astar"], [0])
    records = [_record("random", f"random-0{i}", p, run_id=0) for i in range(2)
               for p in ("lazy", "astar")]
    assert pending_jobs(jobs, records, rerun=["lazy"]) == [j for j in jobs if j.planner == "lazy"]
    # random-00 lazy was redone by run 1, the current code: only random-01 lazy is left
    records.append(_record("random", "random-00", "lazy", run_id=1))
    todo = pending_jobs(jobs, records, rerun=["lazy"], current_runs={1})
    assert [j.key for j in todo] == [("random", "random-01", "lazy", 0)]
    assert pending_jobs(jobs, records) == []  # without --rerun nothing is pending


@pytest.mark.parametrize(("sessions", "commit", "dirty", "expected"), [
    ([("a", False), ("b", False), ("a", True), ("a", False)], "a", False, {0, 3}),
    ([("a", False)], "a", True, set()),  # uncommitted code matches no recorded run
    ([("a", False)], None, None, set()),
    ([("a", None)], "a", False, set()),
])
def test_current_runs_are_clean_runs_of_the_running_commit(sessions, commit, dirty, expected):
    from lamp.bench.provenance import current_runs

    previous = {"sessions": [{"git_commit": c, "git_dirty": d} for c, d in sessions]}
    assert current_runs(previous, commit, dirty) == expected


# ----------------------------------------------------------------------- results file
def test_malformed_trailing_line_is_skipped_and_terminated(tmp_path):
    path = tmp_path / "results.jsonl"
    rf = ResultsFile(path)
    rf.append({"a": 1})
    rf.append({"a": 2})
    with open(path, "ab") as f:  # a writer killed mid-line
        f.write(b'{"a": 3, "objects": [1, 2')
    skipped = []
    assert read_records(path, on_skip=lambda i, r: skipped.append(i)) == [{"a": 1}, {"a": 2}]
    assert skipped == [3]
    rf.append({"a": 4})  # the fragment is terminated first, the new line stays intact
    assert read_records(path, on_skip=lambda i, r: None) == [{"a": 1}, {"a": 2}, {"a": 4}]


@settings(max_examples=40, deadline=None)
@given(records=st.lists(st.dictionaries(st.text(max_size=5), st.integers() | st.text(max_size=8)
                                        | st.floats(allow_nan=False, allow_infinity=False),
                                        max_size=4), max_size=6),
       garbage=st.binary(max_size=30))
def test_reader_recovers_every_complete_record(tmp_path_factory, records, garbage):
    path = tmp_path_factory.mktemp("r") / "results.jsonl"
    rf = ResultsFile(path)
    for rec in records:
        rf.append(rec)
    with open(path, "ab") as f:
        f.write(garbage.replace(b"\n", b" "))
    got = read_records(path, on_skip=lambda i, r: None)
    # the trailing fragment may itself be a valid JSON object (e.g. "{}"); nothing else is lost
    assert got[:len(records)] == records
    assert len(got) - len(records) in (0, 1)


def _append_many(path: str, worker: int, n: int) -> None:
    rf = ResultsFile(path)
    for i in range(n):
        rf.append({"worker": worker, "i": i, "pad": "x" * (1000 + 37 * i)})


def test_concurrent_appends_never_interleave(tmp_path):
    path = str(tmp_path / "results.jsonl")
    ctx = mp.get_context("fork")
    procs = [ctx.Process(target=_append_many, args=(path, w, 40)) for w in range(4)]
    for p in procs:
        p.start()
    for p in procs:
        p.join()
    bad = []
    recs = read_records(path, on_skip=lambda i, r: bad.append(i))
    assert not bad
    assert sorted((r["worker"], r["i"]) for r in recs) == [(w, i) for w in range(4)
                                                           for i in range(40)]


# --------------------------------------------------------------------------- runner
def test_local_runner_records_timeout_error_and_crash_as_failures():
    jobs = enumerate_jobs([suite("random", 1)], ["lazy", "astar", "astar-replan", "gco-var"],
                          [0], time_cap_s=60.0)
    jobs = [dataclasses.replace(j, time_cap_s=1.0) if j.planner == "lazy" else j for j in jobs]
    outcomes = []
    run_local(jobs, "bench_fakes:mixed_job", 2, outcomes.append)
    by = {o.job.planner: o for o in outcomes}
    assert {p: o.status for p, o in by.items()} == {
        "lazy": "timeout", "astar": "error", "astar-replan": "crashed", "gco-var": "ok"}
    timeout = outcome_record(by["lazy"])
    assert timeout["success"] is False and timeout["failure_reason"] == "timeout"
    assert timeout["total_planning_time_s"] == 1.0 and timeout["planning_time_s"] == []
    assert timeout["objects"][0]["failure_reason"] == "timeout"
    assert timeout["suite"] == "random" and timeout["scene_file"] == "random/random-00.yaml"
    assert by["lazy"].wall_time_s >= 1.0
    error = outcome_record(by["astar"])
    assert not error["success"] and "planner exploded" in error["failure_reason"]
    assert "RuntimeError" in error["error_detail"]
    crashed = outcome_record(by["astar-replan"])
    assert not crashed["success"] and "exited with code 3" in crashed["failure_reason"]
    ok = outcome_record(by["gco-var"])
    from bench_fakes import synthetic_job

    expected = synthetic_job(jobs[3])
    assert ok["success"] == expected["success"] and ok["makespan"] == expected["makespan"]


def test_job_function_must_be_importable():
    with pytest.raises(ValueError, match="cannot be imported"):
        run_local([], "bench_fakes:no_such_function", 1, lambda o: None)
    with pytest.raises(ValueError, match="top-level function"):
        run_local([], lambda job: {}, 1, lambda o: None)


@pytest.mark.slow  # starting a Ray instance takes about 10 s
def test_ray_backend_runs_the_same_jobs():
    import ray  # the `test` extra installs it (it is also the `ray` extra)

    from lamp.bench.runner import run_ray

    jobs = enumerate_jobs([suite("random", 1)], ["lazy", "astar", "astar-replan", "gco-var"],
                          [0], time_cap_s=120.0)
    jobs = [dataclasses.replace(j, time_cap_s=1.0) if j.planner == "lazy" else j for j in jobs]
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False,
             logging_level="ERROR")
    try:
        outcomes = []
        run_ray(jobs, "bench_fakes:mixed_job", 2, outcomes.append, start_grace_s=3.0)
    finally:
        ray.shutdown()
    assert {o.job.planner: o.status for o in outcomes} == {
        "lazy": "timeout", "astar": "error", "astar-replan": "crashed", "gco-var": "ok"}
    rec = outcome_record(next(o for o in outcomes if o.job.planner == "lazy"))
    assert rec["failure_reason"] == "timeout" and rec["total_planning_time_s"] == 1.0


# --------------------------------------------------------------------------- report
def _res(suite_name, scene, planner, success, times, makespan, fh, seed=0, n_objects=1):
    share = [len(times) // n_objects] * n_objects  # segments split between the objects
    share[-1] += len(times) - sum(share)
    objects = [{"success": success, "full_horizon_plan": fh, "segments": share[i],
                "planning_time_s": float(sum(times)) / n_objects,
                "failure_reason": "" if success else "x"} for i in range(n_objects)]
    return {"suite": suite_name, "scene": scene, "planner": planner, "seed": seed,
            "status": "ok", "success": success, "objects": objects, "segments": len(times),
            "planning_time_s": times, "total_planning_time_s": float(sum(times)),
            "makespan": makespan, "time_cap_s": 100.0}


SYNTHETIC = [
    _res("random", "r1", "lazy", True, [1.0, 2.0, 3.0], 100, True),
    _res("random", "r2", "lazy", True, [4.0], 50, True),
    _res("maze", "m1", "lazy", True, [2.0, 2.0], 300, True),
    _res("maze", "m2", "lazy", False, [], 0, False),
    _res("random", "r1", "gco-var", True, [0.5, 0.5], 80, False),
    _res("random", "r2", "gco-var", False, [1.0], 0, False),
    _res("maze", "m1", "gco-var", False, [0.2], 0, False),
    _res("maze", "m2", "gco-var", True, [0.1], 10, False),
    _res("random", "r1", "astar", True, [10.0], 200, True),
    _res("random", "r2", "astar", True, [5.0, 5.0], 25, False),
    _res("maze", "m1", "astar", False, [20.0], 0, True),
    _res("maze", "m2", "astar", False, [], 0, False),
    _res("iros", "iros", "lazy", True, [1.0, 3.0, 2.0], 999, True, n_objects=2),
]


def test_report_tables_equal_hand_computed_numbers():
    t1 = success_table(SYNTHETIC)
    assert list(t1) == ["gco-var", "astar", "lazy"]  # paper row order, IROS left out
    assert {p: {f: (r.k, r.n) for f, r in row.items()} for p, row in t1.items()} == {
        "lazy": {"random": (2, 2), "maze": (1, 2), "all": (3, 4)},
        "gco-var": {"random": (1, 2), "maze": (1, 2), "all": (2, 4)},
        "astar": {"random": (2, 2), "maze": (0, 2), "all": (2, 4)},
    }
    t2 = full_horizon_table(SYNTHETIC)
    assert {p: {f: (r.k, r.n) for f, r in row.items()} for p, row in t2.items()} == {
        "astar": {"random": (1, 2), "maze": (1, 2), "all": (2, 4)},
        "lazy": {"random": (2, 2), "maze": (1, 2), "all": (3, 4)},
    }
    med = median_planning_time_table(SYNTHETIC)
    assert med["lazy"] == {"random": (3.0, 2), "maze": (2.0, 1), "all": (2.0, 3)}
    assert med["astar"] == {"random": (7.5, 2), "maze": (None, 0), "all": (7.5, 2)}
    costs = path_cost_comparison(SYNTHETIC)
    g = costs["gco-var"]
    assert (g.n, g.dnf_baseline, g.dnf_reference, g.both_failed) == (1, 2, 1, 0)
    assert g.mean_ratio == pytest.approx(100 / 80)
    a = costs["astar"]
    assert (a.n, a.dnf_baseline, a.dnf_reference, a.both_failed) == (2, 1, 0, 1)
    assert a.mean_ratio == pytest.approx((100 / 200 + 50 / 25) / 2)
    pts = planning_time_points(SYNTHETIC, fail_value=60.0)
    assert sorted(v for _, v, _ in pts["lazy"]) == [2.0, 2.0, 4.0, 60.0]
    assert [bad for _, v, bad in pts["lazy"] if v == 60.0] == [True]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["random", "maze", "tilt", "warehouse", "iros"]),
                          st.integers(0, 3), st.sampled_from(["lazy", "astar", "gco-var"]),
                          st.booleans(), st.booleans()), max_size=40))
def test_tables_count_the_raw_records(rows):
    """Every Table I/II cell (and its Markdown) is the brute-force count of the raw lines."""
    from lamp.bench.report import full_horizon_markdown, success_markdown

    records = list(latest_by_key(
        _res(f, f"{f}-{i}", p, ok, [1.0], 10, fh) for f, i, p, ok, fh in rows).values())
    t1, t2 = success_table(records), full_horizon_table(records)
    fams = sorted({r["suite"] for r in records if r["suite"] != "iros"})
    md1 = success_markdown(t1, fams)
    for p in {r["planner"] for r in records if r["suite"] != "iros"}:
        for f in [*fams, "all"]:
            cell = [r for r in records if r["planner"] == p and r["suite"] != "iros"
                    and f in ("all", r["suite"])]
            k = sum(r["success"] for r in cell)
            assert (t1[p][f].k, t1[p][f].n) == (k, len(cell))
            if cell:
                assert f"{round(100 * k / len(cell))}% ({k}/{len(cell)})" in md1
            if p != "gco-var":
                kf = sum(r["objects"][0]["full_horizon_plan"] for r in cell)
                assert (t2[p][f].k, t2[p][f].n) == (kf, len(cell))
    assert "gco-var" not in t2
    full_horizon_markdown(t2, fams)


def test_lamp_report_rebuilds_from_results(tmp_path):
    rf = ResultsFile(tmp_path / "results.jsonl")
    stale = dict(SYNTHETIC[0], success=False, status="error")  # superseded by the next line
    for rec in [stale, *SYNTHETIC]:
        rf.append(rec)
    res = runner.invoke(app, ["report", str(tmp_path)])
    assert res.exit_code == 0, res.output
    md = (tmp_path / "report.md").read_text()
    assert "| LAMP-Lazy | 100% (2/2) [paper 100%] | 50% (1/2) [paper 96%] | 75% (3/4) |" in md
    assert "| GCo_var | 50% (1/2) [paper 68%] | 50% (1/2) [paper 12%] | 50% (2/4) |" in md
    assert "| LAMP-A*_ori | 50% (1/2) [paper 100%] | 50% (1/2) [paper 8%] | 50% (2/4) |" in md
    assert "| LAMP-Lazy vs GCo_var | 1 | 1.250 | 1.250 | 2 | 1 | 0 |" in md
    assert "| LAMP-Lazy | 3 (n=2) | 2 (n=1) | 2 (n=3) |" in md
    assert "| LAMP-Lazy | 0 | yes | 2/2 | 3 | 2 | 6 |" in md  # IROS: mean 6 s / 3 segments
    for fig in ("planning_time.png", "planning_time_by_family.png", "path_cost.png",
                "iros_planning_time.png"):
        assert (tmp_path / fig).stat().st_size > 1000
    assert "no config.json" in md


def _mapush(suite_name, scene, loose, strict=False, status="ok", run_id=None):
    rec = dict(_res(suite_name, scene, "mapush", strict, [0.1] * 15, 0, False),
               status=status, stats={} if status != "ok" else {"mapush_success": loose})
    return rec if run_id is None else dict(rec, run_id=run_id)


MAPUSH = [_mapush("random", "r1", True), _mapush("random", "r2", True, strict=True),
          _mapush("maze", "m1", False), _mapush("maze", "m2", False, status="timeout"),
          _mapush("iros", "iros", True)]


def test_mapush_criteria_equal_hand_computed_numbers():
    from lamp.bench.report import mapush_criteria_table

    table = mapush_criteria_table(SYNTHETIC + MAPUSH)
    assert {c: {f: (r.k, r.n) for f, r in row.items()} for c, row in table.items()} == {
        "mapush": {"random": (2, 2), "maze": (0, 2), "all": (2, 4)},  # IROS left out
        "strict": {"random": (1, 2), "maze": (0, 2), "all": (1, 4)},
    }
    assert mapush_criteria_table(SYNTHETIC) == {}


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["random", "maze", "tilt", "warehouse"]),
                          st.integers(0, 5), st.booleans(), st.booleans(),
                          st.sampled_from(["ok", "ok", "timeout"])), max_size=30))
def test_mapush_criterion_counts_the_raw_records(rows):
    """Each cell is the brute-force count of ``stats.mapush_success`` over the MAPush lines."""
    from lamp.bench.report import mapush_criteria_table

    records = list(latest_by_key(_mapush(f, f"{f}-{i}", loose, strict, status)
                                 for f, i, loose, strict, status in rows).values())
    table = mapush_criteria_table(records + SYNTHETIC)
    assert bool(table) == bool(records)
    for f in ([*{r["suite"] for r in records}, "all"] if records else []):
        cell = [r for r in records if f in ("all", r["suite"])]
        k = sum(bool(r["stats"].get("mapush_success")) for r in cell)
        assert (table["mapush"][f].k, table["mapush"][f].n) == (k, len(cell))
        assert table["strict"][f].k == sum(r["success"] for r in cell)


def test_report_shows_both_mapush_criteria_and_where_rows_come_from(tmp_path):
    rf = ResultsFile(tmp_path / "results.jsonl")
    for rec in [*SYNTHETIC, *(dict(r, run_id=1) for r in MAPUSH)]:
        rf.append(rec)
    sessions = [{"command": "lamp bench a", "git_commit": "aaaaaaaaaaaa1", "git_dirty": False},
                {"command": "lamp bench b", "git_commit": "bbbbbbbbbbbb2", "git_dirty": False,
                 "machine": {"cpu": "Zen 9"}}]
    (tmp_path / "config.json").write_text(json.dumps({"sessions": sessions}))
    res = runner.invoke(app, ["report", str(tmp_path)])
    assert res.exit_code == 0, res.output
    md = (tmp_path / "report.md").read_text()
    # Table I: strict, without the paper's MAPush figures (they count the other criterion)
    assert "| MAPush (strict criterion) | 50% (1/2) | 0% (0/2) | 25% (1/4) |" in md
    assert ("| MAPush criterion (0.5 m, position only, 120 s) | 100% (2/2) [paper 8%] "
            "| 0% (0/2) [paper 0%] | 50% (2/4) |") in md
    assert "| strict criterion (0.1 m and 0.1 rad, as Table I) | 50% (1/2) | 0% (0/2) |" in md
    assert "- run 1: `lamp bench b` on ?, commit `bbbbbbbbbbbb2`, on Zen 9\n" in md
    assert "- run 0: `lamp bench a` on ?, commit `aaaaaaaaaaaa1`\n" in md
    assert ("MAPush: 5 from run 1 (commit `bbbbbbbbbb`); GCo_var: 4 written before lines "
            "carried a run id (run 0)") in md


def test_report_needs_results(tmp_path):
    res = runner.invoke(app, ["report", str(tmp_path)])
    assert res.exit_code == 2 and "no results.jsonl" in res.output


# ------------------------------------------------------------------------------ CLI
def test_bench_end_to_end_resume_and_render(tmp_path):
    write_suite(tmp_path / "suites", "random", 2)
    write_suite(tmp_path / "suites", "iros", 1, n_objects=2)
    out = tmp_path / "run"
    args = ["bench", "--suite", f"{tmp_path}/suites/random,{tmp_path}/suites/iros",
            "--planners", "lazy,gco-var", "--workers", "2", "--out", str(out),
            "--job-fn", "bench_fakes:render_job", "--no-progress", "--render-iros",
            "--time-cap", "30", "--no-report"]  # the report has its own tests
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    recs = read_records(out / "results.jsonl")
    assert len(recs) == 6 and {r["status"] for r in recs} == {"ok"}
    assert {(r["suite"], r["scene"], r["planner"]) for r in recs} == {
        (s, f"{s}-{i:02d}", p) for s, n in (("random", 2), ("iros", 1)) for i in range(n)
        for p in ("lazy", "gco-var")}
    assert all(r["scene_file"].endswith(f"{r['scene']}.yaml") for r in recs)
    assert (out / "iros.gif").exists() and not (out / "report.md").exists()
    config = json.loads((out / "config.json").read_text())
    assert config["time_cap_s"] == 30.0 and config["planning_limit_s"] == 30.0
    assert config["sessions"][0]["command"].startswith("lamp bench --suite")
    assert "--time-cap 30 --planning-limit 30" in config["sessions"][0]["command"]

    # a killed run: two results lost, a half-written line left, the animation missing
    lines = (out / "results.jsonl").read_bytes().splitlines(keepends=True)
    (out / "results.jsonl").write_bytes(b"".join(lines[:4]) + lines[4][:25])
    (out / "iros.gif").unlink()
    res = runner.invoke(app, args)
    assert res.exit_code == 2 and "not empty" in res.output and "--resume" in res.output
    res = runner.invoke(app, [*args, "--resume"])
    assert res.exit_code == 0, res.output
    assert "6 jobs" in res.output and "4 already recorded" in res.output
    recs = read_records(out / "results.jsonl", on_skip=lambda i, r: None)
    assert len(recs) == 6 and len({(r["scene"], r["planner"]) for r in recs}) == 6
    assert (out / "iros.gif").exists()
    assert len(json.loads((out / "config.json").read_text())["sessions"]) == 2

    # nothing left to do; a resume with different caps is refused
    res = runner.invoke(app, [*args, "--resume"])
    assert res.exit_code == 0 and "0 to run" in res.output
    res = runner.invoke(app, [*args, "--time-cap", "31", "--resume"])
    assert res.exit_code == 2 and "time_cap_s" in res.output


def test_bench_rerun_replaces_one_planners_records(tmp_path, monkeypatch):
    """--resume --rerun lazy appends new LAMP-Lazy lines only; the report counts those; a
    second --rerun with the same code has nothing left to do, new code re-runs them again."""
    from lamp.bench import provenance
    from lamp.bench.report import load_results

    version = ["c0"]
    monkeypatch.setattr(provenance, "code_version", lambda out: (version[0], False))
    folder = write_suite(tmp_path, "random", 2)
    out = tmp_path / "run"
    args = ["bench", "--suites", str(folder), "--planners", "lazy,gco-var", "--workers", "1",
            "--out", str(out), "--job-fn", "bench_fakes:synthetic_job", "--no-progress"]
    assert runner.invoke(app, args).exit_code == 0
    res = runner.invoke(app, [*args, "--resume", "--rerun", "lazy"])
    assert res.exit_code == 0 and "0 to run" in res.output  # recorded by this very code
    version[0] = "c1"
    before = (out / "results.jsonl").read_bytes()
    res = runner.invoke(app, [*args, "--resume", "--rerun", "lazy"])
    assert res.exit_code == 0, res.output
    assert "2 to run, 2 already recorded; re-running lazy" in res.output
    after = (out / "results.jsonl").read_bytes()
    assert after.startswith(before)  # nothing rewritten
    new = read_records(out / "results.jsonl")[4:]
    assert [(r["scene"], r["planner"], r["run_id"]) for r in new] == [
        ("random-00", "lazy", 1), ("random-01", "lazy", 1)]
    latest = {(r["scene"], r["planner"]): r["run_id"] for r in load_results(out)}
    assert latest == {("random-00", "lazy"): 1, ("random-01", "lazy"): 1,
                      ("random-00", "gco-var"): 0, ("random-01", "gco-var"): 0}
    res = runner.invoke(app, [*args, "--resume", "--rerun", "lazy"])
    assert res.exit_code == 0 and "0 to run" in res.output
    version[0] = "c2"
    res = runner.invoke(app, [*args, "--resume", "--rerun", "lazy"])
    assert res.exit_code == 0 and "2 to run" in res.output
    for extra, message in ((["--rerun", "lazy"], "--rerun needs --resume"),
                           (["--resume", "--rerun", "astar"], "'astar' is not in --planners")):
        res = runner.invoke(app, [*args, *extra])
        assert res.exit_code == 2 and message in res.output, res.output
    assert len(read_records(out / "results.jsonl")) == 8


@pytest.mark.parametrize("extra, message", [
    (["--suite", "nonsense"], "unknown suite 'nonsense'"),
    (["--planners", "lazy,dijkstra"], "unknown planner 'dijkstra'"),
    (["--model", "magic"], "unknown model"),
    (["--backend", "slurm"], "unknown backend"),
    (["--seeds", "0"], "--num-seeds must be at least 1"),
    (["--num-seeds", "0"], "--num-seeds must be at least 1"),
    (["--time-cap", "-1"], "--time-cap must be positive"),
])
def test_bench_rejects_bad_input_with_exit_2(tmp_path, extra, message):
    folder = write_suite(tmp_path, "random", 1)
    args = ["bench", "--suite", str(folder), "--out", str(tmp_path / "run"),
            "--job-fn", "bench_fakes:synthetic_job", "--no-progress", *extra]
    res = runner.invoke(app, args)
    assert res.exit_code == 2, res.output
    assert message in res.output
    assert not (tmp_path / "run").exists()


def test_bench_param_reaches_the_jobs_and_the_config(tmp_path):
    """--param is checked against the run's planners before anything runs, reaches each job
    of its planner only, is recorded in config.json's command and ``params``, and a resume
    with other parameters is refused."""
    import json

    from lamp.bench.request import BenchRequest

    folder = write_suite(tmp_path, "random", 1)
    out = tmp_path / "run"
    args = ["bench", "--suites", str(folder), "--planners", "lazy,gco-var", "--workers", "1",
            "--out", str(out), "--job-fn", "bench_fakes:synthetic_job", "--no-progress"]
    for bad, message in ((["--param", "astar.k=4"], "planner 'astar' is not among --planners"),
                         (["--param", "gco-var.max_plan_iterations=4"], "no parameter"),
                         (["--param", "lazy.k=-1"], "lazy.k: an integer >= 1")):
        res = runner.invoke(app, [*args, *bad])
        assert res.exit_code == 2 and message in res.output, res.output
        assert not out.exists()
    res = runner.invoke(app, [*args, "--param", "lazy.max_plan_iterations=300"])
    assert res.exit_code == 0, res.output
    config = json.loads((out / "config.json").read_text())
    assert config["params"] == ["lazy.max_plan_iterations=300"]
    assert "--param lazy.max_plan_iterations=300" in config["sessions"][-1]["command"]
    res = runner.invoke(app, [*args, "--resume", "--param", "lazy.max_plan_iterations=200"])
    assert res.exit_code == 2 and "params" in res.output
    request = BenchRequest(out=out, suites=(str(folder),), planners=("lazy",),
                           params=("lazy.k=4", "lazy.edge_penalty=2"))
    by_planner = request.planner_params
    assert by_planner == {"lazy": (("edge_penalty", "2"), ("k", "4"))}
    assert request.params == ("lazy.edge_penalty=2", "lazy.k=4")
    jobs = enumerate_jobs([suite("tilt", 1)], ["lazy", "gco-var"], [0], params=by_planner)
    assert [j.params for j in jobs] == [by_planner["lazy"], ()]


def test_dry_run_lists_jobs_without_writing(tmp_path):
    folder = write_suite(tmp_path, "maze", 3)
    res = runner.invoke(app, ["bench", "--suite", str(folder), "--out", str(tmp_path / "run"),
                              "--scenes", "2", "--seeds", "2", "--dry-run"])
    assert res.exit_code == 0, res.output
    assert "20 jobs" in res.output and "20 to run" in res.output  # 2 scenes x 5 x 2 seeds
    assert not (tmp_path / "run").exists()


def test_fake_synthetic_job_is_deterministic():
    job = enumerate_jobs([suite("tilt", 1)], ["lazy"], [3])[0]
    from bench_fakes import synthetic_job

    a, b = synthetic_job(job), synthetic_job(dataclasses.replace(job))
    assert a == b and a["segments"] == len(a["planning_time_s"])
    assert np.isclose(a["total_planning_time_s"], sum(a["planning_time_s"]))
    assert isinstance(job, Job)


def test_solve_job_wiring_and_render_failure(monkeypatch, tmp_path):
    """solve_job builds the run request from the job's settings; a failing GIF writer
    costs only the animation, never the run's result."""
    import sys
    import types

    import lamp.pipeline as pipeline
    from lamp.bench.runner import solve_job
    from lamp.contract.result import RunResult

    calls = []

    def fake_run(request):
        calls.append((request.scene.name, request.planner, request.seed, request.model,
                      request.params.loop.planning_time_limit, request.params.loop.max_segments))
        return RunResult(scene=request.scene.name, planner=request.planner, seed=request.seed)

    def broken_render(recording, path):
        raise OSError("disk full")

    monkeypatch.setattr(pipeline, "run", fake_run)
    monkeypatch.setitem(sys.modules, "lamp.viz.replay",
                        types.SimpleNamespace(render=broken_render))
    jobs = enumerate_jobs([suite("iros", 1)], ["lazy", "astar"], [2], model="geometric",
                          planning_limit_s=12.0)
    out = solve_job(dataclasses.replace(jobs[0], render_to=str(tmp_path / "iros.gif")))
    assert out["render_error"] == "OSError: disk full" and out["scene"] == "iros-00"
    assert not (tmp_path / "iros.gif").exists()
    solve_job(jobs[1])
    # synthetic scenes, not the built-in suite: the segment limit scales with the task
    assert calls == [("iros-00", "lazy", 2, "geometric", 300.0, None),
                     ("iros-00", "astar", 2, "geometric", 12.0, None)]


@pytest.mark.parametrize(("changed", "dirty"), [
    (" M results/full/results.jsonl\n M results/full/config.json", False),
    (" M results/full/results.jsonl\n M src/lamp/planners/lazy.py", True),
    ("", False),
])
def test_session_ignores_changes_inside_the_output_folder(tmp_path, monkeypatch, changed, dirty):
    from lamp.bench import provenance

    answers = {"status": changed, "rev-parse": str(tmp_path)}
    monkeypatch.setattr(provenance, "_git", lambda *args: answers[args[0]])
    session = provenance._session("lamp bench", tmp_path / "results" / "full")
    assert session["git_dirty"] is dirty
    assert session["machine"]["cpu_count"] == os.cpu_count()  # each run says where it ran
