"""Tests of the MuJoCo simulator: pushing physics, walls, workspace checks, timing, API."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.shapes import to_shapely
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle, Scene, SceneObject
from lamp.sim import (
    MAX_STEP,
    ROBOT_SPEED,
    SETTLE_TIME,
    WORKSPACE_TOLERANCE,
    Simulator,
    footprint_outside,
)
from lamp.sim.mjcf import build_model, convex_pieces, plate_properties

R = 0.05  # robot radius
L_SHAPE = Polygon(((0.0, 0.0), (0.4, 0.0), (0.4, 0.1), (0.1, 0.1), (0.1, 0.3), (0.0, 0.3)))


def line(a, b, step: float = MAX_STEP, n: int | None = None) -> np.ndarray:
    """Waypoints from a to b, at most ``step`` apart (or ``n`` intervals), both ends included."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if n is None:
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
    return a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)


def hold(p, t: int) -> np.ndarray:
    return np.repeat(np.asarray(p, float)[None], t, axis=0)


def make_scene(objects, robots, obstacles=(), workspace=(3.0, 3.0)) -> Scene:
    objs = tuple(
        SceneObject(shape, tuple(map(float, pose)), tuple(map(float, pose)))
        for shape, pose in objects
    )
    return Scene(
        name="test",
        workspace=tuple(map(float, workspace)),
        robot_starts=tuple(tuple(map(float, p)) for p in robots),
        objects=objs,
        obstacles=tuple(obstacles),
        robot_radius=R,
    )


def penetration(shape, pose, centre) -> float:
    """How deep a robot disk at ``centre`` overlaps the object footprint (0 if apart)."""
    geom = to_shapely(shape, pose)
    p = shapely.Point(*centre)
    if geom.contains(p):
        return R + geom.exterior.distance(p)
    return max(0.0, R - geom.distance(p))


# ------------------------------------------------------------------ pushing


@pytest.mark.parametrize("angle", [0.0, 0.6, -2.0])
def test_straight_push_moves_box_along_push_by_commanded_distance(angle):
    """A centred push along the box's own x axis moves it that way, about as far as the robot
    travels after touching it (contact gap subtracted), without turning it."""
    d = np.array([np.cos(angle), np.sin(angle)])
    box = np.array([1.5, 1.5])
    start = box - (0.2 + R + 0.03) * d  # 3 cm gap before contact
    end = start + 0.6 * d
    sim = Simulator(make_scene([(Rectangle((0.4, 0.3)), (*box, angle))], [start]))
    out = sim.execute(line(start, end)[None])
    moved = out.object_poses[0, :2] - box
    along = moved @ d
    across = moved @ np.array([-d[1], d[0]])
    assert along == pytest.approx(0.6 - 0.03, abs=0.015)  # plus a few mm of coasting
    assert abs(across) < 0.005
    assert abs(np.angle(np.exp(1j * (out.object_poses[0, 2] - angle)))) < 0.01
    assert np.allclose(out.robot_positions[0], end, atol=2e-3)
    assert not out.left_workspace


def test_off_centre_push_turns_box_the_right_way():
    """Pushing +x above the centre line turns the box clockwise (negative theta)."""
    sim = Simulator(make_scene([(Rectangle((0.4, 0.3)), (1.0, 1.0, 0.0))], [(0.7, 1.1)]))
    out = sim.execute(line((0.7, 1.1), (1.2, 1.1))[None])
    assert out.object_poses[0, 2] < -0.2
    assert out.object_poses[0, 0] > 1.05


def test_two_robot_push_of_circle_and_polygon():
    """Two robots push a disk and an L-shaped polygon (through its centroid) straight ahead."""
    cx = 1.0 + plate_properties(L_SHAPE)[0][0]  # the L's centroid is at x = 1.15
    scene = make_scene(
        [(Circle(0.2), (1.0, 1.0, 0.0)), (L_SHAPE, (1.0, 2.0, 0.0))],
        [(1.0, 0.7), (cx, 1.9)],
    )
    sim = Simulator(scene)
    paths = np.stack([line((1.0, 0.7), (1.0, 1.2)), line((cx, 1.9), (cx, 2.4))])
    out = sim.execute(paths)
    # both: pushed +y by 0.5 minus the 0.05 contact gap
    assert out.object_poses[:, 1] == pytest.approx([1.45, 2.45], abs=0.015)
    assert out.object_poses[:, 0] == pytest.approx([1.0, 1.0], abs=0.005)
    assert out.object_poses[:, 2] == pytest.approx([0.0, 0.0], abs=0.01)


def test_pushed_box_pushes_another_box():
    """Objects collide with each other: a pushed box shoves the box in front of it."""
    scene = make_scene(
        [(Rectangle((0.2, 0.2)), (1.0, 1.0, 0.0)), (Rectangle((0.2, 0.2)), (1.3, 1.0, 0.0))],
        [(0.85, 1.0)],
    )
    out = Simulator(scene).execute(line((0.85, 1.0), (1.45, 1.0))[None])
    assert out.object_poses[1, 0] > 1.55  # moved by roughly 0.6 - 0.1 gap
    assert out.object_poses[1, 0] - out.object_poses[0, 0] >= 0.2 - 0.002  # never overlap


# ---------------------------------------------------------- walls, no tunnelling


def test_robot_commanded_through_border_wall_stops_at_it():
    sim = Simulator(make_scene([(Circle(0.1), (2.0, 2.0, 0.0))], [(0.3, 1.0)]))
    out = sim.execute(line((0.3, 1.0), (-0.4, 1.0))[None], record_every=1)
    xs = out.trace.robot_positions[:, 0, 0]
    assert xs.min() > R - 0.002
    assert out.robot_positions[0, 0] == pytest.approx(R, abs=0.002)
    assert out.robot_errors[0] > 0.4  # it could not reach the commanded end


def test_robot_commanded_through_thin_obstacle_stays_on_its_side():
    wall = Obstacle(Rectangle((0.01, 0.6)), (1.0, 1.0, 0.0))  # 1 cm thick
    sim = Simulator(make_scene([(Circle(0.1), (2.5, 2.5, 0.0))], [(0.7, 1.0)], [wall]))
    out = sim.execute(line((0.7, 1.0), (1.4, 1.0))[None], record_every=1)
    xs = out.trace.robot_positions[:, 0, 0]
    assert xs.max() < 1.0 - 0.005 - R + 0.002


def test_robot_path_through_free_object_pushes_it_never_enters_it():
    """A robot driven straight through an object's footprint pushes the object ahead."""
    scene = make_scene([(L_SHAPE, (1.0, 1.0, 0.3))], [(0.6, 1.15)])
    sim = Simulator(scene)
    out = sim.execute(line((0.6, 1.15), (1.6, 1.15))[None], record_every=1)
    tr = out.trace
    worst = max(
        penetration(L_SHAPE, tr.object_poses[i, 0], tr.robot_positions[i, 0])
        for i in range(0, len(tr.times), 5)
    )
    assert worst < 0.002
    assert out.object_poses[0, 0] > 1.5  # it was pushed along


@pytest.mark.parametrize("shape", [Rectangle((0.3, 0.3)), L_SHAPE, Circle(0.15)])
def test_object_pushed_into_border_wall_stays_inside(shape):
    """Walls keep objects in: three robots at their force limit press an object into the right
    border; it stops at the wall, sinks in by far less than the tolerance, is not reported."""
    scene = make_scene(
        [(shape, (1.3, 1.0, 0.0))], [(1.0, 0.9), (1.0, 1.0), (1.0, 1.1)], workspace=(2.0, 2.0)
    )
    paths = np.stack([line((1.0, y), (2.5, y), n=75) for y in (0.9, 1.0, 1.1)])
    out = Simulator(scene).execute(paths, record_every=1)
    right = max(to_shapely(shape, p).bounds[2] for p in out.trace.object_poses[::4, 0])
    assert 2.0 - 0.002 < right < 2.0 + 0.5 * WORKSPACE_TOLERANCE
    assert not out.left_workspace
    assert np.all(out.robot_positions[:, 0] < 2.0 - 0.02)  # the robots stop behind it


def test_untouched_object_does_not_drift_or_spin():
    scene = make_scene([(L_SHAPE, (1.5, 1.5, 0.7)), (Circle(0.15), (2.5, 0.5, 0.0))], [(0.3, 0.3)])
    sim = Simulator(scene)
    before = sim.object_poses
    assert np.allclose(before, scene.object_starts(), atol=1e-12)
    path = np.concatenate([line((0.3, 0.3), (1.0, 0.3)), line((1.0, 0.3), (0.3, 0.3))])
    out = sim.execute(path[None], settle_time=2.0)
    assert out.sim_time > 7.0
    assert np.array_equal(out.object_poses, before)  # bit-identical: no force, no motion


# --------------------------------------------------------------- workspace check


def _footprint_outside_reference(shape, pose, workspace, tol) -> bool:
    box = shapely.box(-tol, -tol, workspace[0] + tol, workspace[1] + tol)
    geom = (
        to_shapely(shape, pose)
        if not isinstance(shape, Circle)
        else shapely.Point(pose[:2]).buffer(shape.radius, 256)
    )
    return not box.buffer(1e-9).contains(geom)


@settings(max_examples=200, deadline=None)
@given(
    kind=st.sampled_from(["circle", "rect", "L"]),
    x=st.floats(-0.3, 2.3),
    y=st.floats(-0.3, 1.8),
    th=st.floats(-4.0, 4.0),
    tol=st.sampled_from([0.0, 0.01]),
)
def test_footprint_outside_matches_shapely(kind, x, y, th, tol):
    shape = {"circle": Circle(0.2), "rect": Rectangle((0.4, 0.2)), "L": L_SHAPE}[kind]
    pose = np.array([x, y, th])
    expected = _footprint_outside_reference(shape, pose, (2.0, 1.5), tol)
    got = bool(footprint_outside(shape, pose, (2.0, 1.5), tol))
    if got != expected:  # only tolerate disagreement within a hair of the border
        geom = to_shapely(shape, pose)
        gap = min(
            geom.bounds[0] + tol,
            geom.bounds[1] + tol,
            2.0 + tol - geom.bounds[2],
            1.5 + tol - geom.bounds[3],
        )
        assert abs(gap) < 1e-3
    # batched call agrees with single calls
    batch = footprint_outside(shape, np.stack([pose, pose]), (2.0, 1.5), tol)
    assert batch.shape == (2,) and batch[0] == got


def test_left_workspace_reported_for_object_partly_outside():
    """An object placed across the border (beyond the tolerance) is reported, one inside is not."""
    scene = make_scene(
        [(Rectangle((0.3, 0.3)), (1.0, 1.0, 0.0)), (Circle(0.1), (2.0, 2.0, 0.0))], [(0.5, 0.5)]
    )
    sim = Simulator(
        scene, object_poses=[[0.15 - 2 * WORKSPACE_TOLERANCE, 1.0, 0.0], [2.0, 2.0, 0.0]]
    )
    out = sim.execute(hold((0.5, 0.5), 1)[None])
    # the wall pushes the overlapping box back in, but it was outside during the call
    assert out.left_workspace
    assert out.objects_left.tolist() == [True, False]
    assert out.object_poses[0, 0] - 0.15 > -WORKSPACE_TOLERANCE


# ------------------------------------------------------------------- timing


def test_robot_speed_matches_documented_speed():
    sim = Simulator(make_scene([(Circle(0.1), (2.5, 2.5, 0.0))], [(0.5, 0.5)]))
    path = line((0.5, 0.5), (1.7, 1.4))  # 1.5 m
    out = sim.execute(path[None], record_every=10)
    tr = out.trace
    speed = np.hypot(*np.diff(tr.robot_positions[:, 0], axis=0).T) / np.diff(tr.times)
    mid = speed[(tr.times[1:] > 1.0) & (tr.times[1:] < 5.0)]
    assert np.all(np.abs(mid - ROBOT_SPEED) < 0.1 * ROBOT_SPEED)
    assert out.sim_time == pytest.approx(1.5 / ROBOT_SPEED + SETTLE_TIME, abs=0.01)


def test_robots_stay_synchronised_with_different_step_lengths():
    """Rows are synchronised: a robot with half-length steps moves at half speed and both
    reach each row together."""
    sim = Simulator(make_scene([(Circle(0.1), (2.5, 2.5, 0.0))], [(0.5, 0.5), (0.5, 1.5)]))
    paths = np.stack([line((0.5, 0.5), (1.3, 0.5)), line((0.5, 1.5), (0.9, 1.5), n=40)])
    targets = sim.targets(paths)
    out = sim.execute(paths, record_every=25)
    tr = out.trace
    assert np.allclose(
        (tr.robot_positions[:, 0, 0] - 0.5) / 2.0, tr.robot_positions[:, 1, 0] - 0.5, atol=0.004
    )
    assert np.allclose(targets[-1], paths[:, -1])
    assert out.sim_time == pytest.approx(0.8 / ROBOT_SPEED + SETTLE_TIME, abs=0.01)


# ------------------------------------------------------- state, determinism, API


def test_state_carries_over_between_calls():
    scene = make_scene([(Rectangle((0.4, 0.3)), (1.0, 1.0, 0.0))], [(0.75, 1.0)])
    one = Simulator(scene).execute(line((0.75, 1.0), (1.35, 1.0))[None])
    sim = Simulator(scene)
    a = sim.execute(line((0.75, 1.0), (1.05, 1.0))[None])
    assert np.array_equal(sim.object_poses, a.object_poses)
    assert np.array_equal(sim.robot_positions, a.robot_positions)
    b = sim.execute(line(sim.robot_positions[0], (1.35, 1.0))[None])
    assert b.object_poses[0, 0] == pytest.approx(one.object_poses[0, 0], abs=0.01)
    assert b.object_poses[0, 0] > a.object_poses[0, 0] + 0.25
    assert sim.time == pytest.approx(a.sim_time + b.sim_time)


def test_deterministic_new_simulator_or_reset():
    scene = make_scene(
        [(L_SHAPE, (1.0, 1.0, 0.3)), (Rectangle((0.2, 0.2)), (1.5, 1.2, 0.0))],
        [(0.6, 1.15), (0.6, 0.8)],
    )
    paths = np.stack(
        [
            line((0.6, 1.15), (1.6, 1.15)),
            line((0.6, 0.8), (1.6, 1.05))[: len(line((0.6, 1.15), (1.6, 1.15)))],
        ]
    )
    sim1 = Simulator(scene)
    start = sim1.state()
    r1 = sim1.execute(paths, record_every=7)
    r2 = Simulator(scene).execute(paths, record_every=7)
    sim1.set_state(start)
    r3 = sim1.execute(paths, record_every=7)
    for r in (r2, r3):
        assert np.array_equal(r1.object_poses, r.object_poses)
        assert np.array_equal(r1.robot_positions, r.robot_positions)
        assert np.array_equal(r1.trace.object_poses, r.trace.object_poses)
    # a snapshot mid-way restores the continuation exactly
    mid = sim1.state()
    back = line(sim1.robot_positions[0], (1.2, 1.5))
    c1 = sim1.execute(np.stack([back, hold(sim1.robot_positions[1], len(back))]))
    sim1.set_state(mid)
    c2 = sim1.execute(np.stack([back, hold(sim1.robot_positions[1], len(back))]))
    assert np.array_equal(c1.object_poses, c2.object_poses)


def test_execute_validates_input():
    sim = Simulator(make_scene([(Circle(0.1), (2.0, 2.0, 0.0))], [(0.5, 0.5), (1.0, 0.5)]))
    good = np.stack([line((0.5, 0.5), (0.6, 0.5), n=10), line((1.0, 0.5), (1.1, 0.5), n=10)])
    with pytest.raises(ValueError, match="shape"):
        sim.execute(good[:1])
    with pytest.raises(ValueError, match="shape"):
        sim.execute(good[..., :1])
    with pytest.raises(ValueError, match="shape"):
        sim.execute(good[:, :0])
    bad = good.copy()
    bad[1, 3, 0] = np.nan
    with pytest.raises(ValueError, match=r"robot_paths\[1, 3\].*not finite"):
        sim.execute(bad)
    bad = good.copy()
    bad[0, 4:] += 0.03
    with pytest.raises(ValueError, match=r"robot_paths\[0\] moves 0.0500 m between rows 3 and 4"):
        sim.execute(bad)
    with pytest.raises(ValueError, match=r"robot_paths\[1, 0\].*from robot 1"):
        sim.execute(good + np.array([[[0.0, 0.0]], [[0.1, 0.0]]]))  # robot 1 starts 0.1 m off
    with pytest.raises(ValueError, match="numeric"):
        sim.execute([["a"]])
    with pytest.raises(ValueError, match="record_every"):
        sim.execute(good, record_every=0)
    with pytest.raises(ValueError, match="settle_time"):
        sim.execute(good, settle_time=-1.0)
    with pytest.raises(ValueError, match="object_poses"):
        Simulator(sim.scene, object_poses=np.zeros((2, 3)))
    assert sim.time == 0.0  # nothing ran
    sim.execute(good)  # and a good path still runs


def test_trace_and_result_shapes():
    scene = make_scene(
        [(Circle(0.1), (2.0, 2.0, 0.0)), (L_SHAPE, (1.0, 2.0, 0.0))], [(0.5, 0.5), (1.0, 0.5)]
    )
    sim = Simulator(scene)
    paths = np.stack([line((0.5, 0.5), (0.7, 0.5)), line((1.0, 0.5), (1.2, 0.5))])
    out = sim.execute(paths, record_every=30)
    n = out.steps
    assert out.sim_time == pytest.approx(n * 0.002)
    assert out.trace.robot_positions.shape == (len(out.trace.times), 2, 2)
    assert out.trace.object_poses.shape == (len(out.trace.times), 2, 3)
    assert out.trace.times[0] == 0.0 and out.trace.times[-1] == pytest.approx(out.sim_time)
    assert np.array_equal(out.trace.robot_positions[-1], out.robot_positions)
    assert out.object_poses.shape == (2, 3) and out.robot_positions.shape == (2, 2)
    assert np.all(np.abs(out.object_poses[:, 2]) <= np.pi)
    assert out.trace is not None and sim.execute(paths[:, -1:]).trace is None
    still = sim.execute(sim.robot_positions[:, None], settle_time=0.0, record_every=1)  # no-op
    assert still.steps == 0 and len(still.trace.times) == 1


def test_start_poses_round_trip_and_model_cache():
    """Poses (including off-centroid polygons) read back as set; one structure, one model."""
    scene = make_scene([(L_SHAPE, (1.0, 1.0, 2.5)), (Circle(0.1), (2.0, 2.0, 0.0))], [(0.3, 0.3)])
    sim = Simulator(scene)
    assert np.allclose(sim.object_poses, scene.object_starts(), atol=1e-12)
    poses = np.array([[1.5, 1.2, -3.0], [2.5, 0.5, 1.0]])
    other = Simulator(scene, object_poses=poses, robot_positions=[[0.2, 2.0]])
    assert other.model is sim.model
    assert np.allclose(other.object_poses, poses, atol=1e-12)
    assert np.allclose(other.robot_positions, [[0.2, 2.0]])


# ------------------------------------------------------------------ model parts


@st.composite
def star_polygons(draw):
    n = draw(st.integers(3, 9))
    angles = np.sort(
        np.array(draw(st.lists(st.floats(0.0, 2 * np.pi), min_size=n, max_size=n, unique=True)))
    )
    gaps = np.diff(np.concatenate([angles, [angles[0] + 2 * np.pi]]))
    if gaps.min() < 0.05 or gaps.max() > 0.9 * np.pi:  # keep the origin inside: star-shaped
        angles = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    radii = np.array(draw(st.lists(st.floats(0.05, 0.3), min_size=n, max_size=n)))
    pts = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
    return tuple(map(tuple, pts))


@settings(max_examples=60, deadline=None)
@given(points=star_polygons())
def test_convex_pieces_tile_the_polygon(points):
    poly = shapely.Polygon(points)
    pieces = [shapely.Polygon(p) for p in convex_pieces(points)]
    for p in pieces:
        assert p.is_valid
        assert p.area == pytest.approx(p.convex_hull.area, rel=1e-9)
    assert sum(p.area for p in pieces) == pytest.approx(poly.area, rel=1e-9)
    assert (
        shapely.union_all(pieces).symmetric_difference(poly).area
        < 1e-9 * max(poly.area, 1e-9) + 1e-12
    )
    assert len(pieces) <= len(points) - 2


def test_plate_properties_match_closed_forms():
    c, rho2 = plate_properties(Rectangle((0.4, 0.2)))
    assert np.allclose(c, 0.0) and rho2 == pytest.approx((0.16 + 0.04) / 12)
    c, rho2 = plate_properties(Circle(0.3))
    assert rho2 == pytest.approx(0.045)
    c, rho2 = plate_properties(L_SHAPE)
    cen = shapely.Polygon(L_SHAPE.points).centroid
    assert np.allclose(c, [cen.x, cen.y])
    # the L as two rectangles: [0,0.4]x[0,0.1] and [0,0.1]x[0.1,0.3], parallel-axis theorem
    parts = [((0.2, 0.05), 0.4, 0.1), ((0.05, 0.2), 0.1, 0.2)]
    area = sum(a * b for _, a, b in parts)
    j = sum(
        a * b * ((a * a + b * b) / 12 + (x - c[0]) ** 2 + (y - c[1]) ** 2) for (x, y), a, b in parts
    )
    assert rho2 == pytest.approx(j / area)


def test_model_has_walls_and_obstacle_geoms_in_place():
    tri = Obstacle(Polygon(((2.0, 2.0), (2.5, 2.0), (2.2, 2.6))))
    scene = make_scene(
        [(Rectangle((0.2, 0.2)), (1.0, 1.0, 0.0))],
        [(0.3, 0.3)],
        [
            Obstacle(Circle(0.15), (0.5, 2.5, 0.0)),
            Obstacle(Rectangle((0.2, 1.0)), (1.5, 2.0, 0.4)),
            tri,
        ],
    )
    sim = Simulator(scene)
    # a robot driven at each obstacle stops at its surface
    for target, surface in [((0.5, 2.5), Circle(0.15)), ((2.2, 2.2), tri.shape)]:
        start = np.array([0.5, 1.8]) if target[0] < 1 else np.array([2.2, 1.5])
        sim.set_state(robot_positions=[start])
        out = sim.execute(line(start, target)[None], record_every=1)
        geom = to_shapely(surface, (0.5, 2.5, 0.0) if isinstance(surface, Circle) else (0, 0, 0))
        dist = min(geom.distance(shapely.Point(*p)) for p in out.trace.robot_positions[::10, 0])
        assert dist > R - 0.002
        assert geom.distance(shapely.Point(*out.robot_positions[0])) < R + 0.002
    assert build_model(scene).model.ngeom == 4 + 3 + 1 + 1  # walls, obstacles, object, robot


def test_robots_do_not_pass_through_each_other():
    """Robots are bodies too: one driven through another that holds still is stopped."""
    sim = Simulator(make_scene([(Circle(0.1), (2.5, 2.5, 0.0))], [(0.5, 1.0), (1.0, 1.0)]))
    path = line((0.5, 1.0), (1.5, 1.0))
    out = sim.execute(np.stack([path, hold((1.0, 1.0), len(path))]), record_every=1)
    gap = np.linalg.norm(out.trace.robot_positions[:, 0] - out.trace.robot_positions[:, 1], axis=1)
    assert gap.min() > 2 * R - 0.002
    assert out.robot_positions[0, 0] < out.robot_positions[1, 0]


def test_object_pushed_into_obstacle_does_not_enter_it():
    post = Obstacle(Circle(0.15), (1.6, 1.05, 0.0))
    scene = make_scene([(Rectangle((0.3, 0.3)), (1.0, 1.0, 0.0))], [(0.8, 1.0)], [post])
    out = Simulator(scene).execute(line((0.8, 1.0), (1.6, 1.0))[None], record_every=5)
    core = to_shapely(post.shape, post.pose).buffer(-0.002)
    for pose in out.trace.object_poses[:, 0]:
        assert not core.intersects(to_shapely(Rectangle((0.3, 0.3)), pose))
    assert out.object_poses[0, 0] < 1.6 - 0.15 - 0.15 + 0.05  # it got stuck or deflected


def test_scene_without_objects_runs():
    scene = Scene("empty", (2.0, 2.0), ((0.5, 0.5),), (), (), R)
    sim = Simulator(scene)
    out = sim.execute(line((0.5, 0.5), (1.0, 0.5))[None])
    assert out.object_poses.shape == (0, 3) and not out.left_workspace
    assert np.allclose(out.robot_positions, [[1.0, 0.5]], atol=1e-3)


def test_robot_stops_at_concave_polygon_obstacle():
    """A non-convex obstacle (decomposed into convex pieces) stops a robot driven into its
    inner corner, from inside the notch."""
    notch = Obstacle(
        Polygon(((1.0, 1.0), (2.0, 1.0), (2.0, 1.2), (1.2, 1.2), (1.2, 2.0), (1.0, 2.0)))
    )
    sim = Simulator(make_scene([(Circle(0.1), (2.5, 2.5, 0.0))], [(1.6, 1.6)], [notch]))
    out = sim.execute(line((1.6, 1.6), (1.1, 1.1))[None], record_every=1)
    geom = to_shapely(notch.shape)
    dist = [geom.distance(shapely.Point(*p)) for p in out.trace.robot_positions[::5, 0]]
    assert min(dist) > R - 0.002
    assert np.allclose(out.robot_positions[0], [1.2 + R, 1.2 + R], atol=0.003)  # in the corner


def test_chunked_rollout_matches_single_rollout(monkeypatch):
    """Long calls are rolled out in chunks; the chunk size must not change anything."""
    import lamp.sim.simulator as simulator

    scene = make_scene([(L_SHAPE, (1.0, 1.0, 0.3))], [(0.6, 1.15)])
    path = line((0.6, 1.15), (1.6, 1.15))[None]
    whole = Simulator(scene).execute(path, record_every=9)
    monkeypatch.setattr(simulator, "_CHUNK", 37)
    chunked = Simulator(scene).execute(path, record_every=9)
    assert whole.steps > 10 * 37
    assert np.array_equal(whole.object_poses, chunked.object_poses)
    assert np.array_equal(whole.trace.times, chunked.trace.times)
    assert np.array_equal(whole.trace.object_poses, chunked.trace.object_poses)
    assert np.array_equal(whole.trace.robot_positions, chunked.trace.robot_positions)
