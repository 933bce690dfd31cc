"""The local backend's warm worker processes (``lamp.bench.pool``).

Workers are reused across jobs, retired after ``jobs_per_worker`` jobs, replaced after a
timeout or a crash without costing other jobs; a real job gives the same result in a reused
worker as in a fresh process; ``SIGTERM`` to ``lamp bench`` leaves no worker and no scratch
folder behind; a resume with nothing to do records no new run.
"""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from bench_fakes import pid_job
from typer.testing import CliRunner

from lamp.bench.jobs import SuiteScene, enumerate_jobs, read_records
from lamp.bench.pool import run_local
from lamp.cli import app
from lamp.scene import scene_from_dict

runner = CliRunner()


def scene_dict(name: str) -> dict:
    return {"format": "lamp-scene/1", "name": name, "workspace": [2.0, 2.0],
            "robots": {"starts": [[0.2, 0.2], [0.4, 0.2], [1.8, 1.8]]},
            "objects": [{"type": "circle", "radius": 0.1, "start": [0.8, 0.8, 0.0],
                         "goal": [1.2, 1.0, 0.0]}]}


def suite(name: str, n: int) -> list[SuiteScene]:
    return [SuiteScene(name, scene_from_dict(scene_dict(f"{name}-{i:02d}")),
                       f"{name}/{name}-{i:02d}.yaml") for i in range(n)]


def write_suite(root: Path, name: str, n: int) -> Path:
    folder = root / name
    folder.mkdir(parents=True)
    for i in range(n):
        (folder / f"{name}-{i:02d}.yaml").write_text(yaml.safe_dump(scene_dict(f"{name}-{i:02d}")))
    return folder


def pid_of(outcome) -> int:
    return outcome.result["stats"]["pid"]


def without_pid(result: dict) -> dict:
    return {**result, "stats": {k: v for k, v in result["stats"].items() if k != "pid"}}


def test_warm_workers_run_many_jobs_each():
    jobs = enumerate_jobs([suite("random", 3)], ["lazy", "gco-var"], [0, 1], time_cap_s=30.0)
    outcomes = []
    run_local(jobs, "bench_fakes:pid_job", 2, outcomes.append)
    assert sorted(o.job.key for o in outcomes) == sorted(j.key for j in jobs)
    assert {o.status for o in outcomes} == {"ok"}
    assert 1 <= len({pid_of(o) for o in outcomes}) <= 2 < len(jobs)
    assert os.getpid() not in {pid_of(o) for o in outcomes}
    for o in outcomes:  # a reused worker returns what the job function returns
        assert without_pid(o.result) == without_pid(pid_job(o.job))


@pytest.mark.parametrize("per_worker", [1, 2])
def test_workers_retire_after_jobs_per_worker(per_worker):
    jobs = enumerate_jobs([suite("maze", 6)], ["gco-var"], [0], time_cap_s=30.0)
    outcomes = []
    run_local(jobs, "bench_fakes:pid_job", 1, outcomes.append, jobs_per_worker=per_worker)
    pids = [pid_of(o) for o in outcomes]
    assert len(set(pids)) == len(jobs) // per_worker
    assert pids == [p for p in dict.fromkeys(pids) for _ in range(per_worker)]


def test_a_worker_lost_to_a_timeout_or_crash_is_replaced():
    # per scene, in this order on one worker: ok, error, ok, crash, timeout (1 s cap)
    jobs = enumerate_jobs([suite("tilt", 2)], ["gco-var", "astar", "gco-ori", "astar-replan",
                                               "lazy"], [0], time_cap_s=30.0)
    jobs = [dataclasses.replace(j, time_cap_s=1.0) if j.planner == "lazy" else j for j in jobs]
    outcomes = []
    t0 = time.monotonic()
    run_local(jobs, "bench_fakes:mixed_job", 1, outcomes.append)
    # the two sleeping jobs (a minute each) were cut at their 1 s cap: well under the 120 s
    # they would take, with room for restarting workers on a loaded machine
    assert time.monotonic() - t0 < 100.0
    assert [o.job.key for o in outcomes] == [j.key for j in jobs]
    assert [o.status for o in outcomes] == ["ok", "error", "ok", "crashed", "timeout"] * 2
    by = {(o.job.scene_name, o.job.planner): o for o in outcomes}
    for scene in ("tilt-00", "tilt-01"):
        # an exception costs the job, not the worker; a crash or a timeout costs the worker
        assert pid_of(by[scene, "gco-var"]) == pid_of(by[scene, "gco-ori"])
        assert 1.0 <= by[scene, "lazy"].wall_time_s < 10.0
        assert "exited with code 3" in by[scene, "astar-replan"].detail
    assert pid_of(by["tilt-00", "gco-var"]) != pid_of(by["tilt-01", "gco-var"])


def _comparable(result: dict) -> dict:
    """A result without what may differ between identical runs: times and wall clocks."""
    def strip(v):
        if isinstance(v, dict):
            return {k: strip(x) for k, x in v.items()
                    if not (k.endswith("_s") or "time" in k)}
        if isinstance(v, list):
            return [strip(x) for x in v]
        return v
    return strip(result)


@pytest.mark.slow  # real planning: about 3 s, most of it worker start-up
def test_real_jobs_give_the_same_result_in_a_reused_worker():
    box = scene_dict("box")
    box["objects"] = [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.7, 1.0, 0.0],
                       "goal": [1.3, 1.1, 0.5]}]
    scenes = [SuiteScene("s", scene_from_dict(box), "box.yaml")]
    lazy0, gco0, lazy1 = enumerate_jobs([scenes], ["lazy", "gco-var"], [0, 1],
                                        time_cap_s=120.0)[:3]
    warm, fresh = [], []
    run_local([lazy0, gco0, lazy1, lazy0], "lamp.bench.runner:solve_job", 1, warm.append)
    run_local([lazy0], "lamp.bench.runner:solve_job", 1, fresh.append, jobs_per_worker=1)
    assert [o.status for o in warm + fresh] == ["ok"] * 5
    assert warm[0].result["segments"] > 0
    first, again, alone = (_comparable(o.result) for o in (warm[0], warm[3], fresh[0]))
    from lamp.bench.runner import solve_job

    here = _comparable(solve_job(lazy0))  # this process: no warm-up, other tests before
    assert first == again == alone == here
    assert _comparable(warm[2].result) != first  # another seed: the comparison can tell


def _bench_process(tmp_path: Path, n_scenes: int = 2) -> tuple[subprocess.Popen, Path]:
    folder = write_suite(tmp_path, "random", n_scenes)
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = {**os.environ, "TMPDIR": str(scratch)}
    proc = subprocess.Popen(
        [sys.executable, "-c", "from lamp.cli import app; app()", "bench", "--suites",
         str(folder), "--planners", "lazy", "--workers", "2", "--out", str(tmp_path / "run"),
         "--job-fn", "bench_fakes:announce_and_sleep_job", "--no-progress"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return proc, scratch


def _worker_pids(scratch: Path, n: int, proc: subprocess.Popen) -> list[int]:
    """The pids the running jobs printed into their logs in the scratch folder."""
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline:
        pids = []
        for log in scratch.glob("lamp-bench-*/[0-9]*.log"):
            text = log.read_text()
            if text.startswith("pid "):
                pids.append(int(text.split()[1]))
        if len(pids) == n:
            return pids
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.1)
    raise AssertionError("the jobs did not start")


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_sigterm_stops_the_workers_and_removes_the_scratch_folder(tmp_path):
    proc, scratch = _bench_process(tmp_path)
    try:
        pids = _worker_pids(scratch, 2, proc)
        assert all(_alive(p) for p in pids)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 143, err
    assert "terminated" in err and "--resume" in err
    assert not any(_alive(p) for p in pids)
    assert list(scratch.iterdir()) == []  # the lamp-bench-* folder is gone
    assert read_records(tmp_path / "run" / "results.jsonl") == []


def test_workers_exit_when_lamp_bench_is_killed(tmp_path):
    proc, scratch = _bench_process(tmp_path, n_scenes=1)
    try:
        (pid,) = _worker_pids(scratch, 1, proc)
        proc.send_signal(signal.SIGKILL)  # no clean-up possible: the workers notice alone
        proc.communicate(timeout=30)
        deadline = time.monotonic() + 10.0
        while _alive(pid) and time.monotonic() < deadline:
            time.sleep(0.1)
    finally:
        proc.kill()
    assert not _alive(pid)


def test_resume_with_nothing_to_do_adds_no_run(tmp_path):
    folder = write_suite(tmp_path, "warehouse", 2)
    out = tmp_path / "run"
    args = ["bench", "--suites", str(folder), "--planners", "lazy,gco-var", "--out", str(out),
            "--job-fn", "bench_fakes:synthetic_job", "--no-progress", "--workers", "2"]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    report = (out / "report.md").read_text()
    for _ in range(2):
        res = runner.invoke(app, [*args, "--resume"])
        assert res.exit_code == 0, res.output
        assert "0 to run" in res.output
    config = json.loads((out / "config.json").read_text())
    assert len(config["sessions"]) == 1
    assert (out / "report.md").read_text() == report
    run_lines = [line for line in report.split("## Run")[1].split("##")[0].splitlines()
                 if line.startswith("- run 0: `lamp bench")]
    assert len(run_lines) == 1
    assert {r["run_id"] for r in read_records(out / "results.jsonl")} == {0}


def test_jobs_per_worker_option(tmp_path):
    folder = write_suite(tmp_path, "maze", 3)
    out = tmp_path / "run"
    res = runner.invoke(app, ["bench", "--suites", str(folder), "--planners", "gco-var",
                              "--out", str(out), "--job-fn", "bench_fakes:pid_job",
                              "--no-progress", "--workers", "1", "--jobs-per-worker", "1",
                              "--no-report"])
    assert res.exit_code == 0, res.output
    recs = read_records(out / "results.jsonl")
    assert len({r["stats"]["pid"] for r in recs}) == 3
    config = json.loads((out / "config.json").read_text())
    assert "--jobs-per-worker 1" in config["sessions"][0]["command"]
    res = runner.invoke(app, ["bench", "--suites", str(folder), "--out", str(tmp_path / "x"),
                              "--jobs-per-worker", "-1"])
    assert res.exit_code == 2


def test_a_worker_that_cannot_start_stops_the_run_with_a_message(tmp_path, monkeypatch):
    folder = write_suite(tmp_path, "random", 1)
    # the job function imports in this process but not in the workers (a broken install)
    monkeypatch.setattr(sys, "path", [str(tmp_path / "missing"), *sys.path])
    (tmp_path / "missing").mkdir()
    (tmp_path / "missing" / "vanishing_jobs.py").write_text(
        "import os\nif os.environ.get('LAMP_BENCH_TEST_WORKER'):\n    raise ImportError('gone')\n"
        "from bench_fakes import synthetic_job as job\n")
    monkeypatch.setenv("LAMP_BENCH_TEST_WORKER", "")
    import vanishing_jobs  # noqa: F401 - imported here, before the workers exist

    monkeypatch.setenv("LAMP_BENCH_TEST_WORKER", "1")
    res = runner.invoke(app, ["bench", "--suites", str(folder), "--planners", "lazy",
                              "--out", str(tmp_path / "run"), "--job-fn", "vanishing_jobs:job",
                              "--no-progress"])
    assert res.exit_code == 1, res.output
    assert "before its first job" in res.output and "gone" in res.output
