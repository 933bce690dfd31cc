"""``lamp.bench.request.BenchRequest``, the one checked form of a ``lamp bench`` invocation,
and the console options of ``lamp bench`` (``-q/--quiet``)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from test_bench import write_suite
from typer.testing import CliRunner

from lamp.bench.jobs import read_records
from lamp.bench.request import DEFAULT_SUITES, BenchRequest
from lamp.cli import app
from lamp.errors import InputError

runner = CliRunner()
FAKE = "bench_fakes:synthetic_job"


def test_a_request_is_frozen_and_normalised(tmp_path):
    folder = write_suite(tmp_path, "random", 1)
    request = BenchRequest(out=str(tmp_path / "run"), suites=[f" {folder} ", str(folder), ""],
                           planners=["lazy", "gco-var", "lazy"], rerun=["", "lazy"],
                           resume=True, params=["lazy.k=4", "gco-var.k=9",
                                                "lazy.edge_penalty=2"])
    assert request.out == tmp_path / "run" and isinstance(request.out, Path)
    assert request.suites == (str(folder),) and request.planners == ("lazy", "gco-var")
    assert request.rerun == ("lazy",)
    assert request.params == ("gco-var.k=9", "lazy.edge_penalty=2", "lazy.k=4")
    assert request.planner_params == {"gco-var": (("k", "9"),),
                                      "lazy": (("edge_penalty", "2"), ("k", "4"))}
    assert request.seed_list == [0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        request.seeds = 3  # type: ignore[misc]
    assert BenchRequest(out=tmp_path).suites == tuple(DEFAULT_SUITES.split(","))


@pytest.mark.parametrize("fields, message", [
    ({"planners": ("lazzy",)}, "--planners: unknown planner 'lazzy'; expected one of: "),
    ({"planners": ()}, "--planners: no planner given"),
    ({"rerun": ("astar",), "resume": True}, "--rerun: planner 'astar' is not in --planners"),
    ({"rerun": ("lazy",)}, "--rerun needs --resume"),
    ({"suites": ("nonsense",)}, "--suites: unknown suite 'nonsense'"),
    ({"suites": ()}, "--suites: no suite given"),
    ({"model": "magic"}, "--model: unknown model 'magic'"),
    ({"backend": "slurm"}, "--backend: unknown backend 'slurm'"),
    ({"seeds": 0}, "--num-seeds must be at least 1, got 0"),
    ({"workers": 0}, "--workers must be at least 1, got 0"),
    ({"time_cap": 0.0}, "--time-cap must be positive"),
    ({"planning_limit": -1.0}, "--planning-limit must be positive"),
    ({"scenes": 0}, "--scenes must be at least 1"),
    ({"jobs_per_worker": -1}, "--jobs-per-worker must be at least 0"),
    ({"job_fn": "nowhere:nothing"}, "--job-fn: "),
    ({"params": ("astar.k=4",)}, "planner 'astar' is not among --planners"),
    ({"disturb": "storm"}, "--disturb: unknown preset 'storm'"),
    ({"disturb": "noise-low", "planners": ("mapush",)}, "run no closed loop"),
    ({"schedule": "whenever"}, "--schedule: unknown schedule 'whenever'"),
])
def test_a_bad_request_names_the_option(tmp_path, fields, message):
    folder = write_suite(tmp_path, "random", 1)
    base = {"out": tmp_path / "run", "suites": (str(folder),), "planners": ("lazy",),
            "job_fn": FAKE}
    with pytest.raises(InputError) as err:
        BenchRequest(**{**base, **fields})
    assert message in str(err.value)


def test_the_recorded_command_line_is_the_requests(tmp_path):
    folder = write_suite(tmp_path, "random", 1)
    out = tmp_path / "run"
    res = runner.invoke(app, ["bench", "--suites", str(folder), "-p", "lazy,gco-var", "-j", "1",
                              "-o", str(out), "--job-fn", FAKE, "--no-progress",
                              "--param", "lazy.k=4", "--no-report"])
    assert res.exit_code == 0, res.output
    request = BenchRequest(out=out, suites=(str(folder),), planners=("lazy", "gco-var"),
                           workers=1, job_fn=FAKE, params=("lazy.k=4",))
    config = json.loads((out / "config.json").read_text())
    assert config["sessions"][0]["command"] == request.command_line()


def test_quiet_prints_nothing_but_writes_everything(tmp_path):
    folder = write_suite(tmp_path, "random", 2)
    args = ["bench", "--suites", str(folder), "--planners", "lazy,gco-var", "--workers", "2",
            "--job-fn", FAKE]
    loud = runner.invoke(app, [*args, "--out", str(tmp_path / "loud"), "--no-progress"])
    assert loud.exit_code == 0 and "ran 4 jobs" in loud.stdout and "wrote" in loud.stdout
    for flag in ("-q", "--quiet"):
        out = tmp_path / flag
        res = runner.invoke(app, [*args, "--out", str(out), flag])
        assert res.exit_code == 0, res.output
        assert res.stdout == "" and res.stderr == ""
        assert len(read_records(out / "results.jsonl")) == 4
        assert (out / "config.json").exists() and (out / "report.md").exists()
    res = runner.invoke(app, [*args, "--out", str(tmp_path / "dry"), "-q", "--dry-run"])
    assert res.exit_code == 0 and "4 jobs" in res.stdout  # the list is a dry run's output
    res = runner.invoke(app, [*args, "--out", str(tmp_path / "bad"), "-q", "--seeds", "0"])
    assert res.exit_code == 2 and "--num-seeds must be at least 1" in res.stderr
