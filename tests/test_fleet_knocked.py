"""Placed objects pushed off their goals are placed again (``fleet.knocked``)."""

from __future__ import annotations

import numpy as np
from fleet_fakes import fleet_at_starts
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.contract.goals import SUCCESS_ORIENTATION_TOL, SUCCESS_POSITION_TOL, within_goal
from lamp.fleet.knocked import MAX_REPLACES
from lamp.fleet.state import ObjectStatus
from lamp.scene import scene_from_dict

BOX = {"type": "rectangle", "size": [0.4, 0.3]}


def _scene(tasks: bool = False):
    d = {"format": "lamp-scene/1", "name": "two", "workspace": [6.0, 4.0],
         "schedule": "concurrent", "robots": {"starts": [[0.3, 0.3], [0.3, 0.8]]},
         "objects": [{**BOX, "start": [1.0, 1.0, 0.0], "goal": [4.0, 1.0, 0.0]},
                     {**BOX, "start": [1.0, 3.0, 0.0], "goal": [4.0, 3.0, 0.5]}]}
    if tasks:
        d["tasks"] = [{"object": 0, "goal": [2.0, 1.0, 0.0], "release_s": 50.0}]
    return scene_from_dict(d)


def _placed(scene, pose0):
    """A fleet whose object 0 was placed and now stands at ``pose0`` (object 1 moves)."""
    fleet = fleet_at_starts(scene)
    fleet._take_tasks()
    o = fleet.objects[0]
    o.move_to(ObjectStatus.ACTIVE)
    o.move_to(ObjectStatus.PLACED)
    fleet.desk.begin(0, 0.0)
    fleet.desk.end(0, 10.0, True)
    fleet.objects[1].status = ObjectStatus.ACTIVE
    fleet.executor.object_poses[0] = pose0
    fleet.stats.counts["events"] += 1
    return fleet


@settings(max_examples=60)
@given(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-0.5, 0.5))
def test_a_placed_object_off_its_goal_gets_its_task_again(dx, dy, dt) -> None:
    """Object 0, placed, is sensed at its goal moved by (dx, dy, dt): outside the success
    tolerances it is reopened (its task queued again, to its goal, and it waits to start
    at the next take), inside them it stays placed. Asked again before the clock ran, it
    looks no further."""
    scene = _scene()
    goal = np.array(scene.objects[0].goal, float)
    pose = goal + [dx, dy, dt]
    fleet = _placed(scene, pose)
    off = not within_goal(pose, goal, SUCCESS_POSITION_TOL, SUCCESS_ORIENTATION_TOL)
    assert fleet.reopen_knocked() == ([0] if off else [])
    assert fleet.reopen_knocked() == []
    fleet._take_tasks()
    o = fleet.objects[0]
    assert o.status == (ObjectStatus.WAITING if off else ObjectStatus.PLACED)
    if off:
        task = fleet.desk.current[0]
        assert task.goal == tuple(goal) and task.id == 2 and fleet.stats.counts["knocked"] == 1
        assert fleet.may_start(0)


def test_an_object_is_placed_again_at_most_max_times_and_never_in_lifelong_runs() -> None:
    scene = _scene()
    off = np.array(scene.objects[0].goal, float) + [0.5, 0.0, 0.0]
    fleet = _placed(scene, off)
    for _ in range(MAX_REPLACES):
        assert fleet.reopen_knocked() == [0]
        fleet.objects[0].status = ObjectStatus.PLACED
        fleet.stats.counts["events"] += 1
    assert fleet.reopen_knocked() == []
    lifelong = _placed(_scene(tasks=True), off)
    assert lifelong.reopen_knocked() == []
