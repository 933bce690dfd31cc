"""Hand-over (``lamp.fleet.handover``): free robots near a moving object take the places
of its team's far robots. The pairing is checked against a brute force, the routes
against walls, and a run end to end (safety-checked)."""

from __future__ import annotations

import itertools
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import lamp
from lamp.fleet.handover import HANDOVER_GAIN, better_team, swaps
from lamp.fleet.transit import TRANSIT_RADIUS
from lamp.record.safety import check_recording, recorded_teams
from lamp.scene import scene_from_dict

routes_st = st.lists(st.one_of(st.floats(0.0, 30.0), st.just(math.inf)), max_size=5)


def _largest(team: list[float], free: list[float], gain: float) -> int:
    """The largest number of valid pairs, by trying every assignment."""
    best = 0
    for n in range(min(len(team), len(free)), 0, -1):
        for ts in itertools.combinations(range(len(team)), n):
            for fs in itertools.permutations(range(len(free)), n):
                if all(math.isfinite(free[f]) and free[f] + gain <= team[t]
                       for t, f in zip(ts, fs, strict=True)):
                    return n
    return best


@settings(max_examples=300)
@given(routes_st, routes_st, st.floats(0.0, 6.0))
def test_swaps_are_valid_as_many_as_possible_and_take_the_nearest_free_robots(
        team, free, gain) -> None:
    pairs = swaps(team, free, gain)
    ts, fs = [t for t, _ in pairs], [f for _, f in pairs]
    assert len(set(ts)) == len(ts) and len(set(fs)) == len(fs)
    for t, f in pairs:
        assert math.isfinite(free[f]) and free[f] + gain <= team[t]
    assert len(pairs) == _largest(team, free, gain)
    nearest = sorted(range(len(free)), key=lambda f: (free[f], f))[:len(pairs)]
    assert sorted(fs) == sorted(nearest)


def _hall(wall: bool) -> dict:
    """A 20 x 6 m hall, a box at (18, 3); robot 0 (its team) at (4, 3), 14 m away;
    robots 1 and 2 free at (15.5, 1.0) and (10, 3). With ``wall``, a wall along y = 1.6
    from x = 6 to the right side parts robot 1 from the box: its route goes round the
    wall's left end, 20 m."""
    obstacles = [{"type": "rectangle", "center": [13.0, 1.6], "size": [14.0, 0.2]}] if wall \
        else []
    return {"format": "lamp-scene/1", "name": "hall", "workspace": [20.0, 6.0],
            "robots": {"starts": [[4.0, 3.0], [15.5, 1.0], [10.0, 3.0]]},
            "obstacles": obstacles,
            "objects": [{"type": "rectangle", "size": [0.4, 0.3], "start": [18.0, 3.0, 0.0],
                         "goal": [18.5, 3.0, 0.0]}]}


def _better(scene, team, free, pos, poses):
    """``better_team`` for object 0, counting the readings it takes."""
    reads = []

    def observe():
        reads.append(1)
        return poses

    return better_team(scene, 0, team, free, pos, poses[0], observe), len(reads)


def test_a_far_team_robot_gives_its_place_to_the_free_robot_nearest_by_route() -> None:
    for wall, expected in ((False, [1]), (True, [2])):
        scene = scene_from_dict(_hall(wall))
        pos = np.asarray(scene.robot_starts, float)
        poses = np.asarray([o.start for o in scene.objects], float)
        assert _better(scene, [0], [1, 2], pos, poses) == (expected, 1)
    scene = scene_from_dict(_hall(False))
    pos = np.asarray(scene.robot_starts, float)
    poses = np.asarray([o.start for o in scene.objects], float)
    near = pos.copy()
    near[0] = [18.0 - TRANSIT_RADIUS + 0.5, 3.0]  # within the transit radius: stays
    assert _better(scene, [0], [1, 2], near, poses) == (None, 0)  # and reads nothing
    assert _better(scene, [0], [], pos, poses) == (None, 0)
    # a free robot only a little nearer (less than the gain) takes no place
    close = pos.copy()
    close[1], close[2] = [4.0 + HANDOVER_GAIN - 1.0, 3.0], [1.0, 3.0]
    assert _better(scene, [0], [1, 2], close, poses) == (None, 1)


def test_robots_freed_beside_an_object_take_over_from_its_team_on_the_way() -> None:
    """Box 2 (``after: [0]``) starts when box 0, at the far left, is placed, with box 0's
    robots: 15 m of transit. Box 1's robots, at the right, are freed while they drive, 2 m
    from box 2: they take over, box 0's robots stop where they are, and every box is
    placed safely."""
    box = {"type": "rectangle", "size": [0.4, 0.3]}
    d = {"format": "lamp-scene/1", "name": "handover", "workspace": [20.0, 3.0],
         "schedule": "concurrent",
         "robots": {"starts": [[0.4, 0.6], [0.4, 1.0], [19.6, 2.0], [19.6, 2.4]]},
         "objects": [{**box, "start": [1.2, 0.8, 0.0], "goal": [1.8, 0.8, 0.0]},
                     {**box, "start": [18.8, 2.2, 0.0], "goal": [17.3, 2.2, 0.0]},
                     {**box, "start": [16.0, 0.8, 0.0], "goal": [15.0, 0.8, 0.0],
                      "after": [0]}]}
    res = lamp.solve(scene_from_dict(d), "lazy", 0)
    assert res.success, [o.failure_reason for o in res.objects]
    rec = res.recording
    report = check_recording(rec.scene_model(), rec.arrays["times"], rec.arrays["robots"],
                             rec.arrays["objects"], robot_team=recorded_teams(rec))
    assert report.ok, report.summary()
    fleet = res.to_dict()["stats"]["fleet"]
    assert fleet["handed_over"] >= 1
    team = recorded_teams(rec)
    times = rec.arrays["times"]
    placed_0, placed_1, placed_2 = fleet["placed_at_s"]
    assert placed_0 < placed_1 < placed_2
    moved = np.linalg.norm(rec.arrays["objects"][:, 2, :2] - [16.0, 0.8], axis=1) > 0.05
    pushing = team[moved]
    assert np.all(pushing[:, 2:4] == 2) and np.all(pushing[:, :2] != 2)
    before = times < placed_1 - 1e-6
    assert np.any(team[before, 0] == 2)  # box 0's robots drove for box 2 first
