"""Implied precedence (``lamp.fleet.precedence``): a load whose goal would cut another's
way starts after it; pairs that cut each other get no precedence."""

from __future__ import annotations

import copy

from run_safety import assert_safe

import lamp
from lamp.fleet.precedence import goal_cuts
from lamp.scene import scene_from_dict

#: A wall with a 1 m gap at its top; object 0's goal is in the gap, object 1 must pass
#: through it to its goal on the other side.
GAP = {
    "format": "lamp-scene/1", "name": "gap-goal", "workspace": [8.0, 6.0],
    "schedule": "concurrent",
    "robots": {"radius": 0.05, "starts": [[0.4, 0.4], [0.6, 0.4], [0.8, 0.4], [0.4, 5.6],
                                          [0.6, 5.6], [0.8, 5.6]]},
    "obstacles": [{"type": "rectangle", "center": [4.0, 2.5], "size": [0.2, 5.0]}],
    "objects": [
        {"type": "rectangle", "size": [0.4, 0.4], "start": [2.5, 5.5, 0.0],
         "goal": [4.0, 5.5, 0.0]},
        {"type": "rectangle", "size": [0.4, 0.4], "start": [2.0, 1.0, 0.0],
         "goal": [6.0, 1.0, 0.0]},
    ],
}


def _scene(d: dict):
    return scene_from_dict(copy.deepcopy(d))


def test_a_goal_in_the_gap_cuts_the_way_through_it_and_nothing_else() -> None:
    scene = _scene(GAP)
    assert goal_cuts(scene, scene.object_starts()) == {0: frozenset({1}), 1: frozenset()}
    wide = copy.deepcopy(GAP)  # a 2 m gap: room to pass beside the placed box
    wide["obstacles"][0] = {"type": "rectangle", "center": [4.0, 2.0], "size": [0.2, 4.0]}
    scene = _scene(wide)
    assert goal_cuts(scene, scene.object_starts()) == {0: frozenset(), 1: frozenset()}


#: Two walls, a 1 m gap at the top of the left one and at the bottom of the right one;
#: object 0 (left room) has its goal in the right gap, object 1 (right room) in the left
#: gap: each goal cuts the other's way.
TWO_GAPS = {
    "format": "lamp-scene/1", "name": "two-gaps", "workspace": [10.0, 6.0],
    "schedule": "concurrent",
    "robots": {"radius": 0.05, "starts": [[0.4, 0.4], [0.6, 0.4], [0.8, 0.4], [9.2, 5.6],
                                          [9.4, 5.6], [9.6, 5.6]]},
    "obstacles": [{"type": "rectangle", "center": [3.0, 2.5], "size": [0.2, 5.0]},
                  {"type": "rectangle", "center": [7.0, 3.5], "size": [0.2, 5.0]}],
    "objects": [
        {"type": "rectangle", "size": [0.4, 0.4], "start": [1.5, 3.0, 0.0],
         "goal": [7.0, 0.5, 0.0]},
        {"type": "rectangle", "size": [0.4, 0.4], "start": [8.5, 3.0, 0.0],
         "goal": [3.0, 5.5, 0.0]},
    ],
}


def test_loads_that_cut_each_other_get_no_precedence() -> None:
    scene = _scene(TWO_GAPS)
    assert goal_cuts(scene, scene.object_starts()) == {0: frozenset(), 1: frozenset()}
    one_way = copy.deepcopy(TWO_GAPS)  # object 1's goal in the middle room: one cut left
    one_way["objects"][1]["goal"] = [5.0, 3.0, 0.0]
    scene = _scene(one_way)
    assert goal_cuts(scene, scene.object_starts()) == {0: frozenset({1}), 1: frozenset()}


def test_a_goal_where_another_stands_is_no_cut() -> None:
    """Places swapped (each goal where the other stands): each waits for the other to
    leave anyway, and one makes way (``fleet.makeway``)."""
    d = copy.deepcopy(GAP)
    d["obstacles"] = []
    d["objects"][0]["start"], d["objects"][0]["goal"] = [2.0, 2.0, 0.0], [4.0, 2.0, 0.0]
    d["objects"][1]["start"], d["objects"][1]["goal"] = [4.0, 2.0, 0.0], [2.0, 2.0, 0.0]
    scene = _scene(d)
    assert goal_cuts(scene, scene.object_starts()) == {0: frozenset(), 1: frozenset()}


def test_the_load_through_the_gap_goes_first_and_both_are_placed() -> None:
    result = lamp.solve(_scene(GAP), "lazy", 0)
    assert result.success, [o.failure_reason for o in result.objects]
    first, second = result.stats["fleet"]["placed_at_s"][1], result.stats["fleet"]["placed_at_s"][0]
    assert first < second
    assert_safe(result)
