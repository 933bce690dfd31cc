"""``static_field``: a robot-space window's static base copied from tiles filled once is,
bit for bit, the window computed alone; spaces built on it are unchanged."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pages import resident_bytes
from test_robot_space import _random_obstacles

from lamp.geometry.clearance_kernels import fill_field
from lamp.geometry.clearance_layers import clear_base_layers, grid_nodes, window_nodes
from lamp.geometry.geometry_set import GeometrySet
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.robot_space import RobotSpace
from lamp.geometry.static_field import TILE, StaticField, window_base
from lamp.planners.team import team_scene
from lamp.scene.model import Circle, Rectangle, Scene, SceneObject


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), h=st.sampled_from([0.01, 0.013]),
       cap=st.sampled_from([0.1, 0.3]), windows=st.integers(1, 4))
def test_windows_from_tiles_are_the_windows_computed_alone(seed, h, cap, windows) -> None:
    rng = np.random.default_rng(seed)
    ws = (float(rng.uniform(1.0, 3.2)), float(rng.uniform(1.0, 3.2)))
    obs = tuple(o for o in _random_obstacles(rng, 8)
                if o.pose[0] < ws[0] and o.pose[1] < ws[1])
    n_nodes = grid_nodes(ws, h)
    field = StaticField(ws, obs, h, cap, n_nodes)
    geo = GeometrySet(obs)
    for _ in range(windows):  # windows across tile edges, at the border, the whole grid
        x0, y0 = rng.uniform(-0.2, ws[0]), rng.uniform(-0.2, ws[1])
        w = (x0, y0, x0 + rng.uniform(0.0, ws[0]), y0 + rng.uniform(0.0, ws[1]))
        nodes = window_nodes(ws, h, w if rng.random() < 0.8 else None)
        got = field.window(nodes)
        assert got.flags.writeable
        np.testing.assert_array_equal(got, window_base(ws, obs, geo, h, cap, nodes))
    # only the tiles some window touched are filled
    assert field.nbytes == int(field.filled.sum()) * TILE * TILE * 8
    assert field.filled.any()


def test_robot_spaces_over_the_tiles_equal_spaces_computed_alone() -> None:
    rng = np.random.default_rng(3)
    ws = (3.0, 2.5)
    obs = _random_obstacles(rng, 10)
    objects = _random_obstacles(rng, 3)
    window = (0.4, 0.3, 2.1, 1.9)
    clear_base_layers()
    tiled = RobotSpace(ws, obs, 0.05, overlay=objects, window=window)
    static = RobotSpace(ws, obs, 0.05, window=window)
    nodes = tiled.window_nodes
    geo = GeometrySet(tuple(obs))
    base = window_base(ws, tuple(obs), geo, tiled.resolution, tiled.cap, nodes)
    np.testing.assert_array_equal(static.field, base)
    alone = base.copy()
    over = GeometrySet(tuple(objects))
    fill_field(alone, tiled.resolution, tiled.cap, over.circles, over.verts, over.ptr,
               nodes[0], nodes[1])
    np.testing.assert_array_equal(tiled.field, alone)
    assert not tiled.field.flags.writeable and not static.field.flags.writeable


def test_team_scenes_keep_the_maps_obstacles_as_their_fixed_part() -> None:
    """A team scene's other robots are obstacles laid over the map's: its spaces read as a
    space of all its obstacles, and share the map's base (the same tuple object)."""
    rng = np.random.default_rng(5)
    ws = (24.0, 20.0)  # large enough that object spaces fill tiles on demand
    obs = tuple(_random_obstacles(rng, 6))
    scene = Scene("t", ws, ((1.0, 1.0), (1.4, 1.0), (0.6, 1.2)),
                  (SceneObject(Rectangle((0.4, 0.3)), (1.0, 0.6, 0.0), (1.5, 1.2, 0.0)),
                   SceneObject(Circle(0.15), (0.4, 0.5, 0.0), (0.5, 1.0, 0.0))), obs)
    team = team_scene(scene, [0, 1], {2: np.array([0.6, 1.2])})
    assert team.fixed_obstacles is scene.obstacles and len(team.obstacles) == len(obs) + 1
    again = team_scene(team, [0], {1: np.array([1.4, 1.0])})
    assert again.fixed_obstacles is scene.obstacles
    # a scene whose obstacles no longer start with its fixed part: all of them are fixed
    assert replace(team, obstacles=obs[1:]).fixed_obstacles == obs[1:]
    window = (0.0, 0.0, 2.0, 1.5)
    clear_base_layers()
    got = RobotSpace.from_scene(team, window=window)
    flat = RobotSpace(ws, team.obstacles, team.robot_radius, window=window,
                      overlay=[o for o in got.overlay_obstacles
                               if o not in team.obstacles])
    np.testing.assert_array_equal(got.field, flat.field)
    a, b = ObjectSpace.from_scene(team, 0), ObjectSpace.from_scene(again, 0)
    assert a.grid._base is not None and a.grid._base is b.grid._base


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), kept=st.integers(1, 6), windows=st.integers(2, 8))
def test_a_field_over_its_budget_drops_tiles_and_gives_the_same_windows(seed, kept, windows
                                                                        ) -> None:
    """With room for ``kept`` tiles, every window is still bit for bit the window computed
    alone, tiles beyond the budget are handed back (at most ``kept``, or as many as the
    widest window so far reads, stay filled) and a dropped tile reads as zeros until
    filled again."""
    rng = np.random.default_rng(seed)
    h, cap = 0.01, 0.3
    ws = (float(rng.uniform(2.6, 4.0)), float(rng.uniform(2.6, 4.0)))  # 2-3 tiles a side
    obs = tuple(o for o in _random_obstacles(rng, 8)
                if o.pose[0] < ws[0] and o.pose[1] < ws[1])
    field = StaticField(ws, obs, h, cap, grid_nodes(ws, h), budget=kept * TILE * TILE * 8)
    geo = GeometrySet(obs)
    widest = 0
    for _ in range(windows):
        x0, y0 = rng.uniform(0.0, ws[0]), rng.uniform(0.0, ws[1])
        w = (x0, y0, x0 + rng.uniform(0.0, 2.0), y0 + rng.uniform(0.0, 2.0))
        nodes = window_nodes(ws, h, w)
        np.testing.assert_array_equal(field.window(nodes), window_base(ws, obs, geo, h, cap,
                                                                        nodes))
        i0, j0, i1, j1 = nodes
        widest = max(widest, (j1 // TILE - j0 // TILE + 1) * (i1 // TILE - i0 // TILE + 1))
        assert int(field.filled.sum()) <= max(kept, widest)
        assert field.filled[j0 // TILE:j1 // TILE + 1, i0 // TILE:i1 // TILE + 1].all()
    ntx = field.filled.shape[1]
    for flat in np.flatnonzero(~field.filled.ravel()):  # handed back (or never filled)
        assert resident_bytes(field._store[flat]) == 0 and not field._store[flat].any()
    assert ntx >= 2
