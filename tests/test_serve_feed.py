"""The live task feed of ``lamp serve`` (``lamp.serve.feed``) and its pace: numbering,
release times, hand-out order and statuses over any order of posts, motions and task
moves (Hypothesis, driven through the fleet's own ``TaskDesk``), and the idle and pace
rules with threads. Wall-clock speed decides nothing here: the pace is checked from
below only (a motion never ends sooner than the pace allows), waits are bounded by
generous joins."""

from __future__ import annotations

import json
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.fleet.desk import TaskDesk
from lamp.fleet.tasks import TaskStatus
from lamp.scene import scene_from_dict
from lamp.serve.feed import IDLE_S, FeedStopped, LiveFeed
from lamp.serve.pace import Pace

SCENE = scene_from_dict({
    "format": "lamp-scene/1", "name": "feed", "workspace": [4.0, 3.0],
    "robots": {"starts": [[0.3, 0.3], [0.3, 0.8], [0.3, 2.5]]},
    "objects": [
        {"type": "circle", "radius": 0.2, "start": [1.5, 1.0, 0.0], "goal": [2.5, 1.0, 0.0]},
        {"type": "rectangle", "size": [0.4, 0.3], "start": [1.5, 2.2, 0.0],
         "goal": [2.5, 2.2, 0.0]},
    ],
    "tasks": [{"object": 0, "goal": [3.0, 1.5, 0.0], "release_s": 3.0}],
})
N_SCENE = 3  # the two objects' goals and the file's task


def trace(duration: float, n: int = 3, start: float = 0.0) -> SimpleNamespace:
    """A motion of ``duration`` s: every robot and object slides along x."""
    times = np.linspace(0.0, duration, 5)
    robots = np.array([[[start + t, 0.5 + i] for i in range(n)] for t in times])
    objects = np.array([[[start + t, 1.0 + k, 0.1] for k in range(2)] for t in times])
    return SimpleNamespace(times=times, robot_positions=robots, object_poses=objects)


# ----------------------------------------------------------------------------- Hypothesis
step = st.one_of(
    st.tuples(st.just("post"), st.integers(0, 1)),
    st.tuples(st.just("move"), st.sampled_from([0.0, 0.5, 1.25, 4.0])),
    st.tuples(st.just("take"), st.just(0)),
    st.tuples(st.just("start"), st.integers(0, 1)),
    st.tuples(st.just("end"), st.integers(0, 1), st.booleans()),
)


@settings(max_examples=150)
@given(st.lists(step, max_size=40))
def test_any_order_of_posts_motions_and_moves_keeps_the_feed_rules(steps):
    feed = LiveFeed(SCENE, realtime=0)
    desk = TaskDesk(feed, len(SCENE.objects))
    clock, posted, handed = 0.0, [], []
    for op, *args in steps:
        if op == "post":
            d = feed.post(args[0], (2.0, 1.2, 0.0))
            assert d["id"] == N_SCENE + len(posted)  # numbered after the scene's, in order
            assert d["status"] == "queued" and d["release_s"] == round(clock, 4)
            posted.append(d["id"])
        elif op == "move":
            feed.moved(clock, trace(args[0], start=clock))
            clock += args[0]
            assert feed.world()["time_s"] == round(clock, 4)
        elif op == "take":
            before = len(desk.records)
            desk.take(clock)
            new = desk.records[before:]
            assert [(t.release_s, t.id) for t in new] == sorted((t.release_s, t.id) for t in new)
            assert all(t.release_s <= clock for t in new)
            handed += [t.id for t in new]
        elif op == "start":
            if desk.next_for(args[0]) is not None or desk.current[args[0]] is not None:
                desk.begin(args[0], clock)
        else:
            desk.end(args[0], clock, args[1], "test")
        # every number at most once, the snapshot = the records
        assert len(handed) == len(set(handed))
        for t in desk.records:
            assert feed.task(t.id) == t.to_dict()
        assert json.loads(feed.state_json()) == feed.state()  # its cached parts are current
    desk.take(clock)
    ids = {t.id for t in desk.records}
    # what is released by now: everything posted, the objects' goals, the file's at 3 s
    assert ids == set(posted) | {0, 1} | ({2} if clock >= 3.0 else set())
    desk.stop(clock, "stopped")
    statuses = {d["id"]: d["status"] for d in feed.tasks()}
    assert all(statuses[i] in ("done", "failed") for i in ids)
    assert sorted(statuses) == list(range(N_SCENE + len(posted)))


def test_a_stopped_feed_takes_no_task_and_waits_for_nothing():
    feed = LiveFeed(SCENE, realtime=0)
    feed.stop()
    assert feed.stopped and feed.wait(0.0) is None
    with pytest.raises(FeedStopped):
        feed.post(0, (2.0, 1.2, 0.0))
    assert feed.state()["stopped"] is True


def test_wait_at_realtime_0_returns_the_next_scene_release_or_now_for_a_post():
    feed = LiveFeed(SCENE, realtime=0)
    assert [t.id for t in feed.released(0.0)] == [0, 1]
    assert feed.wait(0.5) == 3.0  # the file's task; nothing blocks
    assert [t.id for t in feed.released(3.0)] == [2]
    feed.post(1, (2.0, 1.2, 0.0))
    assert feed.wait(3.0) == 3.0
    assert [t.id for t in feed.released(3.0)] == [3]


def test_wait_at_realtime_0_blocks_until_a_post_or_a_stop():
    feed = LiveFeed(SCENE, realtime=0)
    feed.released(10.0)
    got = []
    waiter = threading.Thread(target=lambda: got.append(feed.wait(10.0)))
    waiter.start()
    time.sleep(0.05)
    feed.post(0, (2.0, 1.2, 0.0))
    waiter.join(30)
    assert got == [10.0]
    assert [t.release_s for t in feed.released(10.0)] == [10.0]
    waiter = threading.Thread(target=lambda: got.append(feed.wait(10.0)))
    waiter.start()
    feed.stop()
    waiter.join(30)
    assert got == [10.0, None]


def test_a_paced_motion_never_ends_before_its_wall_time():
    feed = LiveFeed(SCENE, realtime=4.0)
    t0 = time.monotonic()
    feed.moved(0.0, trace(0.8))  # 0.8 s simulated at 4x: at least 0.2 s of wall time
    assert time.monotonic() - t0 >= 0.2 - 1e-3
    assert feed.world()["time_s"] == 0.8
    assert feed.world()["robots"][0] == [0.8, 0.5]


def test_idle_at_realtime_runs_the_clock_and_a_post_ends_it():
    feed = LiveFeed(SCENE, realtime=2.0)
    feed.released(5.0)
    until = feed.wait(5.0)  # nothing posted: one idle stretch, at most IDLE_S * F
    assert 5.0 <= until <= 5.0 + IDLE_S * 2.0 + 1e-9
    got = []
    waiter = threading.Thread(target=lambda: got.append(feed.wait(until)))
    waiter.start()
    time.sleep(0.05)
    task = feed.post(0, (2.0, 1.2, 0.0))
    waiter.join(30)
    assert got[0] >= task["release_s"] >= until
    assert [t.id for t in feed.released(got[0])] == [task["id"]]
    feed.stop()
    assert feed.wait(got[0]) is None


def test_an_idle_stretch_paced_by_wait_is_not_paced_again_by_moved():
    """The fleet idles until ``wait``'s answer and shows the feed that stretch
    (``moved``): the feed lived through it already and reads the wall clock at most
    once more (a fake clock, 0.05 s per read)."""
    reads = [0]

    def wall() -> float:
        reads[0] += 1
        return 0.05 * reads[0]

    feed = LiveFeed(SCENE, realtime=2.0, wall=wall)
    feed.released(5.0)
    until = feed.wait(5.0)
    assert until > 5.0
    reads[0] = 0
    feed.moved(5.0, trace(until - 5.0, start=5.0))
    assert reads[0] <= 1 and feed.world()["time_s"] == round(until, 4)


def test_the_pace_reanchors_when_the_simulation_lags():
    wall = [100.0]
    pace = Pace(2.0, lambda: wall[0])
    pace.anchor(10.0)
    assert pace.now() == 10.0 and pace.wall_at(12.0) == 101.0
    wall[0] = 103.0  # planning took 3 s of wall time, simulated time stood at 10
    pace.anchor(10.0)
    assert pace.now() == 10.0
    pace.anchor(11.0)  # ahead of the pace: the anchor stays, the caller waits
    assert pace.wall_at(11.0) == 103.5
    with pytest.raises(ValueError, match="factor"):
        Pace(0.0)


def test_bad_realtime_is_refused_naming_it():
    with pytest.raises(ValueError, match="realtime"):
        LiveFeed(SCENE, realtime=float("nan"))
    assert TaskStatus.QUEUED == "queued"
