"""``fleet.objects.sub_scene`` with ``near``: the world an object's loop plans in holds the
other teams' robots standing within ``near`` of one of its own as disk obstacles, no
others, in robot order, after the map's own obstacles (its ``fixed`` part)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.fleet.config import PLAN_NEAR, FleetConfig
from lamp.fleet.objects import sub_scene
from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, SceneObject

WALL = Obstacle(Rectangle((0.2, 4.0)), (6.0, 5.0, 0.0))


def _scene(starts: list[tuple[float, float]]) -> Scene:
    return Scene("near", (12.0, 10.0), tuple(starts),
                 (SceneObject(Circle(0.2), (1.0, 1.0, 0.0), (2.0, 2.0, 0.0)),), (WALL,))


@settings(max_examples=60, deadline=None)
@given(points=st.lists(st.tuples(st.floats(0.1, 11.9), st.floats(0.1, 9.9)), min_size=2,
                       max_size=12, unique=True),
       team_size=st.integers(1, 3), near=st.sampled_from([0.0, 1.0, 3.0, math.inf]))
def test_only_robots_near_the_team_stand_as_obstacles(points, team_size, near) -> None:
    scene = _scene(points)
    team = list(range(min(team_size, len(points) - 1)))
    pos = np.asarray(points, float)
    got = sub_scene(scene, team, pos, near)
    mine = pos[team]
    want = [i for i in range(len(points)) if i not in team
            and np.min(np.hypot(*(mine - pos[i]).T)) <= near]
    assert got.fixed_obstacles is scene.obstacles
    disks = got.obstacles[len(scene.obstacles):]
    assert [d.pose[:2] for d in disks] == [tuple(pos[i]) for i in want]
    assert all(isinstance(d.shape, Circle) and d.shape.radius == scene.robot_radius
               for d in disks)
    assert got.robot_starts == tuple(tuple(p) for p in pos[team])
    if math.isinf(near):  # the default of old: every other robot
        assert len(disks) == len(points) - len(team)


def test_the_default_reach_is_the_documented_constant() -> None:
    assert FleetConfig().plan_near == PLAN_NEAR == math.inf
