"""A planner that finds no plan while other objects move (``Fleet.plan_failed``): the
space it needs (``teams.needed_space``), who stands in it, and when it plans again
(``fleet.blocked``)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import shapely
from fleet_fakes import fleet_at_starts
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.fleet.blocked import BLOCKED_WAKE_EVENTS
from lamp.fleet.state import ObjectStatus
from lamp.fleet.teams import needed_space
from lamp.geometry.shapes import to_shapely
from lamp.scene import scene_from_dict
from lamp.scene.model import Circle, Rectangle

R = 0.05


def _brute_distance(shape, pose, goal, team, claim, point) -> float:
    """The distance from ``point`` to the parts ``needed_space`` grows by a robot
    diameter, each taken on its own: the hull of the footprints at ``pose`` and ``goal``,
    the hull of the footprint at ``pose`` and the robots; and to ``claim`` (not grown)."""
    p = shapely.Point(point)
    at, to = to_shapely(shape, pose), to_shapely(shape, goal)
    way = shapely.union(at, to).convex_hull
    approach = shapely.union(at, shapely.MultiPoint([tuple(t) for t in team])).convex_hull
    d = min(way.distance(p), approach.distance(p)) - 2 * R
    return min(d, claim.distance(p)) if claim is not None else d


@settings(max_examples=60)
@given(st.integers(0, 2**31 - 1), st.integers(0, 3), st.booleans(), st.booleans())
def test_needed_space_is_the_way_the_approach_and_the_claim(seed, n, disk, with_claim):
    """``needed_space`` holds every point within a robot diameter of the object's way (the
    hull of its footprints now and at its goal) or of its robots' approach (the hull of
    its footprint and the robots), and every point of the claim; no point farther from
    all of them (brute force, each part on its own; a point within 1 mm of the edge may
    fall either way: the buffers are polygons)."""
    rng = np.random.default_rng(seed)
    shape = Circle(0.2) if disk else Rectangle((0.4, 0.25))
    pose, goal = rng.uniform(1, 5, 3), rng.uniform(1, 5, 3)
    team = rng.uniform(0, 6, (n, 2))
    x0, y0 = rng.uniform(0, 5, 2)
    claim = shapely.box(x0, y0, x0 + rng.uniform(0.1, 1), y0 + rng.uniform(0.1, 1)) \
        if with_claim else None
    space = needed_space(shape, pose, goal, team, R, claim)
    for point in rng.uniform(-0.5, 6.5, (300, 2)):
        d = _brute_distance(shape, pose, goal, team, claim, point)
        if abs(d) > 1e-3:
            assert space.intersects(shapely.Point(point)) == (d < 0), (point, d)
    for part in [to_shapely(shape, pose), to_shapely(shape, goal), *(
            shapely.Point(t).buffer(R) for t in team)]:
        assert space.contains(part)


def _blocked_fleet(third_box: bool = False):
    """A 6 x 3 m room: box 0 pushed along y = 0.8 by robots 0 and 1, box 1 along y = 2.2
    by robots 2 and 3; robot 2 stands in box 0's way (at x = 2.5); with ``third_box`` a
    box 2, not yet started, stands in it too (at x = 3.2). Box 0's planner has just found
    no plan: (fleet, robot positions, box 0's state)."""
    box = {"type": "rectangle", "size": [0.4, 0.3]}
    objects = [{**box, "start": [1.2, 0.8, 0.0], "goal": [3.8, 0.8, 0.0]},
               {**box, "start": [3.3, 2.2, 0.0], "goal": [5.0, 2.2, 0.0]}]
    if third_box:
        objects.append({**box, "start": [3.2, 0.8, 0.0], "goal": [5.0, 1.5, 0.0]})
    scene = scene_from_dict({
        "format": "lamp-scene/1", "name": "blocked", "workspace": [6.0, 3.0],
        "schedule": "concurrent",
        "robots": {"radius": R, "starts": [[0.6, 0.6], [0.6, 1.0], [2.5, 0.8], [2.8, 2.2]]},
        "objects": objects})
    fleet = fleet_at_starts(scene)
    fleet.turns = SimpleNamespace(pause=lambda k: None)  # no loop threads here
    for k, team in enumerate(([0, 1], [2, 3])):
        o = fleet.objects[k]
        o.status, o.rank, o.team = ObjectStatus.ACTIVE, k, team
        fleet.owner[team] = k
    assert fleet.plan_failed(0) is False  # waits for a change
    return fleet, fleet.executor.robot_positions, fleet.objects[0]


def test_a_blocked_planner_wakes_once_what_stood_in_its_way_has_left() -> None:
    """``Fleet.plan_failed`` (``blocked.note_blocked``) notes the objects standing in the
    space its object needs (body or sub-team robot: box 1, by its robot 2);
    ``wake_blocked`` wakes it at the
    first event at which one of them has left that space, before ``BLOCKED_WAKE_EVENTS``
    events; not while it only moves within it, and not between events."""
    fleet, robots, o = _blocked_fleet()
    assert o.blockers == {1} and o.blocked_at == (0, 0)

    def event(position=None) -> bool:
        """Robot 2 moves to ``position``; one event passes; whether box 0 woke."""
        if position is not None:
            robots[2] = position
        fleet.stats.counts["events"] += 1
        fleet._wake_blocked()
        return o.blocked_at is None

    assert not event()  # it still stands there
    assert not event((3.1, 0.8))  # it moved along the way, still in it
    robots[2] = (2.5, 2.7)  # it left: looked at only at the next event
    fleet._wake_blocked()
    assert o.blocked_at is not None
    assert event()
    assert o.replan and o.ready
    assert fleet.stats.counts["events"] < BLOCKED_WAKE_EVENTS


def test_with_nobody_in_its_way_a_blocked_planner_waits_for_the_events() -> None:
    """What blocks a planner may be no object's (a robot of nobody's team, the
    obstacles): with no object standing in the space it needs it plans again after
    ``BLOCKED_WAKE_EVENTS`` events, as before, however the others move meanwhile."""
    fleet, robots, o = _blocked_fleet()
    robots[2] = (2.5, 2.7)
    fleet.plan_failed(0)
    assert o.blockers == frozenset()
    for n in range(1, BLOCKED_WAKE_EVENTS + 1):
        robots[3] = (2.8 + 0.1 * n, 2.2)
        fleet.stats.counts["events"] += 1
        fleet._wake_blocked()
        assert (o.blocked_at is None) == (n == BLOCKED_WAKE_EVENTS)


def test_one_blocker_gone_wakes_it_while_another_stays() -> None:
    """Two objects in its way (box 1 by its robot 2, box 2 by its body, not yet started):
    the first event at which one of them has left wakes it, the other still standing
    there."""
    fleet, robots, o = _blocked_fleet(third_box=True)
    assert o.blockers == {1, 2}
    robots[2] = (2.5, 2.7)
    fleet.stats.counts["events"] += 1
    fleet._wake_blocked()
    assert o.blocked_at is None and o.replan
