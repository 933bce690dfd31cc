"""ObjectSpace against exact Shapely geometry (Hypothesis), plus edge cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lamp.geometry import se2
from lamp.geometry.object_space import ObjectSpace, inflated_geometry, inflated_outline
from lamp.geometry.shapes import obstacle_geometry
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle, Scene, SceneObject

W, H = 2.0, 2.0
L_SHAPE = Polygon(
    ((-0.2, -0.2), (0.2, -0.2), (0.2, -0.05), (-0.05, -0.05), (-0.05, 0.2), (-0.2, 0.2))
)
TRIANGLE = Polygon(((-0.15, -0.1), (0.2, -0.05), (-0.05, 0.15)))

coord = st.floats(0.0, 2.0)
angle = st.floats(-math.pi, math.pi)


@st.composite
def obstacles(draw: st.DrawFn) -> Obstacle:
    kind = draw(st.sampled_from(["circle", "rect", "tri"]))
    x, y, th = draw(coord), draw(coord), draw(angle)
    if kind == "circle":
        return Obstacle(Circle(draw(st.floats(0.01, 0.25))), (x, y, 0.0))
    if kind == "rect":
        return Obstacle(
            Rectangle((draw(st.floats(0.01, 0.8)), draw(st.floats(0.01, 0.3)))), (x, y, th)
        )
    s = draw(st.floats(0.1, 1.0))
    return Obstacle(Polygon(tuple((s * px, s * py) for px, py in TRIANGLE.points)), (x, y, th))


object_shapes = st.one_of(
    st.floats(0.05, 0.3).map(Circle),
    st.tuples(st.floats(0.1, 0.5), st.floats(0.1, 0.5)).map(Rectangle),
    st.just(L_SHAPE),
    st.just(TRIANGLE),
)


def truth(space: ObjectSpace, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(collides, true clearance) of the inflated footprint at (P, 3) poses, exact with
    Shapely (vectorised); the clearance is -1 where it collides."""
    if isinstance(space.shape, Circle):
        feet = shapely.buffer(
            shapely.points(poses[:, :2]), space.shape.radius + space.inflation, quad_segs=64
        )
    else:
        local = inflated_outline(space.shape, space.inflation)
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        world = np.stack(
            [
                poses[:, :1] + c * local[:, 0] - s * local[:, 1],
                poses[:, 1:2] + s * local[:, 0] + c * local[:, 1],
            ],
            axis=-1,
        )
        feet = shapely.polygons(world)
    box = shapely.box(0.0, 0.0, *space.workspace)
    geoms = [obstacle_geometry(o) for o in space.obstacles]
    collides = ~shapely.contains(box, feet)
    dist = shapely.distance(box.exterior, feet)
    if geoms:
        union = shapely.union_all(geoms)
        collides |= shapely.intersects(union, feet)
        dist = np.minimum(dist, shapely.distance(union, feet))
    return collides, np.where(collides, -1.0, dist)


# Shapely's disks are 256-gons inscribed in the circle: allow for the chord deficit
GEOM_TOL = 1e-4


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    shape=object_shapes,
    obs=st.lists(obstacles(), min_size=0, max_size=6),
    inflation=st.sampled_from([0.0, 0.03, 0.2]),
    seed=st.integers(0, 2**31 - 1),
)
def test_pose_queries_match_shapely(shape, obs, inflation, seed):
    space = ObjectSpace(shape, (W, H), obs, inflation)
    rng = np.random.default_rng(seed)
    poses = rng.uniform([0, 0, -math.pi], [W, H, math.pi], size=(40, 3))
    free = space.pose_free(poses)
    clear = space.clearance(poses)
    assert free.shape == (40,) and clear.shape == (40,)
    # pose_free may use a looser (coarse) lower bound, which can only add True answers
    assert np.all(free[clear > 0])
    for p, f, c, collides, true_clear in zip(poses, free, clear, *truth(space, poses), strict=True):
        if collides:
            assert not f, f"reported free but collides at {p}"
            assert c <= 0.0
        else:
            assert c <= true_clear + GEOM_TOL, (p, c, true_clear)
            assert c >= true_clear - space.band - GEOM_TOL, (p, c, true_clear)
            if true_clear > space.band + GEOM_TOL:
                assert f


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    shape=object_shapes,
    obs=st.lists(obstacles(), min_size=1, max_size=5),
    inflation=st.sampled_from([0.0, 0.05]),
    seed=st.integers(0, 2**31 - 1),
)
def test_motions_match_dense_shapely_sampling(shape, obs, inflation, seed):
    space = ObjectSpace(shape, (W, H), obs, inflation)
    rng = np.random.default_rng(seed)
    a = rng.uniform([0.3, 0.3, -math.pi], [W - 0.3, H - 0.3, math.pi], size=(8, 3))
    b = a + rng.uniform([-0.3, -0.3, -1.0], [0.3, 0.3, 1.0], size=(8, 3))
    ok = space.motions_free(a, b)
    n = 100
    t = np.linspace(0.0, 1.0, n + 1)
    for i in range(len(a)):
        collides, clear = truth(space, se2.interpolate(a[i], b[i], t))
        if collides.any():
            assert not ok[i], f"motion {a[i]} -> {b[i]} reported free but collides"
            continue
        d_xy, d_th = se2.pose_distance(a[i], b[i])
        gap = (d_xy + space.reach * d_th) / n  # max displacement between reference samples
        worst = clear.min() - gap
        if worst > space.band + space.motion_margin + GEOM_TOL:
            assert ok[i], f"motion {a[i]} -> {b[i]} with clearance {worst} reported blocked"
    assert space.motion_free(a[0], b[0]) == ok[0]


def test_obstacle_inside_footprint_is_caught():
    tiny = Obstacle(Circle(0.01), (1.0, 1.0, 0.0))
    space = ObjectSpace(Rectangle((0.5, 0.4)), (W, H), [tiny])
    assert not space.pose_free([1.0, 1.0, 0.3])
    assert space.clearance([1.0, 1.0, 0.3]) <= 0.0
    assert space.pose_free([1.5, 1.0, 0.0])
    # a motion that passes over the tiny obstacle is blocked even though both ends are free
    assert not space.motion_free([0.6, 1.0, 0.0], [1.4, 1.0, 0.0])


def test_nonconvex_notch_is_free():
    # obstacle in the notch of the L: not inside the footprint
    notch = Obstacle(Circle(0.03), (1.1, 1.1, 0.0))
    space = ObjectSpace(L_SHAPE, (W, H), [notch])
    assert space.pose_free([1.0, 1.0, 0.0])
    assert not space.pose_free([1.0, 1.0, math.pi])


def test_inflated_geometry_matches_outline():
    pose = np.array([1.0, 0.5, 0.7])
    for shape in (Rectangle((0.4, 0.2)), L_SHAPE, TRIANGLE):
        g = inflated_geometry(shape, pose, 0.05)
        local = shapely.Polygon(inflated_outline(shape, 0.05))
        assert g.area == pytest.approx(local.area)
        assert (
            g.centroid.distance(shapely.Point(pose[:2]))
            <= local.centroid.distance(shapely.Point(0, 0)) + 1e-9
        )
    rect = inflated_outline(Rectangle((0.4, 0.2)), 0.1)
    np.testing.assert_allclose(np.abs(rect).max(axis=0), [0.3, 0.2])


def test_border_and_inflation_semantics():
    space = ObjectSpace(Rectangle((0.4, 0.2)), (W, H), [], inflation=0.1)
    # rectangle + 0.1 per side: half extents 0.3 x 0.2; border clearance is exact
    np.testing.assert_allclose(space.clearance([1.0, 1.0, 0.0]), 0.7)
    np.testing.assert_allclose(space.clearance([0.35, 1.0, 0.0]), 0.05)
    assert not space.pose_free([0.25, 1.0, 0.0])
    circ = ObjectSpace(Circle(0.2), (W, H), [], inflation=0.2)
    np.testing.assert_allclose(circ.clearance([0.5, 1.0, 0.0]), 0.1)
    assert circ.pose_free(np.zeros((2, 3, 3))).shape == (2, 3)


def test_from_scene_uses_other_objects():
    scene = Scene(
        name="t",
        workspace=(W, H),
        robot_starts=((0.1, 0.1),),
        objects=(
            SceneObject(Circle(0.1), (0.5, 1.0, 0.0), (1.5, 1.0, 0.0)),
            SceneObject(Rectangle((0.2, 0.2)), (1.0, 1.0, 0.0), (1.0, 1.5, 0.0)),
        ),
        obstacles=(Obstacle(Circle(0.1), (1.5, 0.4, 0.0)),),
    )
    space = ObjectSpace.from_scene(scene, 0)
    assert not space.pose_free([1.0, 1.0, 0.0])  # object 1 at its start
    assert not space.pose_free([1.5, 0.4, 0.0])  # static obstacle
    moved = ObjectSpace.from_scene(scene, 0, [[0.5, 1.0, 0.0], [1.0, 1.7, 0.0]])
    assert moved.pose_free([1.0, 1.0, 0.0])
    with pytest.raises(ValueError, match="object_index"):
        ObjectSpace.from_scene(scene, 2)
    with pytest.raises(ValueError, match="object_poses"):
        ObjectSpace.from_scene(scene, 0, np.zeros((3, 3)))


def test_with_inflation_keeps_everything_but_the_inflation():
    obs = (Obstacle(Circle(0.1), (1.0, 1.0, 0.0)), Obstacle(Rectangle((0.3, 0.1)), (0.4, 1.5, 0.3)))
    base = ObjectSpace(
        L_SHAPE, (W, H), obs, 0.05, resolution=0.005, sample_spacing=0.003,
        motion_margin=0.004, cover_cell=0.05,
    )  # fmt: skip
    other = base.with_inflation(-0.01)
    direct = ObjectSpace(
        L_SHAPE, (W, H), obs, -0.01, resolution=0.005, sample_spacing=0.003,
        motion_margin=0.004, cover_cell=0.05,
    )  # fmt: skip
    assert other.inflation == -0.01 and base.inflation == 0.05
    for name in ("shape", "workspace", "obstacles", "resolution", "sample_spacing",
                 "motion_margin", "cover_cell", "band", "reach"):  # fmt: skip
        assert getattr(other, name) == getattr(direct, name), name
    poses = np.random.default_rng(3).uniform([0, 0, -3], [W, H, 3], (300, 3))
    assert np.array_equal(other.clearance(poses), direct.clearance(poses))
    assert not np.array_equal(other.clearance(poses), base.clearance(poses))


def test_bad_arguments():
    with pytest.raises(ValueError, match="inflation"):
        ObjectSpace(Circle(0.1), (W, H), [], inflation=-1.0)
    with pytest.raises(ValueError, match="inflation"):
        ObjectSpace(Rectangle((0.1, 0.3)), (W, H), [], inflation=-0.05)
    with pytest.raises(ValueError, match="inflation"):
        ObjectSpace(Circle(0.1), (W, H), [], inflation=float("nan"))
    shrunk = ObjectSpace(Rectangle((0.4, 0.2)), (W, H), [], inflation=-0.05)
    np.testing.assert_allclose(shrunk.clearance([0.5, 1.0, 0.0]), 0.35)
    with pytest.raises(ValueError, match="workspace"):
        ObjectSpace(Circle(0.1), (0.0, H), [])
    space = ObjectSpace(Circle(0.1), (W, H), [])
    with pytest.raises(ValueError, match="poses"):
        space.pose_free([1.0, 2.0])
