"""Windows and tiles: robot spaces over a window of the map, Gspi lattices on them, and the
object space's tiled distance grid, each against the whole-map implementation (which the
other test files check against Shapely), plus an end-to-end run on a map larger than the
window."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mrmp_checker import check_plan
from test_object_space import object_shapes, truth
from test_object_space import obstacles as object_obstacles
from test_robot_space import _random_obstacles

from lamp.geometry.distance_tiles import TILE, DistanceTiles
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp import plan_paths
from lamp.mrmp.distance_field import Lattice
from lamp.planners.config import PlannerConfig
from lamp.planners.task import WINDOW_MARGIN, ManipulationTask
from lamp.scene.loader import scene_from_dict
from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, SceneObject
from lamp.search.lattice import ObjectLattice

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from bench_scale import pillar_scene  # noqa: E402

W, H = 2.0, 1.5
R = 0.05

window = st.tuples(st.floats(0.0, 1.5), st.floats(0.0, 1.0), st.floats(0.1, 2.5),
                   st.floats(0.1, 2.0)).map(lambda t: (t[0], t[1], t[0] + t[2], t[1] + t[3]))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), k=st.integers(0, 10), win=window)
def test_window_space_agrees_with_the_whole_map(seed, k, win) -> None:
    rng = np.random.default_rng(seed)
    obs = _random_obstacles(rng, k)
    full = RobotSpace((W, H), obs, radius=R, overlay=obs[:1])
    part = RobotSpace((W, H), obs, radius=R, overlay=obs[:1], window=win)
    i0, j0, i1, j1 = part.window_nodes
    assert part.origin == (i0, j0) and part.shape == (j1 - j0 + 1, i1 - i0 + 1)
    # the window's nodes hold the whole grid's values, bit for bit
    assert np.array_equal(part.field, full.field[j0 : j1 + 1, i0 : i1 + 1])
    x0, y0, x1, y1 = part.window
    assert x0 <= max(0.0, win[0]) + 1e-9 and y0 <= max(0.0, win[1]) + 1e-9
    assert x1 >= min(W, win[2]) - 1e-9 or x1 >= W - 0.01
    p = rng.uniform([-0.1, -0.1], [W + 0.1, H + 0.1], size=(3000, 2))
    lo_f, lo_p = full.clearance_lower(p), part.clearance_lower(p)
    h = part.resolution
    inside = ((p[:, 0] >= x0) & (p[:, 0] <= x1 - h) & (p[:, 1] >= y0) & (p[:, 1] <= y1 - h))
    # never above the whole map's bound (so never free where the whole map is not) ...
    assert np.all(lo_p <= lo_f)
    # ... and the same wherever the point's cell lies in the window
    assert np.array_equal(lo_p[inside], lo_f[inside])
    assert np.array_equal(part.clearance(p)[inside], full.clearance(p)[inside])
    assert np.all(np.isneginf(part.clearance(p)[~inside & ((p[:, 0] < x0) | (p[:, 1] < y0))]))
    free = part.is_free(p)
    assert np.all(full.is_free(p)[free])
    assert np.all(part.clearance(p[free], exact=True) >= part.threshold)
    # exact queries do not depend on the window
    assert np.array_equal(part.clearance(p, exact=True), full.clearance(p, exact=True))
    # waiting spots: free, inside the window, at most as close as the whole map's
    q = rng.uniform([x0, y0], [x1, y1])
    spot = part.nearest_free(q, max_distance=0.5)
    if spot is not None:
        assert full.is_free(spot[None], exact=True)[0]
        assert x0 - 1e-9 <= spot[0] <= x1 + 1e-9 and y0 - 1e-9 <= spot[1] <= y1 + 1e-9
        best = full.nearest_free(q, max_distance=0.5, through_free=False)
        assert best is not None and np.hypot(*(best - q)) <= np.hypot(*(spot - q)) + 1e-9


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), k=st.integers(0, 8), win=window,
       step=st.sampled_from([0.05, 0.03, 0.02]))
def test_window_lattice_is_the_whole_lattice_cut_to_the_window(seed, k, win, step) -> None:
    obs = _random_obstacles(np.random.default_rng(seed), k)
    full = Lattice(RobotSpace((W, H), obs, radius=R), step)
    part = Lattice(RobotSpace((W, H), obs, radius=R, window=win), step)
    index = {tuple(np.round(c / step).astype(int)): n for n, c in enumerate(full.coords)}
    ids = np.array([index[tuple(np.round(c / step).astype(int))] for c in part.coords],
                   dtype=np.int64)
    assert np.array_equal(full.coords[ids], part.coords)  # same places, bit for bit
    mapped = np.where(part.nbr >= 0, ids[np.maximum(part.nbr, 0)], -1)
    whole = full.nbr[ids]
    # every window edge is an edge of the whole lattice; only edges leaving the window drop
    assert np.all((mapped == whole) | (mapped == -1))
    x0, y0, x1, y1 = part.window
    c = part.coords
    interior = ((c[:, 0] >= x0 + step) & (c[:, 0] <= x1 - step)
                & (c[:, 1] >= y0 + step) & (c[:, 1] <= y1 - step))
    assert np.array_equal(mapped[interior], whole[interior])
    # every whole-map node inside the window is there
    e = 1e-9
    inw = ((full.coords[:, 0] >= x0 - e) & (full.coords[:, 0] <= x1 + e)
           & (full.coords[:, 1] >= y0 - e) & (full.coords[:, 1] <= y1 + e))
    assert inw.sum() == part.V


def test_gspi_in_a_window_plans_valid_paths_and_the_whole_window_changes_nothing() -> None:
    obs = tuple(Obstacle(Circle(0.12), (x, y, 0.0)) for x, y in
                ((2.0, 2.0), (3.1, 2.6), (2.6, 3.4), (5.0, 5.0)))
    obj = SceneObject(Rectangle((0.4, 0.3)), (2.6, 2.0, 0.3), (6.0, 6.0, 0.0))
    scene = Scene("window", (8.0, 8.0), ((1.9, 1.5), (3.0, 1.7), (3.3, 2.2)), (obj,), obs, R)
    S = np.array(scene.robot_starts)
    G = np.array([[2.3, 2.55], [3.05, 2.0], [2.2, 1.7]])
    full = plan_paths(scene, S, G, time_limit=30.0)
    whole = RobotSpace.from_scene(scene, window=(0.0, 0.0, 8.0, 8.0))
    assert whole.covers_workspace
    same = plan_paths(scene, S, G, time_limit=30.0, space=whole)
    assert full.success and np.array_equal(full.paths, same.paths)
    part = RobotSpace.from_scene(scene, window=(0.5, 0.5, 4.5, 4.5))
    plan = plan_paths(scene, S, G, time_limit=30.0, space=part)
    assert plan.success and plan.stats["lattice_nodes"] < full.stats["lattice_nodes"] / 3
    check_plan(scene, S, G, plan, require_success=True)


def test_task_windows_cover_small_maps_and_stay_local_on_large_ones() -> None:
    small = scene_from_dict(pillar_scene(4))
    large = scene_from_dict(pillar_scene(30))
    for scene in (small, large):
        task = ManipulationTask(scene, 0, scene.object_starts(), None, PlannerConfig())
        rng = np.random.default_rng(1)
        L = scene.workspace[0]
        for _ in range(50):
            q = np.r_[rng.uniform(0.3, L - 0.3, 2), rng.uniform(-3, 3)]
            pts = q[:2] + rng.uniform(-0.8, 0.8, (3, 2))
            x0, y0, x1, y1 = task.window(q, pts)
            space = task.robot_space_at(q, (x0, y0, x1, y1))
            if L <= 4.0:
                assert space.covers_workspace
            else:
                assert x1 - x0 <= 8.0 and y1 - y0 <= 8.0
            lo = np.minimum(pts.min(axis=0), q[:2]) - WINDOW_MARGIN
            hi = np.maximum(pts.max(axis=0), q[:2]) + WINDOW_MARGIN
            assert x0 <= max(0.0, lo[0]) and y0 <= max(0.0, lo[1])
            assert x1 >= min(L, hi[0]) and y1 >= min(L, hi[1])
            x2, y2, x3, y3 = task.window(q, pts, 2.0)
            assert x2 <= x0 and y2 <= y0 and x3 >= x1 and y3 >= y1


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(obs=st.lists(object_obstacles(), min_size=0, max_size=6),
       cap=st.sampled_from([0.05, 0.2, 0.5]), seed=st.integers(0, 2**31 - 1))
def test_tiles_on_demand_match_the_whole_grid_capped(obs, cap, seed) -> None:
    whole = DistanceTiles((2.0, 2.0), obs, 0.004)
    tiles = DistanceTiles((2.0, 2.0), obs, 0.004, cap=cap, full_grid_cells=0)
    assert not whole.capped and tiles.capped
    rng = np.random.default_rng(seed)
    p = rng.uniform(0.0, 2.0, size=(400, 2))
    ny, nx = whole.shape
    rows = np.minimum((p[:, 1] / 0.004).astype(int), ny - 1)
    cols = np.minimum((p[:, 0] / 0.004).astype(int), nx - 1)
    # nothing is filled before it is asked for: reads are -inf ("not free")
    assert np.all(np.isneginf(tiles.values(rows, cols))) and (tiles.table < 0).all()
    tiles.ensure(p[:200], 0.0)
    got, ref = tiles.values(rows[:200], cols[:200]), whole.values(rows[:200], cols[:200])
    two_h = whole.two_h
    # the whole grid's value, capped: exact (to float32, rounded down) below the cap, a
    # lower bound above it
    want = np.minimum(ref + two_h, cap) - two_h
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-7)
    assert np.all(got <= want) and np.all(got <= ref)
    # tiles not asked for are not filled
    filled = int((tiles.table >= 0).sum())
    assert filled <= tiles.table.size
    span = TILE * 0.004
    touched = {(int(y // span), int(x // span)) for x, y in p[:200]}
    assert filled >= len(touched)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(shape=object_shapes, obs=st.lists(object_obstacles(), min_size=0, max_size=6),
       seed=st.integers(0, 2**31 - 1))
def test_object_space_on_capped_tiles_is_conservative(shape, obs, seed) -> None:
    exact = ObjectSpace(shape, (2.0, 2.0), obs)
    with pytest.raises(ValueError, match="min_grid_cap"):
        ObjectSpace(shape, (2.0, 2.0), obs, grid=DistanceTiles(
            (2.0, 2.0), obs, 0.004, cap=0.5 * exact.min_grid_cap, full_grid_cells=0))
    # the tightest cap allowed
    grid = DistanceTiles((2.0, 2.0), obs, 0.004, cap=exact.min_grid_cap, full_grid_cells=0)
    space = ObjectSpace(shape, (2.0, 2.0), obs, grid=grid)
    rng = np.random.default_rng(seed)
    poses = rng.uniform([0, 0, -math.pi], [2.0, 2.0, math.pi], size=(40, 3))
    free, clear = space.pose_free(poses), space.clearance(poses)
    assert np.all(clear <= exact.clearance(poses) + 1e-12)
    collides, true_clear = truth(space, poses)
    assert not np.any(free & collides)
    # true clearance beyond the band is still free, the cap being above it
    assert np.all(free[~collides & (true_clear > space.band + 1e-4)])
    a = rng.uniform([0.3, 0.3, -math.pi], [1.7, 1.7, math.pi], size=(8, 3))
    b = a + rng.uniform([-0.3, -0.3, -1.0], [0.3, 0.3, 1.0], size=(8, 3))
    ok = space.motions_free(a, b)
    t = np.linspace(0.0, 1.0, 101)
    from lamp.geometry import se2

    for i in range(len(a)):
        if truth(space, se2.interpolate(a[i], b[i], t))[0].any():
            assert not ok[i]


def test_object_lattice_on_tiles_matches_the_whole_grid() -> None:
    obs = (Obstacle(Circle(0.15), (0.7, 0.6, 0.0)), Obstacle(Rectangle((0.1, 0.6)), (1.2, 0.9, 0.3)))
    shape = Rectangle((0.3, 0.16))
    ws = (1.6, 1.3)
    # a cap above the map's diagonal: tiles filled on demand hold the exact values
    grid = DistanceTiles(ws, obs, 0.004, cap=3.0, full_grid_cells=0)
    lazy = ObjectLattice(ObjectSpace(shape, ws, obs, grid=grid), (1.33, 0.41, 0.7))
    ref = ObjectLattice(ObjectSpace(shape, ws, obs), (1.33, 0.41, 0.7))
    rng = np.random.default_rng(0)
    same = 0
    nodes = rng.choice(ref.n_nodes, 300, replace=False).tolist()
    for u in nodes:
        got, want = lazy.successors(u), ref.successors(u)
        # float32 storage rounds distances down by < 1e-7 m: a node is never freer than
        # on the whole grid, and the answers agree but for rare grazing motions
        assert lazy.node_valid(u) <= ref.node_valid(u)
        same += got == want
    assert same >= 0.97 * len(nodes)
    assert 0 < int((grid.table >= 0).sum()) <= grid.table.size


def test_lamp_lazy_on_a_map_larger_than_its_windows() -> None:
    from lamp import solve
    from lamp.geometry import robot_space

    robot_space.clear_caches()
    scene = scene_from_dict(pillar_scene(6))
    res = solve(scene, planner="lazy", seed=0, config=PlannerConfig.of(max_segments=400)).to_dict()
    assert res["success"], res["objects"][0]["failure_reason"]
    spaces = list(robot_space._SPACE_CACHE.values())
    # the robots planned in windows of the 6 m map, not over all of it
    assert spaces and any(not sp.covers_workspace for sp in spaces)
    assert all(sp.shape[0] * sp.shape[1] < 601 * 601 for sp in spaces if not sp.covers_workspace)


def test_approach_grows_its_window_when_the_way_leaves_it() -> None:
    from types import SimpleNamespace

    wall = Obstacle(Rectangle((6.0, 0.1)), (6.0, 4.5, 0.0))  # x from 3 to 9
    obj = SceneObject(Rectangle((0.4, 0.3)), (6.0, 6.0, 0.0), (6.0, 10.0, 0.0))
    scene = Scene("detour", (12.0, 12.0), ((6.0, 3.5),), (obj,), (wall,), R)
    task = ManipulationTask(scene, 0, scene.object_starts(), None, PlannerConfig())
    q_from = np.array(obj.start)
    q_R = np.array([[6.0, 3.5]])
    goals = np.array([[6.0, 5.75]])  # in contact below the box, beyond the wall
    first = task.robot_space_at(q_from, task.window(q_from, q_R))
    assert not plan_paths(scene, q_R, goals, space=first, time_limit=5.0).success
    routed = task.verifier.approach(q_from, q_R, goals)
    assert routed is not None
    paths, goal_of = routed
    assert np.abs(paths[0, :, 0] - 6.0).max() > 3.0  # around an end of the wall
    check_plan(scene, q_R, goals, SimpleNamespace(paths=paths, goal_of=goal_of, success=True, reason=""),
               require_success=True)
