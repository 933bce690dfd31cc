"""Lifelong scenes: tasks in the scene file, the fleet serving them as they are released,
and the run's tasks and figures in result.json."""

from __future__ import annotations

import copy
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from run_safety import assert_safe

import lamp
from lamp.contract.goals import SUCCESS_POSITION_TOL
from lamp.contract.result import ObjectResult
from lamp.contract.runner import ObjectOutcome
from lamp.errors import InputError
from lamp.fleet.config import FleetConfig
from lamp.fleet.coordinator import Fleet
from lamp.fleet.tasks import (
    TASK_MOVES,
    ScheduledFeed,
    TaskRecord,
    TaskStatus,
    lifelong_figures,
    merged_tasks,
)
from lamp.pipeline import RunRequest
from lamp.scene import SceneError, scene_from_dict
from lamp.scene.model import Task
from lamp.scene.tasks import chain_lower_bound, numbered, served_order

#: Two objects in an open hall, four robots; object 0 goes on to a second goal at 5 s,
#: object 1 to a third place at 40 s (after idling).
HALL = {
    "format": "lamp-scene/1", "name": "hall-tasks", "workspace": [6.0, 4.0],
    "robots": {"starts": [[0.5, 0.5], [0.5, 1.0], [0.5, 3.0], [0.5, 3.5]]},
    "objects": [
        {"type": "circle", "radius": 0.25, "start": [2.0, 1.0, 0.0], "goal": [4.0, 1.0, 0.0]},
        {"type": "rectangle", "size": [0.5, 0.4], "start": [2.0, 3.0, 0.0],
         "goal": [4.0, 3.0, 0.0]},
    ],
    "obstacles": [{"type": "rectangle", "center": [3.0, 2.0], "size": [1.0, 0.2]}],
    "tasks": [
        {"object": 0, "goal": [2.0, 1.5, 0.0], "release_s": 5.0},
        {"object": 1, "goal": [5.0, 2.8, 0.0], "release_s": 40.0},
    ],
}


def hall(**changes: Any) -> dict[str, Any]:
    d = copy.deepcopy(HALL)
    d.update(changes)
    return d


# ----------------------------------------------------------------------------- the file


def test_tasks_load_default_to_the_fleet_and_round_trip() -> None:
    scene = scene_from_dict(hall())
    assert scene.schedule == "concurrent"
    assert scene.tasks == (Task(0, (2.0, 1.5, 0.0), 5.0), Task(1, (5.0, 2.8, 0.0), 40.0))
    assert scene_from_dict(scene.to_dict()) == scene
    sequential = scene_from_dict(hall(schedule="sequential"))
    assert sequential.schedule == "sequential"
    assert scene_from_dict(sequential.to_dict()).schedule == "sequential"
    no_release = hall(tasks=[{"object": 1, "goal": [5.0, 2.8, 0.0]}])
    assert scene_from_dict(no_release).tasks[0].release_s == 0.0


@pytest.mark.parametrize(("task", "field", "words"), [
    ({"object": 2, "goal": [1, 1, 0]}, "tasks[0].object", "no object 2"),
    ({"object": -1, "goal": [1, 1, 0]}, "tasks[0].object", "no object -1"),
    ({"object": 0.5, "goal": [1, 1, 0]}, "tasks[0].object", "an object index"),
    ({"object": True, "goal": [1, 1, 0]}, "tasks[0].object", "an object index"),
    ({"object": "0", "goal": [1, 1, 0]}, "tasks[0].object", "an object index"),
    ({"object": float("inf"), "goal": [1, 1, 0]}, "tasks[0].object", "an object index"),
    ({"object": 0}, "tasks[0].goal", "missing"),
    ({"object": 0, "goal": [1, 1]}, "tasks[0].goal", "3 numbers"),
    ({"object": 0, "goal": [5.9, 1, 0]}, "tasks[0].goal", "outside the workspace"),
    ({"object": 0, "goal": [3.0, 2.0, 0]}, "tasks[0].goal", "overlaps obstacles[0]"),
    ({"object": 0, "goal": [1, 1, 0], "release_s": -1}, "tasks[0].release_s", ">= 0"),
    ({"object": 0, "goal": [1, 1, 0], "release_s": float("nan")}, "tasks[0].release_s",
     "finite"),
    ({"object": 0, "goal": [1, 1, 0], "when": 3}, "tasks[0].when", "unknown key"),
])
def test_a_bad_task_is_refused_naming_its_field(task: dict, field: str, words: str) -> None:
    with pytest.raises(SceneError) as err:
        scene_from_dict(hall(tasks=[task]))
    assert err.value.field == field and words in err.value.reason


def test_lamp_validate_exits_2_naming_the_task(tmp_path) -> None:
    import yaml
    from typer.testing import CliRunner

    from lamp.cli import app

    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(hall(tasks=[{"object": 7, "goal": [1, 1, 0]}])))
    out = CliRunner().invoke(app, ["validate", str(path)])
    assert out.exit_code == 2 and "tasks[0].object" in out.output


def test_tasks_are_numbered_own_goals_first_and_served_by_release() -> None:
    scene = scene_from_dict(hall(tasks=[
        {"object": 1, "goal": [5.0, 2.8, 0.0], "release_s": 9.0},
        {"object": 0, "goal": [2.0, 1.5, 0.0], "release_s": 3.0},
        {"object": 0, "goal": [4.0, 1.0, 0.0], "release_s": 3.0}]))
    tasks = numbered(scene)
    assert [t.object for t in tasks] == [0, 1, 1, 0, 0]
    assert served_order(scene) == [0, 1, 3, 4, 2]


def test_chain_bound_follows_each_object_s_tasks() -> None:
    scene = scene_from_dict(hall())
    v = scene.physics.robot_speed
    tol = SUCCESS_POSITION_TOL
    later = list(scene.tasks)
    # object 0: own goal by 10 s, then 0.5 m; object 1: by 1 s, then 1.02 m from 40 s
    bound = chain_lower_bound(scene, [10.0, 1.0], later)
    want = max(10.0 + (0.5 - 2 * tol) / v, 40.0 + (np.hypot(1.0, 0.2) - 2 * tol) / v)
    assert bound == pytest.approx(want)
    assert chain_lower_bound(scene, [10.0, 1.0], []) == 10.0


def test_a_lifelong_scene_needs_a_closed_loop_planner() -> None:
    with pytest.raises(InputError, match="closed-loop"):
        RunRequest.build(scene_from_dict(hall(schedule="sequential")), "mapush")


# ----------------------------------------------------------------------------- records


def test_task_moves_follow_the_table_and_times_are_kept() -> None:
    t = TaskRecord(3, 0, (1.0, 1.0, 0.0), 2.0)
    with pytest.raises(ValueError, match="task 3"):
        t.move_to(TaskStatus.DONE, 1.0)
    assert t.status is TaskStatus.QUEUED
    t.move_to(TaskStatus.ACTIVE, 4.0)
    t.move_to(TaskStatus.DONE, 9.5)
    assert (t.start_s, t.done_s, t.service_s) == (4.0, 9.5, 7.5)
    for s in TaskStatus:
        with pytest.raises(ValueError):
            t.move_to(s, 10.0)
    assert TASK_MOVES[TaskStatus.DONE] == frozenset() == TASK_MOVES[TaskStatus.FAILED]


def test_lifelong_figures_count_only_done_tasks() -> None:
    ts = [TaskRecord(i, 0, (0.0, 0.0, 0.0), float(i)) for i in range(4)]
    for t, end in zip(ts[:3], (10.0, 20.0, 40.0), strict=True):
        t.move_to(TaskStatus.ACTIVE, t.release_s)
        t.move_to(TaskStatus.DONE, end)
    ts[3].move_to(TaskStatus.FAILED, 5.0, "no plan")
    f = lifelong_figures(ts, 3600.0, {"working": 0.5})
    assert (f["tasks"], f["done"], f["failed"]) == (4, 3, 1)
    assert f["throughput_per_hour"] == pytest.approx(3.0)
    assert f["service_median_s"] == pytest.approx(19.0)  # 10, 19, 38
    assert f["service_p95_s"] == pytest.approx(np.percentile([10, 19, 38], 95), abs=1e-4)
    assert f["utilisation"] == {"working": 0.5}


def test_merged_tasks_sum_work_and_keep_the_last_verdict() -> None:
    def outcome(ok: bool, segs: int, plan: list[float], rows: int) -> ObjectOutcome:
        r = ObjectResult(success=ok, final_pose=[0.0, 0.0, 0.0], goal=[1.0, 0.0, 0.0],
                         position_error=0.0, orientation_error=0.0, left_workspace=False,
                         segments=segs, full_horizon_plan=True, replans=1,
                         planning_time_s=sum(plan))
        return ObjectOutcome(r, plan, rows)

    a, b = outcome(True, 2, [0.1, 0.2], 30), outcome(False, 3, [0.3], 12)
    assert merged_tasks([]) is None and merged_tasks([a]) is a
    m = merged_tasks([a, b])
    assert not m.result.success and m.result.segments == 5 and m.result.replans == 2
    assert m.planning_time_s == [0.1, 0.2, 0.3] and m.makespan == 42


def test_a_world_at_rest_is_skipped_without_physics() -> None:
    from lamp.fleet.tasks import REST_M, at_rest, rest_until

    robots, objects = np.array([[1.0, 2.0], [3.0, 1.0]]), np.array([[2.0, 2.0, 0.5]])
    out = rest_until(robots, objects, 12.5)
    assert out.sim_time == 12.5 and out.steps == 0
    assert np.array_equal(out.trace.times, [0.0, 12.5])
    assert np.array_equal(out.trace.robot_positions[-1], robots)
    assert np.array_equal(out.object_poses, objects) and at_rest(out.trace)
    moved = copy.deepcopy(out.trace.robot_positions)
    moved[-1, 0, 1] += 2 * REST_M
    assert not at_rest(SimpleNamespace(robot_positions=moved,
                                       object_poses=out.trace.object_poses))


# ----------------------------------------------------------------------------- the fleet

#: Simulated seconds a fake segment takes per row.
ROW_S = 0.5


class FakeWorld:
    """An executor that teleports: a segment takes ``ROW_S`` per row (plus the settle
    time) and moves nothing; a task's loop (``main``) puts its object at its goal."""

    def __init__(self, scene: Any) -> None:
        self.object_poses = np.array([o.start for o in scene.objects], float)
        self.true_object_poses = self.object_poses
        self.robot_positions = np.array(scene.robot_starts, float)
        self.failed: dict = {}
        self.disturbed = False
        self.pushes_tracked = True
        self.time = 0.0

    def row_durations(self, paths: np.ndarray) -> np.ndarray:
        return np.full(paths.shape[1], ROW_S)

    def execute(self, paths: np.ndarray, record_every: int | None = None,
                settle_time: float = 0.0, stop: Any = None) -> Any:
        sim = paths.shape[1] * ROW_S + settle_time
        trace = SimpleNamespace(times=np.array([0.0, sim]),
                                robot_positions=np.repeat(self.robot_positions[None], 2, 0),
                                object_poses=np.repeat(self.object_poses[None], 2, 0))
        self.time += sim
        return SimpleNamespace(sim_time=sim, trace=trace, stopped_at=None, steps=1,
                               objects_left=np.zeros(len(self.object_poses), bool))


def fake_main(world: FakeWorld, rows: int) -> Any:
    """A loop that runs one segment of ``rows`` rows in place, then places its object."""

    def main(fleet: Fleet, k: int) -> ObjectOutcome:
        team = fleet.team_of(k)
        paths = np.repeat(world.robot_positions[team][:, None], rows, axis=1)
        fleet.submit(k, paths, None, team)
        goal = fleet.scene.objects[k].goal
        world.object_poses[k] = goal
        r = ObjectResult(success=True, final_pose=list(goal), goal=list(goal),
                         position_error=0.0, orientation_error=0.0, left_workspace=False,
                         segments=1, full_horizon_plan=True, replans=0, planning_time_s=0.0)
        return ObjectOutcome(r, [0.0], rows)

    return main


class Watched(ScheduledFeed):
    """The scene's feed, noting every status move and the clock it was told."""

    def __init__(self, scene: Any) -> None:
        super().__init__(scene)
        self.moves: list[tuple[int, str]] = []
        self.clock = 0.0

    def changed(self, task: TaskRecord) -> None:
        self.moves.append((task.id, str(task.status)))

    def moved(self, start_s: float, trace: Any) -> None:
        assert start_s >= self.clock - 1e-9  # the clock never runs back
        self.clock = start_s + float(trace.times[-1])


tasks_strategy = st.lists(
    st.tuples(st.integers(0, 2), st.sampled_from([(1.5, 1.0), (4.5, 1.0), (4.5, 3.2),
                                                  (1.5, 3.2)]),
              st.floats(0.0, 60.0).map(lambda t: round(t, 2))),
    max_size=6)


@settings(max_examples=25, deadline=None)
@given(tasks=tasks_strategy, rows=st.integers(1, 30), serial=st.booleans())
def test_the_fleet_serves_every_released_task_in_order(tasks, rows, serial) -> None:
    """Every task ends done exactly once; an object's tasks start in release order, none
    before its release, each after the one before it ended; serially, no two at once."""
    d = {"format": "lamp-scene/1", "name": "yard", "workspace": [6.0, 4.2],
         "robots": {"starts": [[0.3, 0.3 + 0.6 * i] for i in range(6)]},
         "objects": [{"type": "circle", "radius": 0.2, "start": [2.5 + k, 2.0, 0.0],
                      "goal": [2.5 + k, 0.5, 0.0]} for k in range(3)],
         "tasks": [{"object": k, "goal": [x, y, 0.0], "release_s": t}
                   for k, (x, y), t in tasks]}
    scene = scene_from_dict(d)
    world = FakeWorld(scene)
    feed = Watched(scene)
    fleet = Fleet(scene, world, fake_main(world, rows), lambda *a: None,
                  config=FleetConfig(), feed=feed, serial=serial)
    outcomes = fleet.run()
    records = fleet.desk.records
    assert sorted(t.id for t in records) == list(range(3 + len(tasks)))
    assert all(t.status is TaskStatus.DONE for t in records)
    for t in records:
        assert [m for m in feed.moves if m[0] == t.id] == [(t.id, "active"), (t.id, "done")]
        assert t.start_s >= t.release_s - 1e-9 and t.done_s >= t.start_s
    for k in range(3):
        mine = sorted((t for t in records if t.object == k), key=lambda t: t.start_s)
        assert [t.id for t in mine] == [t.id for t in sorted(
            mine, key=lambda t: (t.release_s, t.id))]
        assert all(b.start_s >= a.done_s - 1e-9 for a, b in zip(mine, mine[1:], strict=False))
        assert outcomes[k].result.segments == len(mine)
        assert np.allclose(world.object_poses[k], mine[-1].goal)
    if serial:
        spans = sorted((t.start_s, t.done_s) for t in records)
        assert all(b[0] >= a[1] - 1e-9 for a, b in zip(spans, spans[1:], strict=False))
    last = max(t.release_s for t in records)
    assert fleet.clock >= last
    # idling is simulated until the world rests, then skipped: never a stretch of over 5 s
    # simulated, and at most one simulated stretch per idle wait
    assert world.time <= fleet.clock


def test_a_stopped_feed_fails_what_is_left() -> None:
    scene = scene_from_dict(hall())
    world = FakeWorld(scene)

    class Stops(ScheduledFeed):
        def moved(self, start_s: float, trace: Any) -> None:
            self.stopped = True  # after the first stretch of the clock

    fleet = Fleet(scene, world, fake_main(world, 3), lambda *a: None, feed=Stops(scene))
    fleet.run()
    status = {t.id: t.status for t in fleet.desk.records}
    assert set(status) == {0, 1}  # the later ones were never released
    assert all(s is TaskStatus.FAILED for s in status.values())
    assert all("stopped" in t.reason for t in fleet.desk.records)


# ----------------------------------------------------------------------------- the family


def test_the_lifelong_family_is_reproduced_and_its_streams_keep_their_rules() -> None:
    """The committed files are the generator's; every stream: N_TASKS tasks, releases
    increasing, each object sent back and forth between its start and its goal."""
    from lamp.suites import lifelong as LIFE
    from lamp.suites.build import build_suite
    from lamp.suites.registry import suite_dir, suite_scenes

    files = build_suite("lifelong")
    for name, text in files.items():
        assert (suite_dir("lifelong") / name).read_text("utf-8") == text, name
    for scene in suite_scenes("lifelong"):
        assert scene.schedule == "concurrent" and len(scene.tasks) == LIFE.N_TASKS
        releases = [t.release_s for t in scene.tasks]
        assert releases == sorted(releases) and releases[0] > 0
        sent = {k: o.goal for k, o in enumerate(scene.objects)}
        for t in scene.tasks:
            o = scene.objects[t.object]
            assert t.goal == (o.start if sent[t.object] == o.goal else o.goal)
            sent[t.object] = t.goal


# ----------------------------------------------------------------------------- end to end


@pytest.fixture(scope="module")
def hall_runs():
    scene = scene_from_dict(hall())
    return (lamp.solve(scene, "lazy", 0),
            lamp.solve(scene, "lazy", 0, schedule="sequential"))


def test_a_lifelong_run_does_every_task_safely_and_reports_it(hall_runs) -> None:
    fleet, fcfs = hall_runs
    for run in (fleet, fcfs):
        d = run.to_dict()
        assert run.success and d["success"]
        assert_safe(run)
        assert [t["status"] for t in d["tasks"]] == ["done"] * 4
        for t in d["tasks"]:
            assert t["start_s"] >= t["release_s"] and t["done_s"] > t["start_s"]
        assert d["lifelong"]["done"] == 4
        assert d["makespan_s"] >= 40.0 and d["makespan_lower_bound_s"] <= d["makespan_s"]
        assert d["makespan_lower_bound_s"] > 40.0
    served = {t["id"]: t for t in fcfs.to_dict()["tasks"]}
    spans = sorted((t["start_s"], t["done_s"]) for t in served.values())
    assert all(b[0] >= a[1] - 1e-6 for a, b in zip(spans, spans[1:], strict=False))  # one at a time
    # the fleet did the two first tasks at once, the baseline one after the other
    first = [t for t in fleet.to_dict()["tasks"] if t["id"] < 2]
    assert max(t["start_s"] for t in first) < min(t["done_s"] for t in first)


def test_the_viewer_shows_each_task_s_status_and_the_goal_in_force(hall_runs, tmp_path):
    """At a time, each task is future / queued / active / done as its record says, and
    an object's goal drawn is that of the task it serves."""
    import json
    import os

    from browser import INSTALL_HINT, Browser, find_chromium

    from lamp.viz.replay_html import write_html

    chromium = find_chromium()
    if chromium is None:
        if os.environ.get("LAMP_REQUIRE_BROWSER"):
            pytest.fail(INSTALL_HINT)
        pytest.skip(INSTALL_HINT)
    run = hall_runs[0]
    tasks = run.to_dict()["tasks"]
    page = write_html(run.recording, tmp_path / "replay.html")
    times = run.recording.arrays["times"]

    def expected(t: float) -> list[str]:
        return ["done" if k["done_s"] <= t else "active" if k["start_s"] <= t else
                "queued" if k["release_s"] <= t else "future" for k in tasks]

    with Browser(chromium, width=1000, height=700) as b:
        b.open(page.as_uri())
        for row in (0, len(times) // 3, len(times) // 2, len(times) - 1):
            b.evaluate(f"window.lampViewer.seekRow({row})")
            shown = json.loads(b.evaluate(
                "document.getElementById('state').dataset.tasks"))
            assert shown == expected(float(times[row])), row
        text = b.evaluate("document.getElementById('tasks').textContent")
        assert text.startswith("tasks: 0 queued, 0 active, 4 done")


def test_lamp_show_draws_every_task_goal() -> None:
    """One dotted outline per task of the file, beside the objects' own goals."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from lamp.viz.scene_plot import ScenePainter

    scene = scene_from_dict(hall())
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ScenePainter(ax, scene)
    dotted = [p for p in ax.patches if p.get_linestyle() == ":"]
    assert len(dotted) == len(scene.tasks)
    plain = scene_from_dict(hall(tasks=None))
    ax2 = fig.add_subplot()
    ScenePainter(ax2, plain)
    assert not [p for p in ax2.patches if p.get_linestyle() == ":"]


def test_the_bench_report_has_the_lifelong_figures() -> None:
    from lamp.bench.tables import lifelong_tables

    def rec(scene: str, ok: bool, per_hour: float | None) -> dict:
        life = None if per_hour is None else {"throughput_per_hour": per_hour,
                                              "service_median_s": 2 * per_hour}
        return {"scene": scene, "suite": "lifelong", "planner": "lazy", "success": ok,
                "lifelong": life}

    assert lifelong_tables([rec("a", True, None)]) == {}
    tables = lifelong_tables([rec("a", True, 10.0), rec("b", True, 30.0),
                              rec("c", False, 99.0)])
    assert tables["tasks done per hour"]["lazy"]["lifelong"] == (20.0, 2)
    assert tables["median service time (s)"]["lazy"]["all"] == (40.0, 2)
