"""The top-level Python API: ``lamp.solve``, ``load_scene`` / ``scene_from_dict`` /
``save_scene``, ``SceneError``, the result's figures and repr, ``py.typed``."""

from __future__ import annotations

import inspect
import json
import typing
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import lamp
from lamp.contract.result import ObjectResult, RunResult
from lamp.pipeline.registry import names

DATA = Path(__file__).parent / "data"


def small_scene_dict() -> dict:
    return {
        "format": "lamp-scene/1", "name": "small", "workspace": [2.2, 2.0],
        "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
        "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                     "goal": [1.15, 1.0, 0.0]}],
    }


def without_times(d: dict) -> dict:
    drop = {"planning_time_s", "total_planning_time_s", "median_planning_time_s",
            "wall_time_s", "executed_planning_time_s", "unexecuted_planning_time_s",
            "planning_time_per_segment_s"}
    d = {k: v for k, v in d.items() if k not in drop}
    d["objects"] = [{k: v for k, v in o.items() if k != "planning_time_s"} for o in d["objects"]]
    d["stats"] = {k: v for k, v in d["stats"].items() if not k.endswith("_time_s")}
    return d


def test_solve_accepts_a_path_and_reports_progress(tmp_path: Path) -> None:
    path = tmp_path / "small.yaml"
    lamp.save_scene(lamp.scene_from_dict(small_scene_dict()), path)
    events = []
    by_path = lamp.solve(path, "lazy", 0, model="geometric", progress=events.append)
    by_scene = lamp.solve(lamp.load_scene(path), "lazy", 0, model="geometric")
    assert by_path.success
    assert without_times(by_path.to_dict()) == without_times(by_scene.to_dict())
    kinds = [e.kind for e in events if e.kind not in ("compiling", "compiled")]
    assert kinds == ["object", *["segment"] * by_path.segments, "object-done"]
    assert [e.segments for e in events if e.kind == "segment"] == list(
        range(1, by_path.segments + 1))


def test_solve_rejects_bad_input_clearly(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    d = small_scene_dict()
    d["objects"][0]["size"] = [0.3, -0.2]
    bad.write_text(json.dumps(d))
    with pytest.raises(lamp.SceneError) as info:
        lamp.solve(bad)
    assert info.value.path == str(bad) and info.value.field == "objects[0].size[1]"
    scene = lamp.scene_from_dict(small_scene_dict())
    with pytest.raises(ValueError, match="did you mean 'astar'"):
        lamp.solve(scene, "astr")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="no such checkpoint"):
        lamp.solve(scene, model=str(tmp_path / "none.pt"))


def test_solve_signature_and_docstring() -> None:
    params = inspect.signature(lamp.solve).parameters
    assert list(params) == ["scene", "planner", "seed", "model", "config", "params",
                            "time_limit", "max_segments", "disturbances", "schedule", "progress"]
    assert all(p.annotation is not inspect.Parameter.empty for p in params.values())
    assert params["planner"].default == "lazy" and params["seed"].default == 0
    for name in names():
        assert f'"{name}"' in lamp.solve.__doc__
    hints = typing.get_type_hints(lamp.solve)
    assert hints["planner"] is str  # the names are the registry's alone
    assert hints["return"] is RunResult


def test_top_level_exports_and_py_typed() -> None:
    for name in ("Scene", "SceneError", "load_scene", "scene_from_dict", "save_scene", "solve",
                 "__version__"):
        assert name in lamp.__all__ and hasattr(lamp, name)
    assert (Path(lamp.__file__).parent / "py.typed").is_file()
    pyproject = Path(__file__).parents[1] / "pyproject.toml"
    assert '"py.typed"' in pyproject.read_text()  # shipped in the wheel


def _some_scenes() -> list[lamp.Scene]:
    from lamp.suites.registry import SUITES, suite_scenes

    scenes = [lamp.load_scene(DATA / "spec_example.yaml"), lamp.load_scene(DATA / "minimal.json")]
    for name in SUITES:
        scenes.extend(suite_scenes(name)[:4])
    return scenes


SCENES = _some_scenes()


@settings(max_examples=40, deadline=None)
@given(scene=st.sampled_from(SCENES), suffix=st.sampled_from([".yaml", ".yml", ".json"]))
def test_save_scene_round_trips(tmp_path_factory, scene: lamp.Scene, suffix: str) -> None:
    path = tmp_path_factory.mktemp("s") / f"scene{suffix}"
    assert lamp.save_scene(scene, path) == path
    again = lamp.load_scene(path)
    assert again == scene and again.source == str(path)
    if suffix == ".json":
        assert json.loads(path.read_text())["format"] == "lamp-scene/1"


def test_save_scene_refuses_unknown_extensions(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"\.txt"):
        lamp.save_scene(SCENES[0], tmp_path / "scene.txt")
    assert list(tmp_path.iterdir()) == []


def _result(times: list[float], unexecuted: float) -> RunResult:
    obj = ObjectResult(success=True, final_pose=[0, 0, 0], goal=[0, 0, 0], position_error=0.0,
                       orientation_error=0.0, left_workspace=False, segments=len(times),
                       full_horizon_plan=True)
    return RunResult(scene="s", planner="lazy", seed=3, objects=[obj], planning_time_s=times,
                     unexecuted_planning_time_s=unexecuted)


@given(times=st.lists(st.floats(0, 100), max_size=300), unexecuted=st.floats(0, 100))
def test_planning_time_figures(times: list[float], unexecuted: float) -> None:
    from lamp.bench.report import scenario_planning_time

    r = _result(times, unexecuted)
    d = r.to_dict()
    assert d["total_planning_time_s"] == pytest.approx(sum(times) + unexecuted, abs=1e-5)
    assert d["executed_planning_time_s"] == pytest.approx(sum(times), abs=1e-5)
    assert d["unexecuted_planning_time_s"] == pytest.approx(unexecuted, abs=1e-6)
    if times:
        per = scenario_planning_time(d, float("inf"))[0]  # the bench report's figure
        assert d["planning_time_per_segment_s"] == pytest.approx(per, rel=1e-6, abs=1e-6)
    else:
        assert d["planning_time_per_segment_s"] is None
    text = repr(r)
    assert len(text) < 200 and "scene='s'" in text and f"segments={len(times)}" in text


def test_warm_up_runs_once_per_process() -> None:
    from lamp.pipeline.warmup import ensure_warm

    ensure_warm()
    again = ensure_warm()
    assert (again.seconds, again.compiled) == (0.0, 0)
    from lamp.pipeline.warmup import warm_up

    events: list = []
    report = warm_up(events.append)  # everything is compiled now: nothing to announce
    assert events == [] and report.compiled == 0 and report.compile_s == 0.0


def test_errors_raised_on_purpose_are_lamp_errors() -> None:
    """A mistyped planner is an InputError (still a ValueError); model and recording
    errors are LampErrors; an unknown scene name is a SceneError naming it."""
    from lamp.errors import InputError, LampError
    from lamp.manip.models import ModelError
    from lamp.record.format import RecordingError

    assert issubclass(ModelError, InputError) and issubclass(RecordingError, InputError)
    assert issubclass(InputError, LampError) and issubclass(InputError, ValueError)
    with pytest.raises(InputError, match="did you mean 'lazy'"):
        lamp.solve("maze-07", "lazzy")
    with pytest.raises(lamp.SceneError, match="maze-99x"):
        lamp.solve("maze-99x")


def test_top_level_namespace_is_the_public_api() -> None:
    assert dir(lamp) == sorted(lamp.__all__)
    assert all(hasattr(lamp, name) for name in lamp.__all__)


def test_progress_counts_the_objects_done_and_moving_in_a_concurrent_run() -> None:
    """Each event counts the objects finished and moving so far (as its own events
    replayed in order say); with two moving at once a description names both counts,
    and a run of one object after another reads as before."""
    scene = lamp.scene_from_dict({
        "format": "lamp-scene/1", "name": "two", "workspace": [6.0, 4.0],
        "schedule": "concurrent",
        "robots": {"radius": 0.05, "starts": [[1.0, 0.4], [1.2, 0.4], [1.4, 0.4],
                                              [4.6, 0.4], [4.8, 0.4], [5.0, 0.4]]},
        "obstacles": [],
        "objects": [{"type": "rectangle", "size": [0.4, 0.4], "start": [1.5, 1.2, 0.0],
                     "goal": [1.5, 2.6, 0.0]},
                    {"type": "rectangle", "size": [0.4, 0.4], "start": [4.5, 1.2, 0.0],
                     "goal": [4.5, 2.6, 0.0]}]})
    for schedule in ("concurrent", "sequential"):
        events = []
        result = lamp.solve(scene, "lazy", 0, schedule=schedule, progress=events.append)
        assert result.success
        events = [e for e in events if e.kind not in ("compiling", "compiled")]
        moving, done = set(), 0
        for e in events:  # the reference: the events themselves, replayed
            if e.kind == "object":
                moving.add(e.object_index)
            elif e.kind == "object-done":
                moving.discard(e.object_index)
                done += 1
            assert (e.done, e.moving) == (done, len(moving))
        assert done == 2
        both = [e for e in events if e.moving == 2]
        if schedule == "concurrent":
            assert any(e.kind == "segment" for e in both)
            assert all(f"({e.done}/2 done, 2 moving)" in e.describe() for e in both)
        else:
            assert not both and not any("moving" in e.describe() for e in events)
