"""Loads that follow the loads ahead of them (``fleet.follow``): who leads whom, the world a
follower plans in, and admission holding a follower's segment for a standing leader
(declined only when nothing else can move)."""

from __future__ import annotations

import numpy as np
from fleet_fakes import fleet_at_starts

from lamp.fleet.segments import Segment
from lamp.fleet.state import ObjectStatus
from lamp.fleet.view import FleetView
from lamp.scene import scene_from_dict

R = 0.05
BOX = {"type": "rectangle", "size": [0.4, 0.3]}


def _aisle(head_on: bool = False):
    """A 10 x 4 m hall; an aisle (walls at y = 1.45 and 2.55) from x = 0 to 8 opens east.
    Loads 0, 1, 2 stand in a line in it at x = 4.5, 3.0, 1.5 (0 nearest the exit) and go
    to drop spots beyond it; load 3 stands south of the aisle. With ``head_on`` load 0
    goes west instead, deeper into the aisle, through the others. Two robots each."""
    objects = [{**BOX, "start": [4.5, 2.0, 0.0], "goal": [9.5, 0.5, 0.0]},
               {**BOX, "start": [3.0, 2.0, 0.0], "goal": [9.5, 3.5, 0.0]},
               {**BOX, "start": [1.5, 2.0, 0.0], "goal": [9.5, 2.0, 0.0]},
               {**BOX, "start": [3.0, 0.6, 0.0], "goal": [8.5, 0.6, 0.0]}]
    if head_on:
        objects[0]["goal"] = [0.6, 2.0, 0.0]
    starts = [[x - 0.35, y + dy] for x, y in ((4.5, 2.0), (3.0, 2.0), (1.5, 2.0), (3.0, 0.6))
              for dy in (-0.1, 0.1)]
    scene = scene_from_dict({
        "format": "lamp-scene/1", "name": "aisle", "workspace": [10.0, 4.0],
        "schedule": "concurrent", "robots": {"radius": R, "starts": starts},
        "obstacles": [{"type": "rectangle", "center": [4.0, 1.45], "size": [8.0, 0.1]},
                      {"type": "rectangle", "center": [4.0, 2.55], "size": [8.0, 0.1]}],
        "objects": objects})
    return scene


def _moving(scene, follow: int = 1):
    """A ``Fleet`` on ``scene`` (poses: the starts) whose objects all move, ranked in file
    order, each pushed by its two robots."""
    fleet = fleet_at_starts(scene, follow=follow)
    for k, o in enumerate(fleet.objects):
        o.status, o.rank, o.team = ObjectStatus.ACTIVE, k, [2 * k, 2 * k + 1]
        fleet.owner[o.team] = k
    return fleet


def test_the_leaders_are_the_moving_objects_ahead_on_its_way() -> None:
    """Each load in the line follows those nearer the exit; the front one and the load
    outside the aisle follow none. A load ahead that is ranked lower, waits on a change,
    is on a detour, or comes head-on leads no one."""
    scene = _aisle()
    fleet = _moving(scene)
    assert [fleet.leaders(k) for k in range(4)] == [set(), {0}, {0, 1}, set()]
    fleet.objects[1].blocked_at = (0, 0)
    assert fleet.leaders(2) == {0}
    fleet.objects[1].blocked_at = None
    fleet.objects[0].detour = np.array([9.0, 1.0, 0.0])
    assert fleet.leaders(2) == {1}
    fleet.objects[0].detour = None
    fleet.objects[0].rank = 5  # now below the others
    assert fleet.leaders(1) == set() and fleet.leaders(2) == {1}
    assert fleet.leaders(0) == set()  # 1 and 2 lie behind it
    head_on = _moving(_aisle(head_on=True))
    assert head_on.leaders(1) == set() and head_on.leaders(2) == {1}


def test_a_follower_plans_with_its_leaders_at_their_goals_and_without_their_robots() -> None:
    """``following``: the leaders each at its goal, set on the object's state; none with
    ``follow`` off. Its view reads them there, and every other object where it is."""
    scene = _aisle()
    off = _moving(scene, follow=0)
    assert off.following(2) == {} and off.objects[2].leaders == frozenset()
    fleet = _moving(scene)
    ghosts = fleet.following(2)
    assert sorted(ghosts) == [0, 1] and fleet.objects[2].leaders == {0, 1}
    view = FleetView(fleet, 2)
    view.ghosts = ghosts
    poses = view.object_poses
    for k in range(4):
        want = scene.objects[k].goal if k in ghosts else scene.objects[k].start
        assert np.allclose(poses[k], want)
    assert np.allclose(fleet.executor.object_poses[0], scene.objects[0].start)  # unchanged


def _request(fleet, k: int, dx: float) -> Segment:
    """Object ``k``'s robots push it ``dx`` m east: its submitted segment."""
    o, scene = fleet.objects[k], fleet.scene
    start = np.asarray(fleet.executor.robot_positions, float)[o.team]
    rows = np.linspace(start, start + [dx, 0.0], 40).transpose(1, 0, 2)
    pose = np.asarray(scene.objects[k].start, float)
    poses = np.linspace(pose, pose + [dx, 0.0, 0.0], 10)
    o.request = Segment(k, list(o.team), rows, poses, None, scene.objects[k].shape, R)
    return o.request


def test_a_segment_into_a_standing_leader_waits_and_is_declined_only_when_forced() -> None:
    """Load 1's segment runs into load 0, standing: with load 0 its leader it waits (not
    declined, counted as waiting on ``leader 0``); without, it is declined (the world
    changed since its plan). When nothing else can move (``force``) the follower's segment
    is declined and its next loop follows no one, the one after follows again."""
    scene = _aisle()
    for follow in (1, 0):
        fleet = _moving(scene, follow=follow)
        fleet.following(1)
        fleet.stats.counts["events"] += 1  # its world was taken before the last event
        _request(fleet, 1, 1.2)
        fleet._admit(force=False)
        o = fleet.objects[1]
        assert o.running is None
        if follow:
            assert o.request is not None and o.reply is None
            assert fleet.stats.waits[1] == {"leader 0": 1}
        else:
            assert o.request is None and o.reply.declined
    fleet = _moving(scene)
    fleet.following(1)
    _request(fleet, 1, 1.2)
    fleet._admit(force=True)
    o = fleet.objects[1]
    assert o.running is None and o.reply.declined and o.follow_off
    assert fleet.following(1) == {} and not o.follow_off
    assert sorted(fleet.following(1)) == [0]


def test_a_segment_that_keeps_clear_of_its_leader_is_admitted() -> None:
    """Load 2 follows 0 and 1; a short push that stays behind load 1 is admitted."""
    fleet = _moving(_aisle())
    fleet.following(2)
    fleet.stats.counts["events"] += 1
    _request(fleet, 2, 0.3)
    fleet._admit(force=False)
    assert fleet.objects[2].running is not None
