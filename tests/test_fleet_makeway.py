"""Making way (``lamp.fleet.makeway``): an object standing on a blocked object's goal moves
aside, so loads that swap places finish; the buffer it moves to is clear, reachable and
the nearest such position."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import shapely
from fleet_fakes import fleet_at_starts
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from run_safety import assert_safe

import lamp
from lamp.fleet.coordinator import Fleet
from lamp.fleet.makeway import (
    BUFFER_STEP,
    buffer_pose,
    standing_in_way,
    way_of,
    with_goal,
)
from lamp.fleet.state import ObjectStatus
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.primitives import Obstacle, Rectangle
from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.scene import scene_from_dict
from lamp.search.landmark import route_length

#: Two boxes in an open yard, each to go where the other stands; three robots each.
SWAP = {
    "format": "lamp-scene/1", "name": "swap", "workspace": [6.0, 4.0],
    "schedule": "concurrent",
    "robots": {"radius": 0.05, "starts": [[1.0, 1.0], [1.2, 1.0], [1.4, 1.0], [4.6, 1.0],
                                          [4.8, 1.0], [5.0, 1.0]]},
    "obstacles": [],
    "objects": [
        {"type": "rectangle", "size": [0.4, 0.4], "start": [2.0, 2.0, 0.0],
         "goal": [4.0, 2.0, 0.0]},
        {"type": "rectangle", "size": [0.4, 0.4], "start": [4.0, 2.0, 0.0],
         "goal": [2.0, 2.0, 0.0]},
    ],
}


def _scene(d: dict):
    return scene_from_dict(copy.deepcopy(d))


def test_two_loads_swapping_places_both_finish_safely() -> None:
    result = lamp.solve(_scene(SWAP), "lazy", 0)
    assert result.success, [o.failure_reason for o in result.objects]
    fleet = result.stats["fleet"]
    assert fleet["made_way"] == 1
    assert all(t is not None for t in fleet["placed_at_s"])
    assert_safe(result)


#: A dead end 1.2 m wide: object 0 deep inside is to come out, object 1 at its mouth to
#: go in past it.
DEAD_END = {
    "format": "lamp-scene/1", "name": "dead-end", "workspace": [8.0, 4.0],
    "schedule": "concurrent",
    "robots": {"radius": 0.05, "starts": [[6.5, 2.0], [6.5, 1.8], [6.5, 2.2], [7.0, 2.0],
                                          [7.0, 1.8], [7.0, 2.2]]},
    "obstacles": [{"type": "rectangle", "center": [2.5, 0.7], "size": [5.0, 1.4]},
                  {"type": "rectangle", "center": [2.5, 3.3], "size": [5.0, 1.4]}],
    "objects": [
        {"type": "rectangle", "size": [0.4, 0.4], "start": [2.0, 2.0, 0.0],
         "goal": [6.0, 3.3, 0.0]},
        {"type": "rectangle", "size": [0.4, 0.4], "start": [4.0, 2.0, 0.0],
         "goal": [1.0, 2.0, 0.0]},
    ],
}


def test_two_loads_passing_in_a_dead_end_both_finish_safely() -> None:
    result = lamp.solve(_scene(DEAD_END), "lazy", 0)
    assert result.success, [o.failure_reason for o in result.objects]
    assert result.stats["fleet"]["made_way"] == 1
    placed = result.stats["fleet"]["placed_at_s"]
    assert placed[0] < placed[1]  # the one inside came out first
    assert_safe(result)


def test_the_sequential_schedule_keeps_its_semantics_on_a_swap() -> None:
    """One after another in the file's order, nobody moves aside: the first object finds
    its goal taken (the paper's schedule is unchanged), and its failure says by whom."""
    result = lamp.solve(_scene(SWAP), "lazy", 0, schedule="sequential")
    assert not result.objects[0].success
    reason = result.objects[0].failure_reason
    assert reason.startswith("no plan found") and "object 1 stands in its way" in reason
    assert "object" not in lamp.solve(_scene(SWAP), "lazy", 0).objects[0].failure_reason


@given(dx=st.floats(-1.5, 1.5), dy=st.floats(-1.0, 1.0), r=st.floats(0.1, 0.4))
@settings(max_examples=60, deadline=None)
def test_standing_in_way_is_the_object_near_the_route(dx, dy, r) -> None:
    """On an open map a route along an axis is the straight segment; a disk's gap to it
    is the distance of its centre to the segment less its radius."""
    assume(math.hypot(1.5 + dx, 0.5 - dy) > 0.3 + r + 0.01)  # apart at their starts
    d = copy.deepcopy(SWAP)
    d["objects"][0] = {"type": "circle", "radius": 0.3, "start": [1.0, 3.0, 0.0],
                       "goal": [3.0, 3.0, 0.0]}
    d["objects"][1] = {"type": "circle", "radius": r, "start": [2.5 + dx, 2.5 + dy, 0.0],
                       "goal": [5.0, 1.0, 0.0]}
    scene = _scene(d)
    poses = np.array([o.start for o in scene.objects])
    way = way_of(scene, 0, poses[0])
    assert np.allclose(np.asarray(way.coords)[:, 1], 3.0)
    cx = min(max(2.5 + dx, 1.0), 3.0)
    gap = math.hypot(2.5 + dx - cx, 2.5 + dy - 3.0) - r
    reach = 0.3 + 2 * scene.robot_radius
    if abs(gap - reach) < 1e-3:  # the polygonal circles' tolerance
        return
    assert standing_in_way(scene, 0, way, poses, [0, 1]) == (1 if gap <= reach else None)


def test_the_first_object_along_the_route_is_the_one_in_the_way() -> None:
    d = copy.deepcopy(SWAP)
    d["objects"].append({"type": "rectangle", "size": [0.3, 0.3], "start": [3.0, 2.0, 0.0],
                         "goal": [3.0, 3.5, 0.0]})
    scene = _scene(d)
    poses = np.array([o.start for o in scene.objects])
    way = way_of(scene, 0, poses[0])
    assert standing_in_way(scene, 0, way, poses, [1, 2]) == 2
    assert standing_in_way(scene, 0, way, poses, [1]) == 1


def _clear_map(draw_obstacles: list[tuple[float, float, float]]) -> dict:
    """SWAP with the drawn circle obstacles that keep clear of its robots and objects."""
    d = copy.deepcopy(SWAP)
    taken = [shapely.Point(*p).buffer(0.1) for p in d["robots"]["starts"]]
    taken += [shapely.box(x - 0.25, y - 0.25, x + 0.25, y + 0.25)
              for o in d["objects"] for x, y, _ in (o["start"], o["goal"])]
    d["obstacles"] = [{"type": "circle", "center": [x, y], "radius": rr}
                      for x, y, rr in draw_obstacles
                      if rr <= x <= 6.0 - rr and rr <= y <= 4.0 - rr and not any(t.intersects(shapely.Point(x, y).buffer(rr)) for t in taken)]
    return d


obstacles = st.lists(st.tuples(st.floats(0.3, 5.7), st.floats(0.3, 3.7), st.floats(0.1, 0.5)),
                     max_size=6)


@given(obs=obstacles, split=st.booleans())
@settings(max_examples=25, deadline=None)
def test_a_buffer_is_clear_reachable_and_the_nearest_such_position(obs, split) -> None:
    """Against a brute force over the grid; ``split``: what will stand when the object goes
    on is a wall across the map at x = 3, so only the half of its goal (2, 2) will do."""
    d = _clear_map(obs)
    scene = _scene(d)
    j, poses = 1, np.array([o.start for o in scene.objects])
    keep = [shapely.box(1.5, 1.5, 2.5, 2.5)]
    robots = np.array(scene.robot_starts, float)
    then = (Obstacle(Rectangle((0.1, 4.0)), (3.0, 2.0, 0.0)),) if split else ()
    got = buffer_pose(scene, j, poses, robots, [3, 4, 5], keep, then)
    r = scene.robot_radius
    clear = scene.objects[j].shape.bounding_radius + 2 * r
    things = [obstacle_geometry(o) for o in scene.obstacles] + keep
    things += [to_shapely(scene.objects[0].shape, poses[0])]
    things += [shapely.Point(*p).buffer(r) for p in robots[:3]]
    W, H = scene.workspace
    now = ObjectSpace.from_scene(scene, j, poses)
    onward = ObjectSpace(scene.objects[j].shape, scene.workspace, (*scene.obstacles, *then))

    def reachable(x: float, y: float) -> bool:
        return (route_length(now, tuple(poses[j][:2]), (x, y), BUFFER_STEP) is not None
                and route_length(onward, (x, y), (2.0, 2.0), BUFFER_STEP) is not None)

    # the brute-force reference: every grid position, nearest first
    xs = np.arange(clear, W - clear + 1e-9, BUFFER_STEP)
    ys = np.arange(clear, H - clear + 1e-9, BUFFER_STEP)
    ok = sorted((math.hypot(x - poses[j][0], y - poses[j][1]), x, y) for x in xs for y in ys
                if all(g.distance(shapely.Point(x, y)) >= clear for g in things))
    if got is None:
        assert not any(reachable(x, y) for _, x, y in ok[:8])
        return
    x, y, th = got
    assert th == poses[j][2]
    assert clear - 1e-9 <= x <= W - clear + 1e-9 and clear - 1e-9 <= y <= H - clear + 1e-9
    assert all(g.distance(shapely.Point(x, y)) >= clear - 1e-9 for g in things)
    assert reachable(x, y)
    if split:
        assert x < 3.0
    first = next((c for c in ok[:8] if reachable(*c[1:])), None)
    if first is not None:  # among the eight nearest: the search finds exactly it
        assert (x, y) == pytest.approx(first[1:])


def test_no_buffer_where_the_map_has_no_room() -> None:
    d = copy.deepcopy(SWAP)
    d["workspace"] = [1.2, 0.8]
    d["robots"]["starts"] = [[0.1, 0.1], [1.1, 0.1]]
    d["objects"] = [
        {"type": "rectangle", "size": [0.3, 0.3], "start": [0.3, 0.4, 0.0],
         "goal": [0.9, 0.4, 0.0]},
        {"type": "rectangle", "size": [0.3, 0.3], "start": [0.9, 0.4, 0.0],
         "goal": [0.3, 0.4, 0.0]},
    ]
    scene = _scene(d)
    poses = np.array([o.start for o in scene.objects])
    keep = [to_shapely(scene.objects[0].shape, scene.objects[0].goal)]
    assert buffer_pose(scene, 1, poses, np.array(scene.robot_starts), [1], keep) is None


def _stuck_fleet(scene) -> Fleet:
    """A ``Fleet`` on ``scene`` whose objects are all started and all blocked, over an
    executor that only reports the start poses (no simulator)."""
    fleet = fleet_at_starts(scene)
    for k, o in enumerate(fleet.objects):
        o.status, o.rank, o.team, o.blocked_at = ObjectStatus.ACTIVE, k, [3 * k, 3 * k + 1, 3 * k + 2], (0, 0)
    return fleet


def test_the_object_on_the_first_blocked_goal_moves_aside_once_per_pair() -> None:
    scene = _scene(SWAP)
    fleet = _stuck_fleet(scene)
    assert fleet._make_way(fleet.ranked())
    mover = fleet.objects[1]  # it stands on the goal of object 0, the first
    assert mover.detour is not None and mover.blocked_at is None and mover.ready
    assert fleet.objects[0].detour is None and fleet.objects[0].blocked_at is not None
    assert not shapely.dwithin(to_shapely(scene.objects[1].shape, mover.detour),
                               to_shapely(scene.objects[0].shape, scene.objects[0].goal),
                               2 * scene.robot_radius)
    # blocked again at the same places: object 0 makes way for object 1, then nobody
    mover.detour, mover.blocked_at = None, (0, 0)
    assert fleet._make_way(fleet.ranked())
    assert fleet.objects[0].detour is not None
    fleet.objects[0].detour, fleet.objects[0].blocked_at = None, (0, 0)
    assert not fleet._make_way(fleet.ranked())
    assert fleet.stats.counts["made_way"] == 2


def test_a_detour_claims_its_way_to_the_buffer_not_to_the_goal() -> None:
    scene = _scene(SWAP)
    fleet = _stuck_fleet(scene)
    fleet._make_way(fleet.ranked())
    target = fleet.objects[1].detour
    fleet.announce(1, np.array([[4.0, 2.0, 0.0]]), np.array([target]))
    goal = to_shapely(scene.objects[1].shape, scene.objects[1].goal)
    assert not fleet.objects[1].way.intersects(goal)
    assert with_goal(scene, 1, target).objects[1].goal == tuple(float(v) for v in target)


def _waiting_in_way(goal_of_1: list[float], third: bool = False) -> Fleet:
    """SWAP (object 1's goal moved to ``goal_of_1``) with object 0 blocked, all six robots
    its team, and object 1, standing on its goal, not started (``third``: and a small box
    in a corner, not started)."""
    d = copy.deepcopy(SWAP)
    d["objects"][1]["goal"] = goal_of_1
    if third:
        d["objects"].append({"type": "rectangle", "size": [0.2, 0.2], "start": [5.5, 3.5, 0.0],
                             "goal": [5.5, 0.5, 0.0]})
    scene = _scene(d)
    fleet = fleet_at_starts(scene)
    first = fleet.objects[0]
    first.status, first.rank, first.team, first.blocked_at = ObjectStatus.ACTIVE, 0, list(range(6)), (0, 0)
    fleet.owner[:] = 0
    fleet.started = 1
    return fleet


def test_robots_go_to_the_object_in_the_way_and_it_moves_aside_when_its_own_way_is_shut():
    fleet = _waiting_in_way([2.0, 2.0, 0.0])  # its goal is where object 0 stands
    try:
        assert fleet._make_way(fleet.ranked())
        first, mover = fleet.objects
        assert mover.status == ObjectStatus.ACTIVE and mover.team == list(range(6)) and mover.ready
        assert list(fleet.owner) == [1] * 6
        assert first.team == [] and first.blocked_at is None and first.ready
        assert mover.detour is not None and fleet.stats.counts["made_way"] == 1
        first.needs_team = True  # its loop ended and waits for robots
        fleet.detour_done(1)  # aside: the robots go back to the object it made way for
        assert mover.detour is None and mover.team == [] and first.team == list(range(6))
        assert list(fleet.owner) == [0] * 6 and not first.needs_team and first.ready
    finally:
        fleet.turns.close()


def test_robots_go_to_the_object_in_the_way_which_goes_straight_on_when_its_way_is_clear():
    fleet = _waiting_in_way([4.0, 3.3, 0.0])
    try:
        assert fleet._make_way(fleet.ranked())
        mover = fleet.objects[1]
        assert mover.team == list(range(6)) and mover.detour is None
        assert fleet.stats.counts["made_way"] == 0
    finally:
        fleet.turns.close()


def test_an_object_precedence_holds_back_moves_aside_but_not_to_its_goal() -> None:
    """A teamless object that may not start yet (its goal would cut a way, precedence)
    gets a detour with the robots it is handed, even with its own way clear (with nothing
    holding it back it goes straight on: the test above); at the detour's end it gives
    the robots up and gets robots again only once it may start."""
    fleet = _waiting_in_way([4.0, 3.3, 0.0], third=True)
    fleet.cuts[1] = {2}  # (as if) object 1's goal would cut the third's way
    try:
        assert not fleet.may_start(1)
        assert fleet._make_way(fleet.ranked())
        first, mover, third = fleet.objects
        assert mover.team == list(range(6)) and mover.detour is not None
        assert fleet.stats.counts["made_way"] == 1
        # aside, with the object it made way for not waiting for robots (it got others):
        # its robots go free and it waits for robots until it may start
        third.status = ObjectStatus.ACTIVE
        fleet.detour_done(1)
        assert mover.detour is None and mover.team == [] and list(fleet.owner) == [-1] * 6
        mover.needs_team = True  # its loop waits for robots
        fleet._release()
        assert mover.team == [] and mover.needs_team
        third.status = ObjectStatus.PLACED  # now nothing holds it back
        fleet._release()
        assert mover.team and not mover.needs_team
    finally:
        fleet.turns.close()


def test_one_robot_swaps_two_loads() -> None:
    d = copy.deepcopy(SWAP)
    d["robots"]["starts"] = [[1.0, 1.0]]
    result = lamp.solve(_scene(d), "lazy", 0)
    assert result.success, [o.failure_reason for o in result.objects]
    assert_safe(result)
