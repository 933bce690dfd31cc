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
