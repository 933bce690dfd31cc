"""Contact geometry and the geometric proposer: shapes, frames, validity, determinism."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.se2 import transform_points
from lamp.geometry.shapes import to_shapely
from lamp.manip import CONTACT_OFFSET, GeometricProposer, Proposal, ProposalModel
from lamp.manip.contacts import (
    contacts_valid,
    project_to_contacts,
    ray_hit,
    rigid_pushes,
    signed_distance,
)
from lamp.manip.geometric import STRATEGIES, contact_ring, strategy_contacts, wrench_residual
from lamp.scene.model import Circle, Polygon, Rectangle

SHAPES = [
    Rectangle((0.4, 0.3)),
    Rectangle((0.15, 0.5)),
    Circle(0.1),
    Circle(0.3),
    Polygon(((0.0, 0.25), (-0.2, -0.1), (0.2, -0.1))),
    # a concave L shape (out of distribution for the model, still handled geometrically)
    Polygon(((-0.2, -0.2), (0.2, -0.2), (0.2, 0.0), (0.0, 0.0), (0.0, 0.2), (-0.2, 0.2))),
]

shape_st = st.one_of(
    st.builds(lambda r: Circle(r), st.floats(0.1, 0.3)),
    st.builds(lambda a, b: Rectangle((a, b)), st.floats(0.15, 0.5), st.floats(0.15, 0.5)),
    st.sampled_from(SHAPES),
)
motion_st = st.tuples(st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.floats(-0.5, 0.5))


@settings(max_examples=60, deadline=None)
@given(shape=shape_st, pts=st.lists(st.tuples(st.floats(-0.6, 0.6), st.floats(-0.6, 0.6)),
                                    min_size=1, max_size=8))
def test_signed_distance_matches_shapely(shape, pts):
    p = np.array(pts)
    geom = to_shapely(shape)
    ref = np.array([
        -geom.exterior.distance(shapely.Point(x, y)) if geom.contains(shapely.Point(x, y))
        else geom.distance(shapely.Point(x, y))
        for x, y in p
    ])
    # circles are 128-gons in shapely: allow their chord error
    np.testing.assert_allclose(signed_distance(shape, p), ref, atol=2e-3)


@settings(max_examples=40, deadline=None)
@given(shape=shape_st, pts=st.lists(st.tuples(st.floats(-0.6, 0.6), st.floats(-0.6, 0.6)),
                                    min_size=1, max_size=8))
def test_projection_lands_on_contact_ring(shape, pts):
    c = project_to_contacts(shape, np.array(pts))
    d = signed_distance(shape, c)
    # concave corners may leave a projected point closer to a neighbouring edge
    if not (isinstance(shape, Polygon) and len(shape.points) > 4):
        np.testing.assert_allclose(d, CONTACT_OFFSET, atol=1e-6)


def test_ray_hit_on_box_and_circle():
    p, n = ray_hit(Rectangle((0.4, 0.3)), (0.0, 0.05), (-1.0, 0.0))
    np.testing.assert_allclose(p, [-0.2, 0.05])
    np.testing.assert_allclose(n, [-1.0, 0.0])
    p, n = ray_hit(Circle(0.2), (0.0, 0.0), (0.0, 1.0))
    np.testing.assert_allclose(p, [0.0, 0.2])
    assert ray_hit(Circle(0.2), (0.0, 0.5), (1.0, 0.0)) is None


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: type(s).__name__)
def test_contact_ring_is_at_offset(shape):
    ring = contact_ring(shape)
    np.testing.assert_allclose(signed_distance(shape, ring.points), CONTACT_OFFSET, atol=1e-6)
    gaps = np.hypot(*(np.roll(ring.points, -1, axis=0) - ring.points).T)
    assert gaps.max() < 0.05  # evenly sampled, closed (concave corners cut small pieces)


@settings(max_examples=50, deadline=None)
@given(contacts=st.lists(st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5)), min_size=1,
                         max_size=3), motion=motion_st, pose=st.tuples(
                             st.floats(-1, 1), st.floats(-1, 1), st.floats(-3, 3)))
def test_rigid_pushes_follow_the_object(contacts, motion, pose):
    c = np.array(contacts)
    p = rigid_pushes(c, motion, 20)
    assert p.shape == (len(c), 20, 2)
    np.testing.assert_array_equal(p[:, 0], c)
    # the last waypoint is the contact carried by the full motion
    np.testing.assert_allclose(p[:, -1], transform_points(motion, c), atol=1e-12)
    # distances between robots are preserved (rigid)
    if len(c) > 1:
        d0 = np.linalg.norm(c[0] - c[1])
        np.testing.assert_allclose(np.linalg.norm(p[0] - p[1], axis=-1), d0, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(shape=shape_st, motion=motion_st, budget=st.integers(1, 3), seed=st.integers(0, 2**31))
def test_geometric_proposals_are_valid(shape, motion, budget, seed):
    props = GeometricProposer().propose(shape, motion, budget, k=8, seed=seed)
    assert len(props) == 8
    for pr in props:
        assert isinstance(pr, Proposal)
        assert 1 <= pr.n_robots <= budget
        assert pr.pushes.shape == (pr.n_robots, 20, 2)
        np.testing.assert_array_equal(pr.pushes[:, 0], pr.contacts)
        np.testing.assert_allclose(pr.pushes, rigid_pushes(pr.contacts, motion), atol=1e-12)
        assert contacts_valid(shape, pr.contacts)


def test_geometric_accepts_dicts_and_is_deterministic():
    g = GeometricProposer()
    assert isinstance(g, ProposalModel)
    a = g.propose({"type": "rectangle", "size": [0.4, 0.3]}, (0.2, 0.0, 0.0), 3, k=16, seed=3)
    b = g.propose(Rectangle((0.4, 0.3)), (0.2, 0.0, 0.0), 3, k=16, seed=3)
    for pa, pb in zip(a, b, strict=True):
        np.testing.assert_array_equal(pa.contacts, pb.contacts)
        np.testing.assert_array_equal(pa.pushes, pb.pushes)
    c = g.propose(Rectangle((0.4, 0.3)), (0.2, 0.0, 0.0), 3, k=16, seed=4)
    assert any(not np.array_equal(pa.contacts, pc.contacts) for pa, pc in zip(a, c, strict=True))


def test_pure_push_from_behind_is_ranked_first():
    props = GeometricProposer().propose(Rectangle((0.4, 0.3)), (0.2, 0.0, 0.0), 1, k=4, seed=0)
    c = props[0].contacts[0]
    # behind the box (x = -0.2 - offset), close to the centre line
    assert c[0] == pytest.approx(-0.2 - CONTACT_OFFSET, abs=5e-3)
    assert abs(c[1]) < 0.06
    assert wrench_residual(Rectangle((0.4, 0.3)), props[0].contacts[None], (0.2, 0, 0))[0] < 0.05


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("budget", [1, 2, 3])
def test_each_strategy_places_valid_contacts(strategy, budget):
    rng = np.random.default_rng(0)
    placed = 0
    for _ in range(10):
        c = strategy_contacts(Rectangle((0.45, 0.35)), (0.15, 0.05, 0.2), budget, strategy, rng)
        if c is not None:
            placed += 1
            assert c.shape == (budget, 2)
            assert contacts_valid(Rectangle((0.45, 0.35)), c)
    assert placed >= 5


def test_wrench_residual_reference_cases():
    box = Rectangle((0.4, 0.3))
    behind = np.array([[[-0.255, 0.0]]])
    front = np.array([[[0.255, 0.0]]])
    assert wrench_residual(box, behind, (0.2, 0, 0))[0] == pytest.approx(0.0, abs=1e-9)
    assert wrench_residual(box, front, (0.2, 0, 0))[0] == pytest.approx(1.0, abs=1e-9)


def test_bad_arguments_raise_clear_errors():
    g = GeometricProposer()
    with pytest.raises(ValueError, match="budget"):
        g.propose(Circle(0.2), (0.1, 0, 0), 4)
    with pytest.raises(ValueError, match="motion"):
        g.propose(Circle(0.2), (0.1, 0), 1)
    with pytest.raises(ValueError, match="k must"):
        g.propose(Circle(0.2), (0.1, 0, 0), 1, k=0)
    with pytest.raises(ValueError, match="shape"):
        g.propose("box", (0.1, 0, 0), 1)
