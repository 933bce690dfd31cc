"""``lamp.record.push_reach``: the largest displacement of a body's points between two
poses, exact (against dense samples of its outline), and the lead measured on
hand-made recordings."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.record.push_reach import _moved, push_reach
from lamp.scene.model import Circle, Rectangle, Scene, SceneObject

poses = st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-7, 7))


@settings(max_examples=200)
@given(poses, poses, st.floats(0.05, 1.0), st.floats(0.05, 1.0))
def test_moved_is_the_farthest_any_point_of_the_outline_moves(a, b, w, h) -> None:
    verts = np.array([[-w, -h], [w, -h], [w, h], [-w, h]]) / 2
    ring = shapely.LinearRing(verts)
    pts = shapely.get_coordinates(shapely.segmentize(ring, 0.005))
    def place(q):
        c, s = np.cos(q[2]), np.sin(q[2])
        return pts @ np.array([[c, s], [-s, c]]) + q[:2]
    a, b = np.array(a), np.array(b)
    sampled = np.max(np.linalg.norm(place(b) - place(a), axis=1))
    got = _moved(verts, 0.0, a[None], b[None])[0]
    assert got == pytest.approx(sampled, abs=1e-9)  # the vertices are among the samples
    # a disk: its points on a fine circle
    r = w
    ang = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    circle = r * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    def on(q):
        c, s = np.cos(q[2]), np.sin(q[2])
        return circle @ np.array([[c, s], [-s, c]]) + q[:2]
    sampled = np.max(np.linalg.norm(on(b) - on(a), axis=1))
    got = _moved(None, r, a[None], b[None])[0]
    assert sampled <= got + 1e-9 and got - sampled < 2 * r * (1 - np.cos(np.pi / 4000)) + 1e-3


def _scene(shape) -> Scene:
    return Scene("open", (10.0, 10.0), ((0.5, 0.5), (0.5, 1.0)),
                 (SceneObject(shape, (5.0, 5.0, 0.0), (6.0, 5.0, 0.0)),), (), 0.05)


def test_the_lead_is_how_far_the_object_outran_its_pushers() -> None:
    """A box pushed 1 m along x over 50 rows by robot 0 while robot 1 (no team) drives
    2 m: the object keeps pace with its pusher (lead 0 with speedup 1); then it slides
    0.1 m on in one row while its pusher stands: the lead is 0.1, at that row. Robot 1
    drives farther, but it pushes nothing."""
    s = 52
    times = 0.08 * np.arange(s)
    robots = np.zeros((s, 2, 2))
    robots[:51, 0, 0] = np.linspace(4.7, 5.7, 51)
    robots[51, 0, 0] = 5.7
    robots[:, 1] = np.linspace([0.0, 0.0], [2.0, 0.0], s)
    objects = np.zeros((s, 1, 3))
    objects[:51, 0, 0] = np.linspace(5.0, 6.0, 51)
    objects[51, 0, 0] = 6.1
    objects[:, 0, 1] = 5.0
    team = np.full((s, 2), -1)
    team[:, 0] = 0
    rep = push_reach(_scene(Rectangle((0.4, 0.3))), robots, objects, team, times, 1.0, 60)
    assert rep.lead == pytest.approx(0.1) and rep.object == 0
    assert rep.until_s == pytest.approx(times[51]) and rep.time_s < rep.until_s
    assert rep.holds(0.1 + 1e-9) and not rep.holds(0.09)
    # while pushed it kept pace: up to row 50 nothing outran the pusher
    rep = push_reach(_scene(Circle(0.2)), robots[:51], objects[:51], team[:51], times[:51],
                     1.0, 60)
    assert rep.lead == pytest.approx(0.0, abs=1e-9)


def _brute_lead(scene, robots, objects, team, speedup, horizon) -> float:
    """The largest lead over every pair of rows (reference: no pair left out)."""
    path = np.concatenate([[np.zeros(robots.shape[1])], np.cumsum(
        np.linalg.norm(np.diff(robots, axis=0), axis=2), axis=0)])
    best = -np.inf
    for k, obj in enumerate(scene.objects):
        disk = isinstance(obj.shape, Circle)
        hx, hy = (0.0, 0.0) if disk else (0.5 * obj.shape.size[0], 0.5 * obj.shape.size[1])
        verts = None if disk else np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
        radius = obj.shape.radius if disk else 0.0
        for i in range(len(robots)):
            for j in range(i + 1, min(len(robots), i + horizon + 1)):
                if any((team[r] == k).tolist() != (team[i] == k).tolist()
                       for r in range(i, j + 1)):
                    break
                drove = max([path[j, n] - path[i, n] for n in range(robots.shape[1])
                             if team[i, n] == k], default=0.0)
                moved = _moved(verts, radius, objects[i:i + 1, k], objects[j:j + 1, k])[0]
                best = max(best, moved - speedup * drove)
    return best


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 30), st.integers(1, 12),
       st.floats(0.5, 2.0), st.booleans())
def test_the_lead_is_that_of_every_pair_of_rows(seed, s, horizon, speedup, disk) -> None:
    """Random recordings whose objects stand still in most steps and whose teams change:
    the lead is the largest over every pair of rows, none left out."""
    rng = np.random.default_rng(seed)
    shape = Circle(0.2) if disk else Rectangle((0.4, 0.3))
    scene = Scene("open", (10.0, 10.0), ((0.5, 0.5), (0.5, 1.0), (1.0, 1.0)),
                  (SceneObject(shape, (5.0, 5.0, 0.0), (6.0, 5.0, 0.0)),
                   SceneObject(shape, (3.0, 3.0, 0.0), (6.0, 3.0, 0.0))), (), 0.05)
    robots = np.cumsum(rng.normal(0, 0.05, (s, 3, 2)) * (rng.random((s, 3, 1)) < 0.6), axis=0)
    objects = np.cumsum(rng.normal(0, 0.05, (s, 2, 3)) * (rng.random((s, 2, 1)) < 0.3), axis=0)
    team = np.repeat(rng.integers(-1, 2, (max(1, s // 4), 3)), 4, axis=0)[:s]
    team = np.concatenate([team, np.full((s - len(team), 3), -1)]).astype(int)
    rep = push_reach(scene, robots, objects, team, np.arange(s) * 0.08, speedup, horizon)
    assert rep.lead == pytest.approx(_brute_lead(scene, robots, objects, team, speedup,
                                                 horizon), abs=1e-12)
