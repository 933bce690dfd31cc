"""Parking (``lamp.fleet.parking``): the spots it picks keep what it promises, and with
``fleet_park_clear`` set (off by default) a team whose object is placed beside another
load's goal moves away, safely, without delaying its placement time."""

from __future__ import annotations

import copy

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.ndimage import distance_transform_edt

import lamp
from lamp.fleet.parking import PARK_OPEN, in_the_way, parking_targets
from lamp.fleet.transit import free_grid
from lamp.planners.bystanders import BYSTANDER_GAP
from lamp.record.safety import check_recording, recorded_teams
from lamp.scene import scene_from_dict
from lamp.scene.model import Obstacle, Rectangle, Scene, SceneObject

R = 0.1
CLEAR = 1.0


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.floats(0.5, 5.5), st.floats(0.5, 3.5)), min_size=1, max_size=5),
       st.tuples(st.floats(1.0, 5.0), st.floats(1.0, 3.0), st.floats(0.3, 2.0),
                 st.floats(0.3, 1.5)),
       st.floats(0.5, 5.5))
def test_parking_spots_are_open_clear_and_apart(robots, keep_box, wall_x) -> None:
    wall = Obstacle(Rectangle((0.2, 2.0)), (wall_x, 1.0, 0.0))
    scene = Scene("yard", (6.0, 4.0), tuple(robots),
                  (SceneObject(Rectangle((0.3, 0.3)), (5.7, 3.7, 0.0), (5.7, 3.7, 0.0)),),
                  (wall,), robot_radius=R)
    poses = np.array(scene.object_starts())
    grid = free_grid(scene, poses)
    x, y, w, h = keep_box
    keep = shapely.box(x - w / 2, y - h / 2, x + w / 2, y + h / 2)
    pos = np.array(robots, float)
    movers = in_the_way(keep, pos, CLEAR)
    targets, moved, _ = parking_targets(grid, keep, pos, movers, R, CLEAR)
    assert not (moved & ~movers).any()
    np.testing.assert_array_equal(targets[~moved], pos[~moved])  # the others stay
    openness = distance_transform_edt(grid.free) * grid.cell
    for i in np.flatnonzero(moved):
        t = targets[i]
        j, c = int(t[1] // grid.cell), int(t[0] // grid.cell)
        assert grid.free[j, c] and openness[j, c] >= PARK_OPEN + grid.cell
        assert keep.distance(shapely.Point(t)) >= CLEAR - 1e-9
        for m in range(len(pos)):  # apart from every spot taken and every robot staying
            if m != i and (moved[m] or not movers[m]):
                assert np.linalg.norm(targets[m] - t) >= 2 * R + BYSTANDER_GAP - 1e-9


#: Two boxes in one room, their goals side by side: the first box's team ends its last
#: push beside the second box's goal while the second is still on its way.
PARK = {
    "format": "lamp-scene/1", "name": "park", "workspace": [6.0, 4.0],
    "schedule": "concurrent",
    "robots": {"starts": [[0.4, 0.6], [0.4, 1.2], [5.6, 3.4], [5.6, 2.8]]},
    "objects": [
        {"type": "rectangle", "size": [0.4, 0.3], "start": [1.2, 1.0, 0.0],
         "goal": [2.6, 1.6, 0.0]},
        {"type": "rectangle", "size": [0.4, 0.3], "start": [5.0, 3.0, 0.0],
         "goal": [2.6, 2.5, 0.0]},
    ],
}


def test_a_placed_objects_team_parks_out_of_the_next_goal_safely() -> None:
    scene = scene_from_dict(copy.deepcopy(PARK))
    assert lamp.solve(scene, "lazy", 0).to_dict()["stats"]["fleet"]["parking_moves"] == 0
    result = lamp.solve(scene, "lazy", 0, params={"fleet_park_clear": CLEAR})
    assert result.success
    fleet = result.to_dict()["stats"]["fleet"]
    assert fleet["parking_moves"] >= 1
    first, last = fleet["placed_at_s"]
    assert first < last and abs(last - result.makespan_s) < 1e-3  # parking came after
    rec = result.recording
    report = check_recording(rec.scene_model(), rec.arrays["times"], rec.arrays["robots"],
                             rec.arrays["objects"], robot_team=recorded_teams(rec))
    assert report.ok, report.summary()
