"""Transit (``lamp.fleet.transit``): routes to an object's staging area against a plain
Dijkstra on the same grid, hops that take far robots round a wall, and a run whose team
starts behind a wall from its object."""

from __future__ import annotations

import copy
import heapq
import math

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

import lamp
from lamp.fleet.transit import (
    CLAIM_CLEARANCE,
    CROSS_REACH,
    HOP_LENGTH,
    MIN_HOP,
    STAGING,
    TRANSIT_RADIUS,
    clear_waypoint,
    far_robots,
    hop,
    routes,
)
from lamp.record.safety import check_recording, recorded_teams
from lamp.scene import scene_from_dict
from lamp.scene.model import Obstacle, Rectangle, Scene, SceneObject

BOX = Rectangle((0.4, 0.3))


def reference_distances(free: np.ndarray, sources: list[tuple[int, int]], cell: float):
    """Dijkstra over the 8-connected free cells, a diagonal step only when both side
    cells are free, from every source at once."""
    ny, nx = free.shape
    dist = np.full((ny, nx), np.inf)
    heap = [(0.0, j, i) for j, i in sources]
    for _, j, i in heap:
        dist[j, i] = 0.0
    heapq.heapify(heap)
    while heap:
        d, j, i = heapq.heappop(heap)
        if d > dist[j, i]:
            continue
        for dj in (-1, 0, 1):
            for di in (-1, 0, 1):
                a, b = j + dj, i + di
                if (dj, di) == (0, 0) or not (0 <= a < ny and 0 <= b < nx) or not free[a, b]:
                    continue
                if dj and di and not (free[j + dj, i] and free[j, i + di]):
                    continue
                nd = d + cell * math.hypot(dj, di)
                if nd < dist[a, b] - 1e-12:
                    dist[a, b] = nd
                    heapq.heappush(heap, (nd, a, b))
    return dist


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.floats(0.3, 2.7), st.floats(0.3, 2.7), st.floats(0.1, 1.5),
                          st.floats(0.1, 1.5)), max_size=4),
       st.floats(0.5, 2.5), st.floats(0.5, 2.5))
def test_routes_are_shortest_paths_on_the_grid(walls, ox, oy) -> None:
    obstacles = tuple(Obstacle(Rectangle((w, h)), (x, y, 0.0)) for x, y, w, h in walls)
    scene = Scene("grid", (3.0, 3.0), ((0.2, 0.2),),
                  (SceneObject(BOX, (ox, oy, 0.0), (ox, oy, 0.0)),), obstacles)
    field = routes(scene, 0, np.array(scene.object_starts()))
    ny, nx = field.shape
    reach = BOX.bounding_radius + STAGING
    sources = [(j, i) for j in range(ny) for i in range(nx) if field.free[j, i]
               and math.hypot((i + 0.5) * field.cell - ox, (j + 0.5) * field.cell - oy) <= reach]
    expect = reference_distances(field.free, sources, field.cell)
    got = field.dist.reshape(ny, nx)
    assert np.array_equal(np.isfinite(got), np.isfinite(expect))
    fin = np.isfinite(expect)
    np.testing.assert_allclose(got[fin], expect[fin], atol=1e-9)
    # every path walks free cells, one 8-neighbour step at a time, as long as its distance
    for j, i in zip(*np.nonzero(fin), strict=True):
        xy = np.array([(i + 0.5) * field.cell, (j + 0.5) * field.cell])
        path = field.path(xy)
        steps = np.hypot(*np.diff(path, axis=0).T)
        assert np.all(steps < field.cell * 1.5)
        assert math.isclose(float(steps.sum()), float(got[j, i]), abs_tol=1e-6)
        cells = np.floor(path / field.cell).astype(int)
        assert field.free[cells[:, 1], cells[:, 0]].all()
        break  # one path per example is enough


def u_scene() -> Scene:
    """A wall across most of an 8 x 10 m map: the way from the bottom to the box at the
    top-left goes round its right end."""
    wall = Obstacle(Rectangle((6.5, 0.2)), (3.25, 5.0, 0.0))
    return Scene("u", (8.0, 10.0), ((0.5, 0.5), (1.0, 0.5)),
                 (SceneObject(BOX, (1.5, 8.5, 0.0), (3.0, 8.5, 0.0)),), (wall,))


def u_start():
    """``u_scene`` with its start poses and positions, its routes and far robots."""
    scene = u_scene()
    poses = np.array(scene.object_starts())
    pos = np.array(scene.robot_starts, float)
    field = routes(scene, 0, poses)
    return scene, poses, pos, field, far_robots(field, pos)


def test_hops_take_far_robots_round_the_wall() -> None:
    scene, poses, pos, field, far = u_start()
    # the straight way to the staging area is under 7 m: the route goes round the wall
    assert far.all() and field.dist[field.cell_of(pos[0])] > 12.0
    for _ in range(6):
        plan = hop(scene, 0, poses, pos, far, field)
        assert plan is not None and plan.success
        before = [field.dist[field.cell_of(p)] for p in pos]
        pos = plan.paths[:, -1]
        after = [field.dist[field.cell_of(p)] for p in pos]
        assert all(a < b - 1.0 for a, b, f in zip(after, before, far, strict=True) if f)
        far = far_robots(field, pos)
        if not far.any():
            break
    assert not far.any()
    assert all(field.dist[field.cell_of(p)] <= TRANSIT_RADIUS for p in pos)


FAR_TEAM = {
    "format": "lamp-scene/1", "name": "far-team", "workspace": [8.0, 10.0],
    "schedule": "concurrent",
    "robots": {"starts": [[0.5, 0.5], [1.0, 0.5]]},
    "obstacles": [{"type": "rectangle", "center": [3.25, 5.0], "size": [6.5, 0.2]}],
    "objects": [{"type": "rectangle", "size": [0.4, 0.3], "start": [1.5, 8.5, 0.0],
                 "goal": [3.0, 8.5, 0.0]}],
}


def test_a_team_behind_a_wall_drives_round_it_and_places_its_object_safely() -> None:
    result = lamp.solve(scene_from_dict(copy.deepcopy(FAR_TEAM)), "lazy", 0)
    assert result.success
    fleet = result.to_dict()["stats"]["fleet"]
    assert fleet["transit_hops"] >= 2 and fleet["transit_planning_s"] > 0
    rec = result.recording
    report = check_recording(rec.scene_model(), rec.arrays["times"], rec.arrays["robots"],
                             rec.arrays["objects"], robot_team=recorded_teams(rec))
    assert report.ok, report.summary()


def reference_waypoint(route, along, n, keep_out, clear):
    """``clear_waypoint`` point by point, from its docstring."""
    def ok(i):
        p = shapely.Point(route[i])
        return all(region.distance(p) > clear for region in keep_out)

    if not keep_out or ok(n - 1):
        return n
    for i in range(n, len(route)):
        if along[i] > along[n - 1] + CROSS_REACH:
            break
        if ok(i):
            return i + 1
    for i in range(n - 2, -1, -1):
        if along[i] >= MIN_HOP and ok(i):
            return i + 1
    return n


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0.0, 20.0), st.floats(0.0, 2.0), st.floats(0.1, 3.0)),
                min_size=0, max_size=3),
       st.integers(1, 150), st.floats(0.0, 0.3))
def test_a_waypoint_moves_clear_of_the_claims_as_documented(strips, n, wiggle) -> None:
    # a route along x with a little sideways wave, claims as boxes across it
    x = np.arange(1, 200) * 0.1
    route = np.c_[x, 1.0 + wiggle * np.sin(x)]
    along = np.cumsum(np.hypot(*np.diff(np.vstack([[0.0, 1.0], route]), axis=0).T))
    keep_out = [shapely.box(x0, y0 - 1.0, x0 + w, y0 + 1.5) for x0, y0, w in strips]
    n = min(n, len(route))
    got = clear_waypoint(route, along, n, keep_out, 0.1)
    assert got == reference_waypoint(route, along, n, keep_out, 0.1)
    assert 1 <= got <= len(route)


def test_a_hop_crosses_a_claim_across_its_route_instead_of_stopping_in_it() -> None:
    scene, poses, pos, field, far = u_start()
    plain = hop(scene, 0, poses, pos, far, field)
    assert plain is not None and plain.success
    # a claim 1 m wide across the way, where the plain hop's robots end
    ends = plain.paths[:, -1]
    cx = float(ends[:, 0].mean())
    claim = shapely.box(cx - 0.5, 0.0, cx + 0.5, 4.9)
    clear = scene.robot_radius + CLAIM_CLEARANCE
    assert shapely.dwithin(claim, shapely.points(ends), clear).any()
    crossed = hop(scene, 0, poses, pos, far, field, keep_out=[claim])
    assert crossed is not None and crossed.success
    got = crossed.paths[:, -1]
    assert not shapely.dwithin(claim, shapely.points(got), scene.robot_radius).any()
    # they went through it, on along their routes (no farther than the reach allows)
    before = np.array([field.length(p) for p in pos])
    after = np.array([field.length(p) for p in got])
    assert np.all(after < before - HOP_LENGTH) and np.all(before - after
                                                            <= HOP_LENGTH + CROSS_REACH + 1.0)
