"""The run pipeline: the request is validated before anything runs, the declared
parameters are parsed and checked, observers only watch, and the result agrees with the
recording (``makespan_s`` is its last time)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scenes import TINY
from typer.testing import CliRunner

from lamp.cli import app
from lamp.contract.params import (
    apply_overrides,
    format_value,
    infos,
    param_table,
    parse_assignments,
    parse_value,
)
from lamp.errors import InputError
from lamp.manip import GeometricProposer
from lamp.pipeline import RunRequest, registry, run
from lamp.pipeline.execute import execute
from lamp.pipeline.request import param_names
from lamp.planners.config import PlannerConfig
from lamp.scene import SceneError, scene_from_dict

SCENE = TINY
INFOS = infos(PlannerConfig)


@pytest.fixture(scope="module")
def scene():
    return scene_from_dict(SCENE)


# ----------------------------------------------------------------------------- parameters
def test_every_planner_config_field_is_a_group_of_declared_parameters():
    """``PlannerConfig`` is made of its groups only; every field of every group is a
    declared parameter, each declared once, and every planner reads declared ones."""
    import dataclasses

    groups = [f.default_factory for f in dataclasses.fields(PlannerConfig)]
    fields = [f.name for g in groups for f in dataclasses.fields(g)]
    assert sorted(fields) == sorted(INFOS) and len(fields) == len(set(fields))
    for spec in registry.specs():
        assert set(spec.params) <= set(INFOS), spec.name


@given(st.sampled_from(sorted(INFOS)), st.data())
def test_parse_reads_back_what_format_writes(name, data):
    info = INFOS[name]
    if info.kind is int:
        value = data.draw(st.integers(min_value=int(info.low or 0) + 1, max_value=10**6))
    else:
        lo = float(info.low or 0.0)
        value = data.draw(st.floats(min_value=lo + 1e-3, max_value=1e6, allow_nan=False))
    if info.optional and data.draw(st.booleans()):
        value = None
    text = format_value(value) if not isinstance(value, float) else repr(value)
    assert parse_value(info, text) == value


@pytest.mark.parametrize(("name", "text", "rule"), [
    ("k", "0", "an integer >= 1"),
    ("k", "2.5", "an integer >= 1"),
    ("drift_position", "-0.1", "> 0"),
    ("drift_position", "nan", "a finite number > 0"),
    ("max_plan_iterations", "many", "an integer >= 1"),
    ("max_segments", "0", ">= 1 or none"),
])
def test_bad_values_are_refused_by_name(name, text, rule):
    with pytest.raises(InputError, match=rf"lazy\.{name}: .*{rule}.*got {text!r}"):
        apply_overrides(PlannerConfig(), registry.get("lazy").params, {name: text}, "lazy")


def test_a_parameter_the_planner_does_not_read_is_refused():
    with pytest.raises(InputError, match="planner gco-var: no parameter 'max_plan_iterations'; "
                                         "it reads: planning_time_limit"):
        apply_overrides(PlannerConfig(), registry.get("gco-var").params,
                        {"max_plan_iterations": 3}, "gco-var")
    got = apply_overrides(PlannerConfig(), registry.get("lazy").params,
                          {"max_plan_iterations": "7", "max_segments": "none", "k": 4}, "lazy")
    assert (got.lazy.max_plan_iterations, got.loop.max_segments, got.verify.k) == (7, None, 4)


def test_planner_config_validates_every_field_on_construction():
    with pytest.raises(InputError, match="LazyConfig.edge_penalty"):
        PlannerConfig.of(edge_penalty=-1.0)
    assert PlannerConfig.of(planning_time_limit=math.inf).loop.planning_time_limit == math.inf
    assert isinstance(PlannerConfig.of(planning_time_limit=20).loop.planning_time_limit, float)


@pytest.mark.parametrize("text", ["lazy", "lazy.k", "k=3", ".k=3", "lazy.=3"])
def test_assignments_need_planner_name_and_value(text):
    with pytest.raises(InputError, match="--param: expected PLANNER.NAME=VALUE"):
        parse_assignments([text])
    assert parse_assignments(["astar.astar_heuristic_weight = 2"]) == [
        ("astar", "astar_heuristic_weight", "2")]


def test_param_table_lists_what_the_planner_reads():
    spec = registry.get("astar")
    rows = param_table(spec.default_config(), spec.params)
    assert [r[0] for r in rows] == list(spec.params)
    assert rows[0][:3] == ("planning_time_limit", "500", "a number (inf allowed) > 0")


# ------------------------------------------------------------------------------- request
def test_request_is_validated_before_anything_runs(scene):
    with pytest.raises(InputError, match="unknown planner 'lazzy'.*did you mean 'lazy'"):
        RunRequest(scene, "lazzy")
    with pytest.raises(InputError, match="seed: an integer"):
        RunRequest(scene, "lazy", seed=1.5)
    with pytest.raises(InputError, match="unknown model 'learnt'"):
        RunRequest(scene, "lazy", model="learnt")
    small = scene_from_dict({**SCENE, "robots": {**SCENE["robots"], "radius": 0.08}})
    with pytest.raises(SceneError, match="robots.radius: the manipulation model makes "
                                         "contacts for robots of radius 0.05"):
        RunRequest(small, "lazy")
    req = RunRequest.build(scene, "astar", 3, model="geometric",
                           params={"astar_heuristic_weight": "2"}, planning_limit=7,
                           max_segments=5)
    assert req.params.astar.astar_heuristic_weight == 2.0
    assert (req.params.loop.planning_time_limit, req.params.loop.max_segments) == (7.0, 5)
    assert "astar_heuristic_weight=2" in req.describe()
    with pytest.raises(InputError, match="planning_time_limit"):
        RunRequest.build(scene, "lazy", planning_limit=0)


def test_built_in_scene_names_resolve():
    req = RunRequest.build("maze-07", "gco-var", model="geometric")
    assert req.scene.name == "maze-07"


# ---------------------------------------------------------------------------------- runs
class Log:
    """Records what an observer is told."""

    def __init__(self):
        self.calls = []

    def object_started(self, index, n):
        self.calls.append(("start", index, n))

    def segment(self, event):
        self.calls.append(("segment", event.object_index, event.segment))

    def object_finished(self, index, n, result):
        self.calls.append(("done", index, result.segments))


def _untimed(d):
    if isinstance(d, dict):
        return {k: _untimed(v) for k, v in d.items()
                if "planning_time" not in k and "wall" not in k}
    return [_untimed(v) for v in d] if isinstance(d, list) else d


def test_observers_watch_in_order_and_change_nothing(scene):
    req = RunRequest(scene, "lazy", 0, GeometricProposer())
    log = Log()
    a = execute(req, [log])
    b = execute(req)
    assert _untimed(a.to_dict()) == _untimed(b.to_dict())
    segs = a.segments
    assert log.calls[0] == ("start", 0, 1) and log.calls[-1] == ("done", 0, segs)
    assert [c for c in log.calls if c[0] == "segment"] == [("segment", 0, i) for i in range(segs)]


def test_result_agrees_with_its_recording(scene):
    res = run(RunRequest(scene, "lazy", 2, GeometricProposer(),
                         PlannerConfig.of(max_plan_iterations=300)))
    d = res.to_dict()
    rec = res.recording
    assert d["success"] and d["segments"] == rec.n_segments >= 1
    assert d["makespan_s"] == pytest.approx(float(rec.arrays["times"][-1]), abs=1e-6)
    assert d["makespan_s"] == pytest.approx(float(np.sum(rec.arrays["sim_time_s"])), abs=1e-6)
    assert d["params"]["max_plan_iterations"] == 300
    assert set(d["params"]) == set(param_names(registry.get("lazy")))
    assert rec.result["makespan_s"] == d["makespan_s"]


# ------------------------------------------------------------------------------------ CLI
def test_cli_help_params_and_param(tmp_path):
    runner = CliRunner()
    res = runner.invoke(app, ["run", "--planner", "astar", "--help-params"],
                        env={"COLUMNS": "200"})
    assert res.exit_code == 0, res.output
    assert "astar_heuristic_weight" in res.output and "max_verify_calls" not in res.output
    scene_file = tmp_path / "tiny.json"
    scene_file.write_text(json.dumps(SCENE))
    out = tmp_path / "out"
    for bad, message in ((["--param", "lazy.nope=1"], "no parameter 'nope'"),
                         (["--param", "astar.k=3"], "names planner 'astar'"),
                         (["--param", "lazy.k=0"], "lazy.k: an integer >= 1")):
        res = runner.invoke(app, ["run", str(scene_file), "-o", str(out), *bad])
        assert res.exit_code == 2 and message in res.stderr, res.output
        assert not out.exists()
    res = runner.invoke(app, ["run", str(scene_file), "-o", str(out), "-m", "geometric", "-q",
                              "--param", "lazy.max_plan_iterations=250"])
    assert res.exit_code == 0, res.output
    result = json.loads((out / "result.json").read_text())
    assert result["params"]["max_plan_iterations"] == 250


def test_one_handler_turns_library_input_errors_into_exit_2(tmp_path, monkeypatch):
    """An InputError raised deep in the library (here: by the run itself) is reported by
    the command group as ``error: ...`` with exit 2, the output folder left unwritten."""
    import lamp.pipeline.execute as execute_mod

    def refuse(request):
        raise InputError("objects[0].size: too thin for the planners")

    monkeypatch.setattr(execute_mod, "object_runner", refuse)
    scene_file = tmp_path / "tiny.json"
    scene_file.write_text(json.dumps(SCENE))
    res = CliRunner().invoke(app, ["run", str(scene_file), "-o", str(tmp_path / "o"),
                                   "-m", "geometric"])
    assert res.exit_code == 2
    assert res.stderr.strip() == "error: objects[0].size: too thin for the planners"
    assert not (tmp_path / "o").exists()
