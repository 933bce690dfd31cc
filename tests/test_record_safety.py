"""``lamp.record.safety``: the independent collision check of recorded runs.

Property tests against brute-force references in plain Python (disks and axis-aligned
rectangles), a hand-built recording with one known collision of each kind (kind, bodies,
first time and depth), a clean hand-built recording, tunnelling between rows, and a real
run of the tiny scene that must come out clean.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scenes import TINY

from lamp.record.safety import (
    DEFAULT_TOL,
    KINDS,
    SAMPLE_SPACING,
    Violation,
    check_recording,
    check_run_dir,
)
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle, Scene, SceneObject

R = 0.05  # robot radius
W, H = 4.0, 3.0
DT = 0.08
FAR = (3.8, 2.8)  # a spare robot's parking spot, clear of everything below


def make_scene(robots=(FAR,), obstacles=(), objects=()) -> Scene:
    objs = tuple(SceneObject(shape, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)) for shape in objects)
    return Scene("hand", (W, H), tuple(robots), objs, tuple(obstacles), robot_radius=R)


def check_one_row(scene, robots, objects=(), tol=0.0):
    robots = np.asarray(robots, float).reshape(1, -1, 2)
    objects = np.asarray(objects, float).reshape(1, -1, 3)
    return check_recording(scene, [0.0], robots, objects, tol=tol)


def rot(theta, v):
    c, s = math.cos(theta), math.sin(theta)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1])


# ------------------------------------------------------------------ brute-force references
def ref_box_sd(px, py, cx, cy, hx, hy):
    """Signed distance of a point from the box [cx - hx, cx + hx] x [cy - hy, cy + hy]."""
    dx, dy = abs(px - cx) - hx, abs(py - cy) - hy
    if dx <= 0 and dy <= 0:
        return max(dx, dy)
    return math.hypot(max(dx, 0.0), max(dy, 0.0))


def ref_edge_depth(lo, hi, at, box, horizontal):
    """Deepest point of the axis-aligned edge {(t, at): lo <= t <= hi} (or (at, t)) inside
    ``box`` = (x0, x1, y0, y1), measured to the box's boundary (0 when it is outside)."""
    x0, x1, y0, y1 = box
    (t0, t1), (c0, c1) = ((x0, x1), (y0, y1)) if horizontal else ((y0, y1), (x0, x1))
    if not c0 < at < c1:
        return 0.0
    a, b = max(lo, t0), min(hi, t1)
    if a > b:
        return 0.0
    cap = min(at - c0, c1 - at)
    mid = min(max(0.5 * (t0 + t1), a), b)
    return max(min(t - t0, t1 - t, cap) for t in (a, b, mid))


def ref_box_box(a, b):
    """Deepest point of either box's outline inside the other; boxes are (x0, x1, y0, y1)."""
    best = 0.0
    for p, q in ((a, b), (b, a)):
        x0, x1, y0, y1 = p
        for at in (y0, y1):
            best = max(best, ref_edge_depth(x0, x1, at, q, True))
        for at in (x0, x1):
            best = max(best, ref_edge_depth(y0, y1, at, q, False))
    return best


def ref_box_box_vertices(a, b):
    best = 0.0
    for p, q in ((a, b), (b, a)):
        for x in p[:2]:
            for y in p[2:]:
                best = max(best, -ref_box_sd(x, y, 0.5 * (q[0] + q[1]), 0.5 * (q[2] + q[3]),
                                              0.5 * (q[1] - q[0]), 0.5 * (q[3] - q[2])))
    return best


# ------------------------------------------------------------------------ property tests
coord = st.floats(0.3, 1.5)


@given(st.lists(st.tuples(coord, coord), min_size=2, max_size=6))
def test_robot_pairs_match_pairwise_distances(points):
    scene = make_scene(robots=points)
    report = check_one_row(scene, points, tol=0.004)
    want = {(i, j): 2 * R - math.dist(points[i], points[j])
            for i in range(len(points)) for j in range(i + 1, len(points))}
    assert report.worst_depth["robot-robot"] == pytest.approx(
        max(0.0, *want.values()), abs=1e-9)
    assert {(v.a, v.b) for v in report.violations} == {k for k, d in want.items() if d > 0.004}


@given(coord, coord, coord, coord, st.floats(0.02, 0.5), st.floats(0.02, 0.5),
       st.floats(-3.2, 3.2), st.booleans())
def test_disk_against_a_rectangle_matches_the_box_distance(px, py, cx, cy, sx, sy, theta,
                                                           as_object):
    """A robot against a rotated rectangle obstacle or object: r - signed distance."""
    rect = Rectangle((sx, sy))
    u, v = rot(-theta, (px - cx, py - cy))  # the robot in the rectangle's frame
    want = max(0.0, R - ref_box_sd(u, v, 0.0, 0.0, sx / 2, sy / 2))
    if as_object:
        report = check_one_row(make_scene([(px, py)], objects=[rect]), [(px, py)],
                               [(cx, cy, theta)])
        got = report.worst_depth["robot-object"]
    else:
        report = check_one_row(make_scene([(px, py)], [Obstacle(rect, (cx, cy, theta))]),
                               [(px, py)])
        got = report.worst_depth["robot-obstacle"]
    assert got == pytest.approx(want, abs=1e-9)


@given(coord, coord, st.floats(0.02, 0.6), st.floats(0.02, 0.6),
       coord, coord, st.floats(0.02, 0.6), st.floats(0.02, 0.6), st.booleans())
def test_two_rectangles_match_the_deepest_outline_point(ax, ay, asx, asy, bx, by, bsx, bsy,
                                                        obstacle):
    """Axis-aligned boxes: exact at the vertices, never too deep, at most half the sample
    spacing short (edges crossing without a vertex inside)."""
    box_a = (ax - asx / 2, ax + asx / 2, ay - asy / 2, ay + asy / 2)
    box_b = (bx - bsx / 2, bx + bsx / 2, by - bsy / 2, by + bsy / 2)
    if obstacle:
        scene = make_scene(obstacles=[Obstacle(Rectangle((bsx, bsy)), (bx, by, 0.0))],
                           objects=[Rectangle((asx, asy))])
        got = check_one_row(scene, [FAR], [(ax, ay, 0.0)]).worst_depth["object-obstacle"]
    else:
        scene = make_scene(objects=[Rectangle((asx, asy)), Rectangle((bsx, bsy))])
        got = check_one_row(scene, [FAR], [(ax, ay, 0.0), (bx, by, 0.0)]).worst_depth[
            "object-object"]
    want = ref_box_box(box_a, box_b)
    assert ref_box_box_vertices(box_a, box_b) - 1e-9 <= got <= want + 1e-9
    assert got >= want - SAMPLE_SPACING / 2 - 1e-9


@given(st.floats(-0.2, W + 0.2), st.floats(-0.2, H + 0.2), st.floats(-3.2, 3.2),
       st.floats(0.02, 0.5), st.floats(0.02, 0.5))
def test_border_depth_is_the_farthest_corner_or_disk_point_outside(x, y, theta, sx, sy):
    corners = [rot(theta, (ex * sx / 2, ey * sy / 2)) for ex in (-1, 1) for ey in (-1, 1)]
    want_box = max(0.0, *(max(-(x + u), x + u - W, -(y + v), y + v - H)
                          for u, v in corners))
    want_disk = max(0.0, R - x, x + R - W, R - y, y + R - H)
    report = check_one_row(make_scene([(x, y)], objects=[Rectangle((sx, sy))]),
                           [(x, y)], [(x, y, theta)])
    assert report.worst_depth["object-border"] == pytest.approx(want_box, abs=1e-9)
    assert report.worst_depth["robot-border"] == pytest.approx(want_disk, abs=1e-9)


@given(st.floats(0.2, 0.8), st.floats(0.0, 2 * math.pi), st.floats(0.2, 0.8),
       st.floats(0.002, 0.05))
def test_a_robot_jumping_across_an_obstacle_between_rows_is_caught(length, heading, frac,
                                                                   radius):
    """The straight path crosses a small disk obstacle; both recorded rows are clear."""
    c = np.array([2.0, 1.5])
    d = np.array([math.cos(heading), math.sin(heading)])
    p, q = c - frac * length * d, c + (1 - frac) * length * d
    clear = radius + R + 0.01
    p = c + (p - c) * max(1.0, clear / np.linalg.norm(p - c))
    q = c + (q - c) * max(1.0, clear / np.linalg.norm(q - c))
    scene = make_scene([p], [Obstacle(Circle(radius), (c[0], c[1], 0.0))])
    report = check_recording(scene, [1.0, 1.0 + DT], np.array([[p], [q]]), np.zeros((2, 0, 3)))
    assert report.states_checked > report.rows_checked == 2
    (v,) = report.violations
    assert (v.kind, v.a, v.b) == ("robot-obstacle", 0, 0)
    assert v.depth_m >= radius + 0.75 * R - 1e-9 and 1.0 < v.time_s < 1.0 + DT


# -------------------------------------------------------------- one known collision a kind
DEPTHS = [-0.03, -0.02, -0.01, 0.001, 0.006, 0.012, 0.006, -0.01]  # per row
FIRST, WORST = 4, 5  # first row over the 2-3 mm tolerances; deepest row
SQ = 0.1 * math.sqrt(2)  # half diagonal of a 0.2 m square


def _case(kind):
    """(scene, place(depth) -> (robots (N, 2), objects (K, 3)), a, b)."""
    tri = Polygon(((1.8, 0.4), (2.2, 0.4), (2.0, 0.8)))
    box = Rectangle((0.3, 0.2))
    obj = (2.0, 1.5, 0.3)
    o = np.array(obj[:2])
    cases = {
        "robot-robot": (make_scene([(1.0, 1.0), (1.2, 1.0)]),
                        lambda d: ([(1.0, 1.0), (1.0 + 2 * R - d, 1.0)], []), 0, 1),
        "robot-obstacle": (make_scene([FAR, (1, 1)], [Obstacle(Circle(0.3), (1, 2, 0)),
                                                      Obstacle(tri)]),
                           lambda d: ([FAR, (2.0, 0.4 - R + d)], []), 1, 1),
        "robot-border": (make_scene([(1.0, 1.0)]), lambda d: ([(1.0, H - R + d)], []), 0, -1),
        "robot-object": (make_scene([FAR, (1, 1)], objects=[box]),
                         lambda d: ([FAR, o + rot(0.3, (0.15 + R - d, 0))], [obj]), 1, 0),
        "object-object": (make_scene(objects=[Circle(0.1), box, Rectangle((0.2, 0.2))]),
                          lambda d: ([FAR], [(0.5, 0.5, 0), (2.0, 1.5, 0),
                                             (2.0 + 0.15 + SQ - d, 1.5, math.pi / 4)]), 1, 2),
        "object-obstacle": (make_scene(obstacles=[Obstacle(box, (2.0, 2.0, 0.0))],
                                       objects=[Rectangle((0.2, 0.1))]),
                            lambda d: ([FAR], [(2.0 + 0.25 - d, 2.0, 0.0)]), 0, 0),
        "object-border": (make_scene(objects=[Circle(0.1), box]),
                          lambda d: ([FAR], [(0.5, 0.5, 0.0), (0.15 - d, 1.0, 0.0)]), 1, -1),
    }
    return cases[kind]


def _recording(place, depths=DEPTHS):
    rows = [place(d) for d in depths]
    robots = np.array([np.asarray(r, float) for r, _ in rows])
    objects = np.array([np.asarray(k, float).reshape(-1, 3) for _, k in rows])
    return DT * np.arange(len(depths)), robots, objects


@pytest.mark.parametrize("kind", [k for k in KINDS if k != "robot-pushed-object"])
def test_a_known_collision_is_reported_with_its_time_and_depth(kind):
    """(Pushing contact has its own test below: it needs the robots' sub-teams.)"""
    scene, place, a, b = _case(kind)
    times, robots, objects = _recording(place)
    report = check_recording(scene, times, robots, objects)
    assert report.violations == [Violation(times[FIRST], kind, a, b, pytest.approx(0.012, abs=1e-6),
                                           times[WORST])]
    assert not report.ok and report.states_checked == report.rows_checked == len(DEPTHS)
    assert report.worst_depth[kind] == pytest.approx(0.012, abs=1e-6)
    assert all(report.worst_depth[k] == 0.0 for k in KINDS if k != kind)
    assert kind in report.summary() and "1 violation" in report.summary()
    clean = check_recording(scene, *_recording(place, [min(d, 0.001) for d in DEPTHS]))
    assert clean.ok and clean.worst_depth[kind] == pytest.approx(0.001, abs=1e-6)


def test_a_clean_hand_built_recording_has_no_violations():
    scene = make_scene([(0.3, 0.3), (0.3, 0.5), (0.3, 0.7)],
                       [Obstacle(Circle(0.2), (3.0, 2.2, 0.0)),
                        Obstacle(Rectangle((0.4, 0.2)), (1.0, 2.5, 0.4)),
                        Obstacle(Polygon(((3.3, 0.4), (3.7, 0.4), (3.5, 0.8))))],
                       [Rectangle((0.3, 0.2)), Circle(0.1)])
    t = np.arange(40)
    robots = np.stack([np.stack([0.3 + 0.02 * t, y + 0 * t], axis=1) for y in (0.3, 0.5, 0.7)],
                      axis=1)
    objects = np.stack([np.stack([1.0 + 0.01 * t, 1.2 + 0 * t, 0.02 * t], axis=1),
                        np.stack([2.0 + 0 * t, 1.2 + 0.01 * t, 0 * t], axis=1)], axis=1)
    report = check_recording(scene, DT * t, robots, objects)
    assert report.ok and report.violations == []
    assert report.rows_checked == report.states_checked == 40
    assert max(report.worst_depth.values()) == 0.0
    assert report.summary().splitlines()[0].endswith(": OK")


def test_tolerances_one_for_all_or_per_kind():
    scene, place, _, _ = _case("robot-object")
    rec = _recording(place)
    assert check_recording(scene, *rec, tol=0.02).ok
    assert not check_recording(scene, *rec, tol={"robot-robot": 0.02}).ok
    assert check_recording(scene, *rec, tol={"robot-object": 0.013}).tol == {
        **DEFAULT_TOL, "robot-object": 0.013}
    with pytest.raises(ValueError, match="unknown kinds"):
        check_recording(scene, *rec, tol={"robot-wall": 0.01})
    with pytest.raises(ValueError, match="expected robots"):
        check_recording(scene, rec[0], rec[1][:, :1], rec[2])


# ------------------------------------------------------------------------ a real recording
def test_a_real_run_of_the_tiny_scene_is_clean(tmp_path):
    from lamp.manip import GeometricProposer
    from lamp.pipeline import RunRequest, run
    from lamp.record import save_recording
    from lamp.scene import scene_from_dict

    rec = run(RunRequest(scene_from_dict(TINY), "lazy", 0, GeometricProposer())).recording
    save_recording(rec, tmp_path)
    report = check_run_dir(tmp_path)
    assert report.ok, report.summary()
    assert report.rows_checked == rec.n_rows and (report.n_robots, report.n_objects) == (3, 1)
    # the robots pushed the box: they touched it, pressing in far less than the tolerance;
    # a sequential run's robots all work for the segment's object: pushing contact
    assert 0.0 < report.worst_depth["robot-pushed-object"] < DEFAULT_TOL["robot-object"] / 4
    assert report.worst_depth["robot-object"] == 0.0


def test_contact_with_the_pushed_object_has_its_own_kind_and_tolerance():
    """A robot 5 mm into a box: a collision for another sub-team's robot, pushing for the
    robot whose sub-team moves the box (deeper than 10 mm is reported again)."""
    scene = make_scene([(1.0, 1.5), FAR], objects=[Rectangle((0.2, 0.2))])
    box = np.array([[[1.0 + R + 0.1 - 0.005, 1.5, 0.0]]] * 2)
    robots = np.array([[[1.0, 1.5], FAR]] * 2)
    other = check_recording(scene, [0.0, DT], robots, box, robot_team=[[-1, -1], [-1, -1]])
    assert [(v.kind, v.a, v.b) for v in other.violations] == [("robot-object", 0, 0)]
    own = check_recording(scene, [0.0, DT], robots, box, robot_team=[[0, -1], [0, -1]])
    assert own.ok and own.worst_depth["robot-pushed-object"] == pytest.approx(0.005, abs=1e-6)
    deep = np.array([[[1.0 + R + 0.1 - 0.012, 1.5, 0.0]]] * 2)
    report = check_recording(scene, [0.0, DT], robots, deep, robot_team=[[0, -1], [0, -1]])
    assert [(v.kind, v.a, v.b) for v in report.violations] == [("robot-pushed-object", 0, 0)]


def test_a_robot_and_a_thin_object_passing_through_each_other_between_rows_are_caught():
    """Both move 0.3 m the opposite ways in one row interval; both rows are clear."""
    scene = make_scene([(1.0, 1.5)], objects=[Rectangle((0.02, 0.4))])
    robots = np.array([[[1.0, 1.5]], [[1.3, 1.5]]])
    objects = np.array([[[1.3, 1.5, 0.0]], [[1.0, 1.5, 0.0]]])
    report = check_recording(scene, [0.0, DT], robots, objects)
    assert [(v.kind, v.a, v.b) for v in report.violations] == [("robot-object", 0, 0)]
    assert report.violations[0].depth_m >= R / 2
    assert report.states_checked == 13  # 0.3 m in 12 steps of r / 2


@given(st.integers(0, 2**32 - 1), st.integers(2, 7), st.integers(1, 12))
def test_robot_pairs_against_a_brute_force(seed, n, rows) -> None:
    """Several robots wandering in small steps (no state interpolated): every pair closer
    than 2r - tol is one violation with its first time, its depth and the time of it, as
    a plain double loop over the pairs finds them."""
    rng = np.random.default_rng(seed)
    start = rng.uniform([0.5, 0.5], [0.9, 0.9], (n, 2))
    steps = rng.uniform(-0.017, 0.017, (rows, n, 2))  # at most 0.024 m < r / 2 a row
    steps[0] = 0.0
    robots = start + np.cumsum(steps, axis=0)
    times = DT * np.arange(rows)
    scene = make_scene(robots=[tuple(p) for p in start])
    report = check_recording(scene, times, robots, np.zeros((rows, 0, 3)))
    assert report.states_checked == rows
    tol = DEFAULT_TOL["robot-robot"]
    want = []
    for i in range(n):
        for j in range(i + 1, n):
            depth = [max(2 * R - math.dist(robots[t, i], robots[t, j]), 0.0)
                     for t in range(rows)]
            over = [t for t in range(rows) if depth[t] > tol]
            if over:
                deepest = int(np.argmax(depth))
                want.append((times[over[0]], i, j, depth[deepest], times[deepest]))
    got = [(v.time_s, v.a, v.b, v.depth_m, v.worst_time_s) for v in report.violations]
    got, want = sorted(got), sorted(want)
    assert [(a, b) for _, a, b, _, _ in got] == [(a, b) for _, a, b, _, _ in want]
    assert np.allclose([[t, d, w] for t, _, _, d, w in got],
                       [[t, d, w] for t, _, _, d, w in want]) if want else got == []
    assert report.worst_depth["robot-robot"] == pytest.approx(
        max([0.0] + [max(2 * R - math.dist(robots[t, i], robots[t, j]), 0.0)
                     for t in range(rows) for i in range(n) for j in range(i + 1, n)]))
