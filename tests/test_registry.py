"""The planner registry: validated specs, one entry adds a planner everywhere."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest
from scenes import TINY
from typer.testing import CliRunner

import lamp
from lamp.bench import presentation, report
from lamp.bench.jobs import Job, planning_limit_applies
from lamp.pipeline import registry
from lamp.pipeline.registry import default_planning_limit, planning_limit_help
from lamp.scene import scene_from_dict

BUILT_IN = ("lazy", "astar", "astar-replan", "gco-ori", "gco-var", "mapush")

SCENE = TINY


def _lazy_factory(task):
    from lamp.planners.lazy import LazyPlanner

    return LazyPlanner.from_task(task)


DUMMY = registry.PlannerSpec(
    "dummy", "LAMP-Lazy under another name (tests)", factory=_lazy_factory,
    policy=registry.get("lazy").policy, planning_limit=42.0, bench_limited=True)
#: How the report shows ``DUMMY``: between LAMP-A*_replan (row 4) and LAMP-Lazy (5).
DUMMY_LOOK = presentation.Presentation(
    "Dummy-Lazy", row=4, color="#123456", marker="X", table_ii=True,
    paper_success={"random": 55}, paper_full_horizon={"random": 66})


@pytest.fixture
def dummy():
    """``DUMMY`` registered (and shown as ``DUMMY_LOOK``) for one test, removed after it."""
    registry.register(DUMMY)
    presentation.register("dummy", DUMMY_LOOK)
    try:
        yield DUMMY
    finally:
        presentation.unregister("dummy")
        registry.unregister("dummy")


def test_builtin_names():
    assert registry.names() == BUILT_IN


def test_builtin_specs_say_what_the_tables_said():
    assert registry.bench_limited() == ("astar", "astar-replan")
    assert "mapush" not in registry.bench_defaults()
    assert [default_planning_limit(n) for n in BUILT_IN] == [300, 500, 500, 300, 300, 300]
    assert planning_limit_help() == "300 s; 500 s for astar, astar-replan"
    assert registry.get("mapush").runner is not None and not registry.get("mapush").closed_loop
    assert all(registry.get(n).closed_loop for n in BUILT_IN[:-1])


@pytest.mark.parametrize("change, field", [
    ({"name": "Bad Name"}, "planner name"),
    ({"description": " "}, "description"),
    ({"runner": lambda *a, **k: None}, "exactly one of factory"),
    ({"factory": None}, "exactly one of factory"),
    ({"policy": None}, "policy"),
    ({"planning_limit": 0.0}, "planning_limit"),
    ({"planning_limit": float("inf")}, "planning_limit"),
    ({"params": ("no_such_field",)}, "params"),
])
def test_spec_validation_names_the_field(change, field):
    with pytest.raises(ValueError, match=field):
        replace(DUMMY, **change)


def test_spec_is_frozen_and_register_refuses_duplicates():
    with pytest.raises(AttributeError):
        DUMMY.description = "x"  # type: ignore[misc]
    with pytest.raises(ValueError, match="already registered"):
        registry.register(replace(registry.get("lazy")))
    with pytest.raises(ValueError, match="did you mean 'lazy'"):
        registry.get("lazzy")


def test_one_entry_adds_a_planner_everywhere(dummy, tmp_path):
    """Registered once, the dummy runs through ``lamp.solve`` like LAMP-Lazy (the same
    factory and policy give the same run), and the CLI, bench and report know it."""
    from lamp.manip import GeometricProposer

    scene = scene_from_dict(SCENE)
    model = GeometricProposer()
    got = lamp.solve(scene, "dummy", seed=3, model=model).to_dict()
    want = lamp.solve(scene, "lazy", seed=3, model=model).to_dict()
    assert got["planner"] == "dummy" and got["success"]
    assert got["objects"][0]["final_pose"] == want["objects"][0]["final_pose"]
    assert got["segments"] == want["segments"] and got["makespan"] == want["makespan"]
    assert registry.get("dummy").default_config().loop.planning_time_limit == 42.0
    assert type(registry.get("dummy").factory(_task(scene, model))).__name__ == "LazyPlanner"

    # bench: --planning-limit applies, the name is accepted
    assert planning_limit_applies("dummy") and not planning_limit_applies("lazy")
    job = Job("random", "tiny", "x.json", scene, "dummy", 0, planning_limit_s=7.0)
    assert job.time_limit == 7.0
    from lamp.cli import app

    res = CliRunner().invoke(app, ["bench", "--suites", "iros", "--planners", "dummy",
                                   "--out", str(tmp_path / "b"), "--dry-run"])
    assert res.exit_code == 0, res.output

    # report: a row in Tables I and II, between LAMP-A*_replan (row 4) and LAMP-Lazy (5)
    records = [{**r, "suite": "random", "status": "ok", "seed": 0}
               for r in (got, want, {**want, "planner": "astar-replan"})]
    table = report.success_table(records)
    assert list(table) == ["astar-replan", "dummy", "lazy"]
    assert table["dummy"]["random"].cell() == report.Rate(1, 1).cell()
    md = report.success_markdown(table, ["random"])
    line = next(x for x in md.splitlines() if x.startswith("| Dummy-Lazy"))
    assert "[paper 55%]" in line
    fh = report.full_horizon_markdown(report.full_horizon_table(records), ["random"])
    assert "| Dummy-Lazy" in fh and "[paper 66%]" in fh
    assert presentation.color("dummy") == "#123456" and presentation.marker("dummy") == "X"

    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    text = report.build_report(run_dir).read_text()
    assert "Dummy-Lazy" in text


def test_unregister_undoes_it(dummy):
    presentation.unregister("dummy")
    registry.unregister("dummy")
    try:
        assert "dummy" not in registry.names()
        with pytest.raises(ValueError, match="unknown planner 'dummy'"):
            lamp.solve(scene_from_dict(SCENE), "dummy")
        assert presentation.label("dummy") == "dummy"  # old results still render
    finally:
        registry.register(DUMMY)
        presentation.register("dummy", DUMMY_LOOK)


def _task(scene, model):
    import numpy as np

    from lamp.planners.config import PlannerConfig
    from lamp.planners.task import ManipulationTask

    poses = np.array([o.start for o in scene.objects], float)
    return ManipulationTask(scene, 0, poses, model, PlannerConfig(), seed=0)


def test_an_object_runner_replaces_the_loop(tmp_path):
    """A planner with a ``runner`` gets the scene and parameters, moves each object in the
    pipeline's schedule; its ``check_scene`` guards the CLI before anything is written."""
    from lamp.contract.goals import goal_errors
    from lamp.contract.result import ObjectResult
    from lamp.contract.runner import ObjectOutcome

    calls = []

    class StandStill:
        """Moves nothing: each object ends where it is."""

        row_dt_s = 0.08

        def __init__(self, scene, config):
            calls.append((scene.name, config.loop.planning_time_limit))

        def run_object(self, index, executor, observe):
            pose = [float(v) for v in executor.object_poses[index]]
            goal = list(SCENE["objects"][index]["goal"])
            dt, dr = goal_errors(pose, goal)
            calls.append(("object", index))
            return ObjectOutcome(ObjectResult(False, pose, goal, dt, dr, False, 0, False,
                                              "stood still"))

        def run_stats(self, outcomes):
            return {"objects": len(outcomes)}

    def check(scene):
        if scene.name != "tiny":
            raise ValueError("planner whole: only the tiny scene")

    registry.register(registry.PlannerSpec("whole", "object-runner test planner",
                                           runner=StandStill, check_scene=check,
                                           uses_model=False))
    try:
        res = lamp.solve(scene_from_dict(SCENE), "whole", seed=5, model="geometric",
                         time_limit=9.0)
        assert calls == [("tiny", 9.0), ("object", 0)] and res.planner == "whole"
        assert res.stats == {"objects": 1} and not res.success and res.segments == 0
        assert res.objects[0].failure_reason == "stood still"
        from lamp.cli import app

        other = tmp_path / "other.json"
        other.write_text(json.dumps({**SCENE, "name": "other"}))
        out = tmp_path / "out"
        res = CliRunner().invoke(app, ["run", str(other), "-p", "whole", "-o", str(out)])
        assert res.exit_code == 2 and "only the tiny scene" in res.stderr
        assert not (out / "result.json").exists()
    finally:
        registry.unregister("whole")
