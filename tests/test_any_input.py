"""Every input ends in exit status 0 or 2: ``lamp run`` on scene files with one field changed.

A Hypothesis property: take a small valid scene (two objects, one waiting for the other, so
that both schedules and ``after`` are exercised), set one field anywhere in it (physics,
robots, obstacles, objects, ``after``, ``schedule``) to a value drawn from the awkward ones
(zero, negative, tiny, huge, non-finite, wrong types), and run ``lamp run`` with tiny limits.
The run either refuses the file (2, naming the field) or runs it (0, whatever the result);
an internal error (1) or a traceback is a failure. MuJoCo's log file never lands in the
working folder.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from lamp.cli import app

runner = CliRunner()


def base_scene(schedule: str) -> dict[str, Any]:
    return {
        "format": "lamp-scene/1", "name": "fuzz", "workspace": [2.2, 1.6],
        "schedule": schedule,
        "physics": {"contact_friction": 0.5, "ground_damping": 30.0},
        "robots": {"radius": 0.05, "speed": 0.25, "force_limit": 60.0,
                   "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9], [0.2, 1.2]]},
        "obstacles": [{"type": "circle", "center": [1.9, 0.3], "radius": 0.1},
                      {"type": "rectangle", "center": [1.1, 1.45], "size": [0.4, 0.1],
                       "angle": 0.0}],
        "objects": [
            {"type": "rectangle", "size": [0.3, 0.2], "start": [0.7, 0.5, 0.0],
             "goal": [1.3, 0.6, 0.0], "mass": 1.0, "friction": 0.5},
            {"type": "circle", "radius": 0.12, "start": [0.7, 1.1, 0.0],
             "goal": [1.5, 1.0, 0.0], "after": [0]},
        ],
    }


#: Every field of the base scene a mutation may set, as a path of keys and indices.
FIELDS: list[tuple[Any, ...]] = [
    ("workspace", 0), ("workspace", 1), ("schedule",),
    ("physics", "contact_friction"), ("physics", "ground_damping"),
    ("robots", "radius"), ("robots", "speed"), ("robots", "force_limit"),
    ("robots", "starts", 0, 0), ("robots", "starts", 1, 1),
    ("obstacles", 0, "radius"), ("obstacles", 0, "center", 0),
    ("obstacles", 1, "size", 0), ("obstacles", 1, "size", 1), ("obstacles", 1, "angle"),
    ("objects", 0, "size", 0), ("objects", 0, "size", 1),
    ("objects", 0, "start", 0), ("objects", 0, "start", 2),
    ("objects", 0, "goal", 1), ("objects", 0, "goal", 2),
    ("objects", 0, "mass"), ("objects", 0, "friction"),
    ("objects", 1, "radius"), ("objects", 1, "start", 2), ("objects", 1, "goal", 2),
    ("objects", 1, "after"), ("objects", 1, "after", 0), ("objects", 0, "after"),
]

NUMBERS = st.sampled_from([
    0.0, -1.0, 1e-300, 1.192092896e-07, 1e-4, 0.01, 0.05, 0.3, 2.0, 2.5, 7.0, 100.0, 1e4,
    1e12, 1e308, -1e308, math.inf, -math.inf, math.nan, 1, 0, -1, 3,
])
OTHERS = st.sampled_from([None, True, "x", "concurrent", "sequential", [], [0], [1], [0, 1],
                          [5], {"a": 1}])
VALUES = st.one_of(NUMBERS, NUMBERS, OTHERS)


def mutated(d: dict[str, Any], path: tuple[Any, ...], value: Any) -> dict[str, Any]:
    out = copy.deepcopy(d)
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("any-input")


@settings(max_examples=120, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(schedule=st.sampled_from(["sequential", "concurrent"]), path=st.sampled_from(FIELDS),
       value=VALUES)
def test_lamp_run_ends_in_0_or_2(workdir: Path, monkeypatch: pytest.MonkeyPatch,
                                 schedule: str, path: tuple[Any, ...], value: Any) -> None:
    monkeypatch.chdir(workdir)
    scene = workdir / "scene.json"
    scene.write_text(json.dumps(mutated(base_scene(schedule), path, value), allow_nan=True))
    res = runner.invoke(app, ["run", str(scene), "--model", "geometric", "--max-segments", "2",
                              "--planning-limit", "5", "--quiet", "--out",
                              str(workdir / "out")])
    detail = f"{path} = {value!r} ({schedule}): exit {res.exit_code}\n{res.output}"
    assert res.exit_code in (0, 2), detail
    if not isinstance(res.exception, SystemExit):
        assert res.exception is None, detail
    if res.exit_code == 2:
        assert "error" in res.output.lower(), detail
    assert not (workdir / "MUJOCO_LOG.TXT").exists(), detail


@pytest.mark.parametrize(("path", "value"), [
    (("robots", "speed"), 1.192092896e-07),      # once allocated 199 GiB
    (("objects", 0, "start", 2), 1e308),          # once sent MuJoCo to NaN and exited 0
    (("objects", 0, "mass"), 1e-300),
])
def test_found_cases_are_refused_by_name(workdir: Path, monkeypatch: pytest.MonkeyPatch,
                                         path: tuple[Any, ...], value: float) -> None:
    monkeypatch.chdir(workdir)
    scene = workdir / "found.json"
    scene.write_text(json.dumps(mutated(base_scene("sequential"), path, value)))
    res = runner.invoke(app, ["run", str(scene), "--model", "geometric", "--max-segments", "1",
                              "--quiet", "--out", str(workdir / "found-out")])
    assert res.exit_code == 2, res.output
    field = ".".join(str(p) for p in path[:2]) if path[0] != "objects" else "objects[0]"
    assert field in res.output, res.output


def test_an_unstable_simulation_is_an_error_naming_the_step(
        workdir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Past the loader's bounds (an object placed by the API with a heading of 1e300),
    MuJoCo resets the state it cannot integrate; the simulator raises instead of
    reporting the reset poses, and MuJoCo's log file is not written."""
    from lamp.scene import scene_from_dict
    from lamp.sim import Simulator
    from lamp.sim.stability import SimulationError

    monkeypatch.chdir(workdir)
    sim = Simulator(scene_from_dict(base_scene("sequential")))
    poses = sim.object_poses
    poses[0, 2] = 1e300
    sim.set_state(object_poses=poses)
    still = sim.robot_positions[:, None].repeat(3, axis=1)
    with pytest.raises(SimulationError, match=r"unstable within the first \d+ physics steps"):
        sim.execute(still)
    assert not (workdir / "MUJOCO_LOG.TXT").exists()


def test_a_failed_predecessor_fails_its_followers_by_name() -> None:
    """``after: [0]`` under the concurrent schedule, object 0 out of segments: object 1 is
    not started and fails naming object 0; the run ends normally (it once raised "no
    object can move and none waits")."""
    import lamp

    result = lamp.solve(lamp.scene_from_dict(base_scene("concurrent")), model="geometric",
                        max_segments=1)
    first, second = result.objects
    assert not first.success
    assert not second.success and second.segments == 0
    assert "object 0, which it waits for (after), was not placed" in second.failure_reason
