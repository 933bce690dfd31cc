"""ExactSpace: exact clearances against a Shapely reference, sound and permissive motions."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lamp.geometry import se2
from lamp.geometry.exact_space import ExactSpace
from lamp.geometry.object_space import ObjectSpace, inflated_geometry
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle

W, H = 2.0, 2.0
L_SHAPE = Polygon(
    ((-0.2, -0.2), (0.2, -0.2), (0.2, -0.05), (-0.05, -0.05), (-0.05, 0.2), (-0.2, 0.2))
)
SHAPES = [Rectangle((0.4, 0.3)), Circle(0.15), L_SHAPE, Rectangle((1.2, 0.2))]
coord = st.floats(0.0, 2.0)
angle = st.floats(-math.pi, math.pi)


@st.composite
def obstacles(draw: st.DrawFn) -> Obstacle:
    x, y, th = draw(coord), draw(coord), draw(angle)
    if draw(st.booleans()):
        return Obstacle(Circle(draw(st.floats(0.01, 0.25))), (x, y, 0.0))
    return Obstacle(Rectangle((draw(st.floats(0.01, 0.8)), draw(st.floats(0.01, 0.3)))),
                    (x, y, th))


def reference_clearance(shape, pose, obs, cap) -> float:
    """Distance of the footprint to obstacles and border by plain Shapely (circles exact)."""
    pose = np.asarray(pose, float)
    foot = inflated_geometry(shape, pose, 0.0) if not isinstance(shape, Circle) else None
    best = cap
    border = shapely.box(0, 0, W, H).exterior
    for o in obs:
        if isinstance(o.shape, Circle):
            c = shapely.Point(o.pose[0], o.pose[1])
            d = (foot.distance(c) if foot is not None else
                 math.dist(pose[:2], o.pose[:2]) - shape.radius) - o.shape.radius
        else:
            g = inflated_geometry(o.shape, o.pose, 0.0)
            d = (foot.distance(g) if foot is not None else
                 shapely.Point(pose[:2]).distance(g) - shape.radius)
        best = min(best, d)
    inside = shapely.box(0, 0, W, H)
    if foot is not None:
        db = foot.distance(border) if inside.contains(foot) else 0.0
    else:
        db = min(pose[0], W - pose[0], pose[1], H - pose[1]) - shape.radius
    return min(best, db)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(obs=st.lists(obstacles(), max_size=6), i=st.integers(0, len(SHAPES) - 1),
       x=st.floats(0.3, 1.7), y=st.floats(0.3, 1.7), th=angle)
def test_clearance_is_the_exact_distance(obs, i, x, y, th):
    shape = SHAPES[i]
    space = ExactSpace(shape, (W, H), obs)
    got = space.clearance((x, y, th))
    ref = reference_clearance(shape, (x, y, th), obs, space.cap)
    if ref > 0:
        assert abs(got - ref) < 1e-6
    else:
        assert got <= 1e-9


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(obs=st.lists(obstacles(), max_size=5), i=st.integers(0, len(SHAPES) - 1),
       a=st.tuples(st.floats(0.3, 1.7), st.floats(0.3, 1.7), angle),
       d=st.tuples(st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.floats(-0.5, 0.5)))
def test_motions_are_sound_and_no_stricter_than_the_grid(obs, i, a, d):
    """Never free through a pose with clearance <= margin / 2 (dense reference samples);
    free whenever the conservative grid checker says free."""
    shape = SHAPES[i]
    a = np.array(a)
    b = a + np.array(d)
    exact = ExactSpace(shape, (W, H), obs)
    free = exact.motion_free(a, b)
    if free:
        for t in np.linspace(0.0, 1.0, 101):
            p = se2.interpolate(a, b, t)
            assert reference_clearance(shape, p, obs, 1.0) > 0.5 * exact.margin - 1e-9
    if ObjectSpace(shape, (W, H), obs).motion_free(a, b):
        assert free


def test_a_corridor_one_centimetre_a_side_is_free_only_exactly():
    """1 cm of clearance a side: beyond the grid checker's band, certified by ExactSpace."""
    walls = [Obstacle(Rectangle((2.0, 0.5)), (1.0, 0.75, 0.0)),
             Obstacle(Rectangle((2.0, 0.5)), (1.0, 1.57, 0.0))]  # free band y in [1.0, 1.32]
    shape = Rectangle((0.4, 0.3))
    a, b = np.array([0.6, 1.16, 0.0]), np.array([0.8, 1.16, 0.0])
    assert not ObjectSpace(shape, (W, H), walls).motion_free(a, b)
    exact = ExactSpace(shape, (W, H), walls)
    assert abs(exact.clearance(a) - 0.01) < 1e-9
    assert exact.motion_free(a, b)
    assert not exact.motion_free(a, b + np.array([0.0, 0.0, 0.1]))  # rotating jams it


def test_a_large_disk_whose_centre_is_far_still_counts():
    """A disk obstacle's edge within the cap while its centre lies beyond it."""
    disk = Obstacle(Circle(0.25), (1.0, 1.6, 0.0))  # edge at y = 1.35
    shape = Rectangle((0.4, 0.3))
    pose = (1.0, 1.1, 0.0)  # top edge at y = 1.25: 0.1 m below the disk
    assert ExactSpace(shape, (W, H), [disk]).clearance(pose) == pytest.approx(0.1)
