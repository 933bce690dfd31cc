"""The makespan lower bound (``lamp.scene.bounds``): a brute force over robots and objects
agrees with it, and no executed run is shorter than it."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scenes import TINY

import lamp
from lamp.contract.goals import SUCCESS_POSITION_TOL
from lamp.manip import GeometricProposer
from lamp.scene import scene_from_dict
from lamp.scene.bounds import makespan_lower_bound


def _brute(d: dict) -> float:
    """The bound from the scene dict with Shapely's buffered disks and boxes (no lamp
    geometry): every robot against every object, the worst object."""
    r = d["robots"]["radius"]
    speed = d["robots"].get("speed", 0.25)
    worst = 0.0
    for o in d["objects"]:
        x, y, th = o["start"]
        if o["type"] == "circle":
            foot = shapely.Point(x, y).buffer(o["radius"], 4096)
        else:
            sx, sy = o["size"]
            box = shapely.box(-sx / 2, -sy / 2, sx / 2, sy / 2)
            foot = shapely.affinity.translate(shapely.affinity.rotate(
                box, th, origin=(0, 0), use_radians=True), x, y)
        reach = min(max(0.0, shapely.Point(p).distance(foot) - r) for p in d["robots"]["starts"])
        travel = max(0.0, math.dist(o["goal"][:2], o["start"][:2]) - SUCCESS_POSITION_TOL)
        worst = max(worst, (reach + travel) / speed)
    return worst


@st.composite
def scenes(draw) -> dict:
    objects, cells = [], draw(st.permutations([(i, j) for i in range(4) for j in range(3)]))
    for k in range(draw(st.integers(1, 3))):
        (i, j), (gi, gj) = cells[2 * k], cells[2 * k + 1]
        th, gth = draw(st.floats(-3.1, 3.1)), draw(st.floats(-3.1, 3.1))
        start, goal = [0.9 + 0.7 * i, 0.4 + 0.7 * j, th], [0.9 + 0.7 * gi, 0.4 + 0.7 * gj, gth]
        if draw(st.booleans()):
            objects.append({"type": "circle", "radius": draw(st.floats(0.05, 0.2)),
                            "start": start, "goal": goal})
        else:
            objects.append({"type": "rectangle", "size": [draw(st.floats(0.05, 0.3)),
                                                          draw(st.floats(0.05, 0.3))],
                            "start": start, "goal": goal})
    robots = [[0.15, 0.3 + 0.25 * i] for i in range(draw(st.integers(1, 6)))]
    return {"format": "lamp-scene/1", "name": "b", "workspace": [4.0, 2.2],
            "robots": {"radius": 0.05, "speed": draw(st.sampled_from([0.1, 0.25, 1.0])),
                       "starts": robots}, "objects": objects}


@settings(max_examples=60)
@given(scenes())
def test_the_bound_equals_a_brute_force(d):
    bound = makespan_lower_bound(scene_from_dict(d))
    assert bound.seconds == pytest.approx(_brute(d), rel=1e-6, abs=1e-6)
    assert bound.seconds == max(bound.per_object)
    assert bound.per_object[bound.critical_object] == bound.seconds


@pytest.mark.parametrize("schedule", ["sequential", "concurrent"])
def test_no_run_is_shorter_than_the_bound(schedule):
    scene = scene_from_dict({**TINY, "objects": [
        {"type": "rectangle", "size": [0.3, 0.2], "start": [0.7, 1.0, 0.0],
         "goal": [1.6, 1.2, 0.5]}]})
    res = lamp.solve(scene, "lazy", 0, model=GeometricProposer(), schedule=schedule)
    d = res.to_dict()
    assert d["success"]
    assert 0 < d["makespan_lower_bound_s"] <= d["makespan_s"]
    assert d["makespan_over_bound"] == pytest.approx(d["makespan_s"] / d["makespan_lower_bound_s"],
                                                     rel=1e-3)


def test_with_a_wall_the_travel_goes_round_it():
    """A wall between start and goal: each object's own bound is the nearest robot's
    straight drive plus the geodesic of a disk of its inscribed radius round the wall
    (``scene.geodesic``), less the tolerance; longer than the straight-line bound, which
    ``straight_line=True`` still gives."""
    from lamp.scene.bounds import inscribed_radius
    from lamp.scene.geodesic import GrownObstacles

    d = {"format": "lamp-scene/1", "name": "wall", "workspace": [4.0, 3.0],
         "obstacles": [{"type": "rectangle", "center": [2.0, 1.15], "size": [0.2, 2.3]}],
         "robots": {"radius": 0.05, "starts": [[0.5, 0.5], [0.5, 0.8]]},
         "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [1.0, 1.0, 0.0],
                      "goal": [3.0, 1.0, 0.0]}]}
    scene = scene_from_dict(d)
    o = scene.objects[0]
    assert inscribed_radius(o.shape) == pytest.approx(0.1)
    wall = shapely.box(1.9, 0.0, 2.1, 2.3)
    geo = GrownObstacles([wall], 0.1, (4.0, 3.0)).distance((1.0, 1.0), (3.0, 1.0))
    reach = min(shapely.Point(p).distance(shapely.box(0.85, 0.9, 1.15, 1.1)) - 0.05
                for p in d["robots"]["starts"])
    want = (reach + geo - SUCCESS_POSITION_TOL) / 0.25
    assert makespan_lower_bound(scene).seconds == pytest.approx(want, rel=1e-9)
    straight = makespan_lower_bound(scene, straight_line=True).seconds
    assert straight == pytest.approx(_brute(d), rel=1e-6) and straight < want - 5.0


def _grid_reach(d: dict, h: float = 0.02) -> float:
    """A drive some robot of scene dict ``d`` can make until it touches object 0, on an
    ``h`` grid (no lamp code): Dijkstra over 8-neighbour steps from the robots' starts
    (on grid nodes) through nodes at least ``r + h`` from every obstacle and inside the
    room by as much (a step of at most ``h * sqrt(2)`` between two such nodes keeps the
    disk clear), to the first node within ``r`` of the object's footprint."""
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import dijkstra

    w, hh = d["workspace"]
    r = d["robots"]["radius"]
    walls = shapely.union_all([shapely.box(c[0] - s[0] / 2, c[1] - s[1] / 2, c[0] + s[0] / 2,
                                           c[1] + s[1] / 2)
                               for c, s in ((b["center"], b["size"]) for b in d["obstacles"])])
    o = d["objects"][0]
    foot = (shapely.Point(o["start"][:2]).buffer(o["radius"], quad_segs=256)
            if o["type"] == "circle" else shapely.box(
                o["start"][0] - o["size"][0] / 2, o["start"][1] - o["size"][1] / 2,
                o["start"][0] + o["size"][0] / 2, o["start"][1] + o["size"][1] / 2))
    nx, ny = int(round(w / h)) + 1, int(round(hh / h)) + 1
    xs, ys = np.meshgrid(np.arange(nx) * h, np.arange(ny) * h, indexing="ij")
    pts = shapely.points(xs.ravel(), ys.ravel())
    m = r + h
    free = ((shapely.distance(pts, walls) >= m) & (xs.ravel() >= m) & (xs.ravel() <= w - m)
            & (ys.ravel() >= m) & (ys.ravel() <= hh - m))
    idx = np.arange(nx * ny).reshape(nx, ny)
    rows, cols, lengths = [], [], []
    for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
        a = idx[max(0, -di):nx - max(0, di), max(0, -dj):ny - max(0, dj)].ravel()
        b = idx[max(0, di):nx - max(0, -di) or None, max(0, dj):ny - max(0, -dj) or None].ravel()
        ok = free[a] & free[b]
        rows.append(a[ok]), cols.append(b[ok]), lengths.append(np.full(ok.sum(), h * math.hypot(di, dj)))
    graph = coo_array((np.concatenate(lengths), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(nx * ny,) * 2).tocsr()
    starts = [int(idx[round(x / h), round(y / h)]) for x, y in d["robots"]["starts"]]
    dist = dijkstra(graph, directed=False, indices=starts, min_only=True)
    touch = free & (shapely.distance(pts, foot) <= r)
    return float(np.min(dist[touch])) if touch.any() else math.inf


@st.composite
def walled_scenes(draw) -> dict:
    """Robots on the left of a 4 x 2.2 m room, one object to the right behind one or two
    walls, its goal its start (so its bound is its reach over the speed)."""
    walls = [{"type": "rectangle", "center": [draw(st.floats(1.2, 2.4)), c],
              "size": [draw(st.floats(0.05, 0.4)), draw(st.floats(0.6, 1.6))]}
             for c in draw(st.lists(st.floats(0.3, 1.9), min_size=1, max_size=2))]
    x, y = draw(st.floats(2.9, 3.6)), draw(st.floats(0.4, 1.8))
    if draw(st.booleans()):
        obj = {"type": "circle", "radius": draw(st.floats(0.05, 0.3))}
    else:
        obj = {"type": "rectangle", "size": [draw(st.floats(0.05, 0.5)), draw(st.floats(0.05, 0.5))]}
    robots = [[0.2 + 0.02 * draw(st.integers(0, 20)), 0.2 + 0.02 * draw(st.integers(0, 90))]
              for _ in range(draw(st.integers(1, 4)))]
    return {"format": "lamp-scene/1", "name": "walled", "workspace": [4.0, 2.2],
            "obstacles": walls, "robots": {"radius": 0.05, "speed": 0.25, "starts": robots},
            "objects": [{**obj, "start": [x, y, 0.0], "goal": [x, y, 0.0]}]}


@settings(max_examples=30, deadline=None)
@given(walled_scenes())
def test_the_reach_goes_round_the_walls_and_below_any_drive(d):
    """The reach lies between the nearest robot's straight-line gap and a drive a robot can
    make to touch the object (``_grid_reach``, no lamp code)."""
    from hypothesis import assume

    try:
        scene = scene_from_dict(d)
    except ValueError:
        assume(False)
    speed = d["robots"]["speed"]
    reach = makespan_lower_bound(scene).seconds * speed
    straight = makespan_lower_bound(scene, straight_line=True).seconds * speed
    assert straight - 1e-9 <= reach <= _grid_reach(d) + 1e-9


def test_round_a_wall_the_reach_is_the_way_to_the_reference_point_less_the_radii():
    """A wall from the border between the only robot and a disk object: the reach is the
    way over the wall's top to the object's centre less both radii (not through the
    zero-width joint of wall and border), longer than the straight gap."""
    from lamp.scene.geodesic import GrownObstacles

    d = {"format": "lamp-scene/1", "name": "wall", "workspace": [4.0, 3.0],
         "obstacles": [{"type": "rectangle", "center": [2.0, 1.15], "size": [0.2, 2.3]}],
         "robots": {"radius": 0.05, "starts": [[1.0, 1.0]]},
         "objects": [{"type": "circle", "radius": 0.2, "start": [3.0, 1.0, 0.0],
                      "goal": [3.0, 1.0, 0.0]}]}
    geo = GrownObstacles([shapely.box(1.9, 0.0, 2.1, 2.3)], 0.0, (4.0, 3.0),
                         merge=True).distance((1.0, 1.0), (3.0, 1.0))
    over_the_top = 2.0 * math.hypot(0.9, 1.3) + 0.2  # (the wall stands on the border)
    got = makespan_lower_bound(scene_from_dict(d)).seconds * 0.25
    assert geo == pytest.approx(over_the_top, rel=1e-9)
    assert got == pytest.approx(geo - 0.25, rel=1e-9) and got > 2.0 - 0.25 + 1.0
