"""Disturbances: what the wrapper does to sensing and actuation, robots that stop, knocked
pushes; the loop does not replan on noise alone; runs stay deterministic; bad input is
refused by name."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from scenes import TINY
from typer.testing import CliRunner

import lamp
from lamp.cli import app
from lamp.contract.disturb import NO_DISTURBANCE, Disturbances, parse_failure
from lamp.contract.trajectory import MAX_STEP
from lamp.errors import InputError
from lamp.manip import GeometricProposer
from lamp.pipeline import RunRequest
from lamp.planners.closed_loop import ClosedLoop, LoopRecord
from lamp.planners.config import PlannerConfig
from lamp.scene import scene_from_dict
from lamp.sim import SETTLE_TIME, Simulator
from lamp.sim.disturbed import DisturbedExecutor

SCENE = {**TINY, "objects": [{"type": "rectangle", "size": [0.3, 0.2],
                              "start": [0.7, 1.0, 0.0], "goal": [1.6, 1.2, 0.5]}]}


@pytest.fixture(scope="module")
def scene():
    return scene_from_dict(SCENE)


def _line(a, b, n):
    return np.linspace(a, b, n)


def _walk(scene, n=41):
    """Robots 1 and 2 hold; robot 0 walks 0.8 m along the bottom."""
    starts = scene.robot_starts_array
    paths = np.repeat(starts[:, None], n, axis=1)
    paths[0] = _line(starts[0], starts[0] + [0.8, 0.0], n)
    return paths


def test_no_disturbance_passes_straight_through(scene):
    a, b = Simulator(scene), DisturbedExecutor(Simulator(scene), NO_DISTURBANCE, seed=3)
    out_a, out_b = a.execute(_walk(scene)), b.execute(_walk(scene))
    assert np.array_equal(out_a.object_poses, out_b.object_poses)
    assert np.array_equal(out_a.robot_positions, out_b.robot_positions)
    assert np.array_equal(b.object_poses, a.object_poses)


def test_sensing_noise_has_its_level_and_the_truth_stays(scene):
    sigma = 0.01
    ex = DisturbedExecutor(Simulator(scene), Disturbances(sensing_noise=sigma), seed=0)
    reads = np.array([ex.object_poses[0] for _ in range(3000)])
    truth = ex.true_object_poses[0]
    err = reads - truth
    assert np.allclose(err[:, :2].mean(axis=0), 0.0, atol=4 * sigma / np.sqrt(3000))
    assert np.allclose(err[:, :2].std(axis=0), sigma, rtol=0.08)
    assert err[:, 2].std() == pytest.approx(sigma / 0.2, rel=0.08)
    assert np.array_equal(truth, ex.sim.object_poses[0])


def test_actuation_noise_moves_robots_off_their_commands_within_row_spacing(scene):
    ex = DisturbedExecutor(Simulator(scene), Disturbances(actuation_noise=0.1), seed=1)
    paths = _walk(scene)
    noisy = ex._imprecise(paths)
    assert np.all(np.linalg.norm(np.diff(noisy, axis=1), axis=2) <= MAX_STEP + 1e-9)
    assert np.array_equal(noisy[:, 0], paths[:, 0])
    end_miss = np.linalg.norm(noisy[0, -1] - paths[0, -1])
    assert 0.002 < end_miss < 0.3  # the walk of 0.8 m ends off by noise, not wildly
    assert np.allclose(noisy[1:, -1], paths[1:, -1])  # robots standing still stay still


def test_a_failed_robot_stops_at_its_time_and_stays(scene):
    ex = DisturbedExecutor(Simulator(scene), Disturbances(robot_failures=((0, 1.0),)), seed=0)
    paths = _walk(scene)  # 0.8 m at 0.25 m/s: 3.2 s of motion
    out = ex.execute(paths, record_every=10)
    place = ex.failed[0]
    assert abs(place[0] - (0.2 + 0.25 * 1.0)) < 0.03  # where the walk was at 1 s
    assert np.linalg.norm(out.robot_positions[0] - place) < 0.005
    t = out.trace
    after = t.robot_positions[t.times > 1.2, 0]
    assert np.all(np.linalg.norm(after - place, axis=1) < 0.01)
    back = np.repeat(out.robot_positions[:, None], 21, axis=1)
    back[0] = _line(out.robot_positions[0], out.robot_positions[0] - [0.3, 0.0], 21)
    ex.execute(back)
    assert np.linalg.norm(ex.robot_positions[0] - place) < 0.005  # later calls: still there


def test_a_knock_moves_the_pushed_object_off_course(scene):
    """Robot 0 pushes the box straight along +x; with a knock the box ends off the line."""
    starts = scene.robot_starts_array.copy()
    starts[0] = [0.5, 1.0]
    push = np.repeat(starts[:, None], 31, axis=1)
    push[0] = _line([0.5, 1.0], [1.1, 1.0], 31)
    ends = []
    for level in (0.0, 2.0):
        sim = Simulator(scene, robot_positions=starts)
        ex = DisturbedExecutor(sim, Disturbances(push_disturbance=level), seed=4)
        ex.execute(push) if level else sim.execute(push)
        ends.append(sim.object_poses[0])
    assert abs(ends[0][1] - 1.0) < 0.01
    assert np.hypot(*(ends[1][:2] - ends[0][:2])) > 0.02


class _StillExecutor:
    """The object moves exactly as planned; its readings carry noise of ``sigma``."""

    def __init__(self, sigma, seed=0):
        self.true = np.array([[1.0, 1.0, 0.0]])
        self.robots = np.array([[0.7, 1.0], [0.7, 1.3]])
        self.rng = np.random.default_rng(seed)
        self.sigma = sigma

    @property
    def object_poses(self):
        return self.true + self.rng.normal(0, 1, (1, 3)) * [self.sigma, self.sigma,
                                                            self.sigma / 0.2]

    @property
    def robot_positions(self):
        return self.robots.copy()

    def execute(self, robot_paths, record_every=None, stop=None):
        from types import SimpleNamespace

        paths = np.asarray(robot_paths, float)
        self.true[0, :2] += paths[0, -1] - paths[0, 0]
        self.robots = paths[:, -1]
        return SimpleNamespace(object_poses=self.object_poses, robot_positions=self.robots,
                               left_workspace=False, trace=None, stopped_at=None,
                               declined=False)


@pytest.mark.parametrize(("sigma_known", "thrash"), [(0.0, True), (0.01, False)])
def test_the_loop_does_not_replan_on_noise_alone(sigma_known, thrash):
    """Pushes that land exactly as planned, seen through a 1 cm sensor, with the tight drift
    limits of a narrow place (1 cm, 0.03 rad): a loop that knows its sensor (sensing_sigma)
    does not call them drift; one that does not, replans on noise."""
    from test_closed_loop import DRIFT_ONLY, GOAL, StraightPlanner

    config = PlannerConfig.of(long_push_length=0.0, planning_time_limit=60.0, stop_position=0.2,
                           drift_position=0.01, drift_orientation=0.03,
                           sensing_sigma=sigma_known)
    events = []
    planner = StraightPlanner(GOAL, step=0.1)
    loop = ClosedLoop(planner, DRIFT_ONLY, _StillExecutor(0.01), index=0, goal=GOAL,
                      config=config, reroute=lambda t, q: t, record=LoopRecord(),
                      observer=events.append)
    loop.run()
    drifts = sum(e.outcome == "drift" for e in events)
    assert (drifts >= 2) if thrash else (drifts == 0)


class _ScriptedSensor(_StillExecutor):
    """An exact object whose readings are the truth plus ``script``'s offsets in turn
    (then the truth); ``reads`` counts them."""

    def __init__(self, start, script):
        super().__init__(0.0)
        self.true = np.array([start], float)
        self.script, self.reads = [np.asarray(o, float) for o in script], 0

    @property
    def object_poses(self):
        self.reads += 1
        return self.true + (self.script.pop(0) if self.script else np.zeros(3))


@pytest.mark.parametrize("sigma", [0.0, 0.01])
def test_a_noisy_sensor_stops_the_loop_only_when_a_closer_look_agrees(sigma):
    """The object is at its goal and the first reading says so. An exact sensor (sigma 0)
    stops there. A noisy one takes ``CONFIRM_FACTOR * sensing_readings`` more readings:
    when they agree it stops with them (no segment), when they see the object 0.3 m short
    it goes on pushing."""
    from test_closed_loop import DRIFT_ONLY, GOAL, StraightPlanner

    from lamp.planners.closed_loop import CONFIRM_FACTOR

    config = PlannerConfig.of(long_push_length=0.0, planning_time_limit=60.0,
                           sensing_sigma=sigma, sensing_readings=4)
    look = CONFIRM_FACTOR * config.loop.sensing_readings
    for short, pushes in ((0.0, False), (-0.3, bool(sigma))):
        ex = _ScriptedSensor(GOAL, [[0, 0, 0]] + [[short, 0, 0]] * look)
        loop = ClosedLoop(StraightPlanner(GOAL, step=0.1), DRIFT_ONLY, ex, index=0, goal=GOAL,
                          config=config, reroute=lambda t, q: t, record=LoopRecord())
        result = loop.run()
        assert (result.segments > 0) == pushes, (short, result)
        if not pushes:
            assert ex.reads == 1 + (look if sigma else 0)


def test_disturbed_runs_are_deterministic_and_judged_on_the_truth(scene):
    d = Disturbances(sensing_noise=0.01, actuation_noise=0.1, push_disturbance=0.3)
    a = lamp.solve(scene, "lazy", 1, model=GeometricProposer(), disturbances=d)
    b = lamp.solve(scene, "lazy", 1, model=GeometricProposer(), disturbances=d)

    def untimed(x):
        if isinstance(x, dict):
            return {k: untimed(v) for k, v in x.items() if "time" not in k or k == "makespan_s"}
        return [untimed(v) for v in x] if isinstance(x, list) else x

    assert untimed(a.to_dict()) == untimed(b.to_dict())
    truth = a.recording.arrays["objects"][-1, 0]
    assert np.allclose(a.objects[0].final_pose, truth, atol=1e-5)
    assert a.to_dict()["disturbances"]["sensing_noise"] == 0.01
    assert a.to_dict()["params"]["sensing_sigma"] == 0.01  # the loop knows its sensor


def test_a_run_carries_on_without_a_failed_robot(scene):
    res = lamp.solve(scene, "lazy", 0, model=GeometricProposer(),
                     disturbances=Disturbances(robot_failures=((1, 2.0),)))
    d = res.to_dict()
    assert d["success"], d["objects"][0]["failure_reason"]
    assert set(d["stats"]["failed_robots"]) == {"1"}
    place = np.array(d["stats"]["failed_robots"]["1"])
    rec = res.recording.arrays
    later = rec["robots"][rec["times"] > 2.5, 1]
    assert np.all(np.linalg.norm(later - place, axis=1) < 0.02)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"sensing_noise": -0.1}, "sensing_noise: a number in [0, 0.2]"),
    ({"actuation_noise": 2.0}, "actuation_noise: a number in [0, 1]"),
    ({"robot_failures": ((0, -1.0),)}, "a time >= 0 s"),
    ({"robot_failures": ((0, 1.0), (0, 2.0))}, "named twice"),
])
def test_bad_disturbances_are_refused(kwargs, message):
    with pytest.raises(InputError, match=message.replace("[", r"\[").replace("]", r"\]")):
        Disturbances(**kwargs)


def test_requests_check_disturbances_against_the_scene(scene):
    with pytest.raises(InputError, match="robot 5: the scene has robots 0..2"):
        RunRequest(scene, "lazy", model="geometric",
                   disturbances=Disturbances(robot_failures=((5, 1.0),)))
    with pytest.raises(InputError, match="every robot would fail"):
        RunRequest(scene, "lazy", model="geometric", disturbances=Disturbances(
            robot_failures=((0, 1.0), (1, 1.0), (2, 1.0))))
    assert parse_failure("2@30.5") == (2, 30.5)
    with pytest.raises(InputError, match="ROBOT@SECONDS"):
        parse_failure("2-30")


def test_cli_disturbance_options(tmp_path):
    f = tmp_path / "tiny.json"
    f.write_text(json.dumps(SCENE))
    runner = CliRunner()
    bad = runner.invoke(app, ["run", str(f), "-o", str(tmp_path / "b"), "--sensing-noise", "-1"])
    assert bad.exit_code == 2 and "--sensing-noise: a number in [0, 0.2]" in bad.stderr
    bad = runner.invoke(app, ["run", str(f), "-o", str(tmp_path / "b"), "--robot-failure", "x"])
    assert bad.exit_code == 2 and "--robot-failure: ROBOT@SECONDS" in bad.stderr
    assert not (tmp_path / "b").exists()
    ok = runner.invoke(app, ["run", str(f), "-o", str(tmp_path / "o"), "-m", "geometric", "-q",
                             "--sensing-noise", "0.005", "--robot-failure", "2@1.5"])
    assert ok.exit_code == 0, ok.output
    result = json.loads((tmp_path / "o" / "result.json").read_text())
    assert result["disturbances"]["robot_failures"] == [[2, 1.5]]


def test_bench_disturb_presets(tmp_path):
    from lamp.bench.disturb import FAILURE_FRACTION, disturbances_for
    from lamp.scene.bounds import makespan_lower_bound
    from lamp.suites.registry import suite_scenes

    scene = suite_scenes("maze")[0]
    a = disturbances_for("one-robot-fails", scene, 0)
    assert a == disturbances_for("one-robot-fails", scene, 0)  # deterministic
    assert a != disturbances_for("one-robot-fails", scene, 1)
    (robot, when), = a.robot_failures
    earliest = min(makespan_lower_bound(scene, straight_line=True).per_object)
    assert 0 <= robot < scene.n_robots
    assert FAILURE_FRACTION[0] * earliest <= when <= FAILURE_FRACTION[1] * earliest
    assert disturbances_for("noise-high", scene, 0).sensing_noise == 0.01
    runner = CliRunner()
    base = ["bench", "--suites", "maze", "--scenes", "1", "--out", str(tmp_path / "b"),
            "--dry-run"]
    res = runner.invoke(app, [*base, "--planners", "lazy", "--disturb", "noise-high"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, [*base, "--planners", "lazy", "--disturb", "storm"])
    assert res.exit_code == 2 and "unknown preset 'storm'" in res.output
    res = runner.invoke(app, [*base, "--planners", "mapush", "--disturb", "noise-low"])
    assert res.exit_code == 2 and "run no closed loop" in res.output


def test_a_watch_firing_with_no_settle_time_ends_the_call(scene):
    """The knock splits a segment into calls without settling; a push watch may fire in the
    first (the simulator once failed to build an empty settle block)."""
    sim = Simulator(scene)
    out = sim.execute(_walk(scene), settle_time=0.0, stop=lambda poses: True)
    assert out.stopped_at is not None and out.sim_time > 0


def test_knocks_resume_from_where_the_robots_are(scene):
    """A robot held back from its target (pressing on a blocked object) must not make the
    second half of a knocked segment start too far from it."""
    starts = scene.robot_starts_array.copy()
    starts[0] = [0.5, 1.0]
    push = np.repeat(starts[:, None], 41, axis=1)
    push[0] = _line([0.5, 1.0], [1.3, 1.0], 41)
    for seed in range(6):
        sim = Simulator(scene, robot_positions=starts)
        ex = DisturbedExecutor(sim, Disturbances(push_disturbance=3.0), seed=seed)
        out = ex.execute(push, record_every=40)
        assert out.trace.times[-1] == pytest.approx(out.sim_time, abs=1e-9)


def test_a_failed_robot_is_braked_where_it_stands(scene):
    """Shoved by another robot, a failed robot stays where it was shoved to (it does not
    spring back to where it stopped)."""
    ex = DisturbedExecutor(Simulator(scene), Disturbances(robot_failures=((0, 0.0),)), seed=0)
    starts = scene.robot_starts_array
    ex.execute(np.repeat(starts[:, None], 3, axis=1))  # robot 0 fails at once, at (0.2, 0.3)
    place = ex.failed[0].copy()
    shove = np.repeat(ex.robot_positions[:, None], 31, axis=1)
    shove[1] = _line(starts[1], [0.2, 0.35], 31)  # robot 1 drives down into robot 0
    ex.execute(shove)
    shoved = ex.robot_positions[0].copy()
    rest = np.repeat(ex.robot_positions[:, None], 3, axis=1)
    rest[1] = np.linspace(ex.robot_positions[1], ex.robot_positions[1] + [0.0, 0.04], 3)
    ex.execute(rest)  # robot 1 backs off
    assert np.linalg.norm(shoved - place) > 0.01
    assert np.linalg.norm(ex.robot_positions[0] - shoved) < 0.005


class _SpySensor(DisturbedExecutor):
    """A disturbed executor that checks what the planner side reads: every pose a push
    watch is handed must be a sensor reading, not the true state; and the true poses may be
    read only where an object's final success is judged."""

    #: each object's judgement when its loops end, and every object's again when the run
    #: ends (``pipeline.execute.still_placed``)
    JUDGES = {"lamp.planners.runner.run_object", "lamp.fleet.objects.main",
              "lamp.pipeline.execute.execute"}

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.watch_reads, self.oracle_reads, self.truth_readers = 0, [], set()

    @property
    def true_object_poses(self):
        caller = sys._getframe(1)
        self.truth_readers.add(f"{caller.f_globals['__name__']}.{caller.f_code.co_name}")
        return super().true_object_poses

    def execute(self, robot_paths, record_every=None, stop=None, settle_time=SETTLE_TIME):
        if stop is not None:
            planner_stop = stop

            def stop(poses):
                self.watch_reads += 1
                if np.array_equal(poses, self.sim.object_poses):
                    self.oracle_reads.append(round(self.sim.time, 3))
                return planner_stop(poses)
        return super().execute(robot_paths, record_every=record_every, stop=stop,
                               settle_time=settle_time)


#: A box pushed straight through a passage 5 cm wider than it: a watched push.
PASSAGE = {**TINY, "workspace": [2.4, 1.2],
           "robots": {"radius": 0.05, "starts": [[0.15, 0.4], [0.15, 0.6], [0.15, 0.8]]},
           "obstacles": [{"type": "rectangle", "center": [1.2, 0.875], "size": [0.6, 0.3]},
                         {"type": "rectangle", "center": [1.2, 0.325], "size": [0.6, 0.3]}],
           "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.55, 0.6, 0.0],
                        "goal": [1.95, 0.6, 0.0]}]}


@pytest.mark.parametrize("schedule", ["sequential", "concurrent"])
def test_under_sensing_noise_the_planner_side_never_reads_the_truth(schedule, monkeypatch):
    import lamp.sim.disturbed as disturbed

    spies = []
    monkeypatch.setattr(disturbed, "DisturbedExecutor",
                        lambda *a, **k: spies.append(_SpySensor(*a, **k)) or spies[-1])
    d = Disturbances(sensing_noise=0.01, actuation_noise=0.05)
    lamp.solve(scene_from_dict(PASSAGE), "lazy", 0, model=GeometricProposer(), disturbances=d,
               schedule=schedule, max_segments=20)
    spy, = spies
    assert spy.watch_reads > 0  # the push watch was consulted
    assert not spy.oracle_reads, f"the watch read true poses at t = {spy.oracle_reads[:5]} s"
    assert spy.truth_readers <= _SpySensor.JUDGES, spy.truth_readers


@pytest.mark.parametrize("schedule", ["sequential", "concurrent"])
def test_the_preset_failure_fires_before_the_first_placement(scene, schedule):
    """``one-robot-fails``: the robot stops before any object could be placed, in every
    run that places one, whatever the schedule; the result says when, and the robot stands
    still from then on."""
    from lamp.bench.disturb import disturbances_for

    d = disturbances_for("one-robot-fails", scene, 0)
    (robot, due), = d.robot_failures
    res = lamp.solve(scene, "lazy", 0, model=GeometricProposer(), disturbances=d,
                     schedule=schedule)
    out = res.to_dict()
    assert out["success"]
    (fired_robot, when), = out["disturbances"]["robot_failures_fired"]
    assert fired_robot == robot and due <= when < due + 0.1
    rec = res.recording.arrays
    later = rec["robots"][rec["times"] >= when + 0.2, robot]
    assert np.all(np.linalg.norm(later - later[0], axis=1) < 0.02)


def test_a_failure_after_the_run_is_reported_as_not_fired(scene):
    d = Disturbances(robot_failures=((1, 1e5),))
    out = lamp.solve(scene, "lazy", 0, model=GeometricProposer(), disturbances=d).to_dict()
    assert out["disturbances"]["robot_failures_fired"] == []
    assert out["stats"]["failed_robots"] == {}
