"""RobotSpace against Shapely (the reference) on random obstacle sets."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.robot_space import RobotSpace, clear_caches, obstacle_from_dict
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle, Scene, SceneObject

W, H = 2.0, 1.5
R = 0.05
BAND = 0.01 * math.sqrt(2) / 2  # documented band of the conservative grid test


def _random_obstacles(rng: np.random.Generator, k: int) -> list[Obstacle]:
    obs: list[Obstacle] = []
    for _ in range(k):
        kind = rng.integers(3)
        x, y = rng.uniform(0.1, W - 0.1), rng.uniform(0.1, H - 0.1)
        if kind == 0:
            obs.append(Obstacle(Circle(float(rng.uniform(0.02, 0.3))), (x, y, 0.0)))
        elif kind == 1:
            size = (float(rng.uniform(0.02, 0.6)), float(rng.uniform(0.02, 0.6)))
            obs.append(Obstacle(Rectangle(size), (x, y, float(rng.uniform(-3, 3)))))
        else:
            # a random star-shaped (simple, possibly non-convex) polygon
            n = int(rng.integers(3, 8))
            ang = np.sort(rng.uniform(0, 2 * np.pi, n))
            rad = rng.uniform(0.03, 0.3, n)
            pts = tuple((float(x + rr * np.cos(a)), float(y + rr * np.sin(a)))
                        for a, rr in zip(ang, rad, strict=True))
            if shapely.Polygon(pts).is_valid and shapely.Polygon(pts).area > 1e-4:
                obs.append(Obstacle(Polygon(pts)))
    return obs


def _reference(obs: list[Obstacle]):
    """Exact reference distances with Shapely: circles as centre + radius."""
    polys = []
    circles = []
    for o in obs:
        d = o.to_dict()
        if d["type"] == "circle":
            circles.append((*d["center"], d["radius"]))
        elif d["type"] == "rectangle":
            cx, cy = d["center"]
            sx, sy = d["size"]
            c, s = math.cos(d["angle"]), math.sin(d["angle"])
            loc = np.array([[-sx, -sy], [sx, -sy], [sx, sy], [-sx, sy]]) / 2
            polys.append(shapely.Polygon(np.c_[cx + c * loc[:, 0] - s * loc[:, 1],
                                               cy + s * loc[:, 0] + c * loc[:, 1]]))
        else:
            polys.append(shapely.Polygon(d["points"]))

    def point_clr(p: np.ndarray) -> np.ndarray:
        out = np.minimum.reduce([p[:, 0], W - p[:, 0], p[:, 1], H - p[:, 1]])
        for cx, cy, rad in circles:
            out = np.minimum(out, np.hypot(p[:, 0] - cx, p[:, 1] - cy) - rad)
        pts = shapely.points(p)
        for g in polys:
            dd = shapely.distance(pts, g)
            out = np.minimum(out, np.where(shapely.contains(g, pts), -shapely.distance(
                pts, g.exterior), dd))
        return out

    def seg_clr(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        out = np.minimum.reduce([a[:, 0], W - a[:, 0], a[:, 1], H - a[:, 1],
                                 b[:, 0], W - b[:, 0], b[:, 1], H - b[:, 1]])
        lines = shapely.linestrings(np.stack([a, b], 1))
        for cx, cy, rad in circles:
            out = np.minimum(out, shapely.distance(lines, shapely.Point(cx, cy)) - rad)
        for g in polys:
            out = np.minimum(out, shapely.distance(lines, g))
        return out

    return point_clr, seg_clr


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), k=st.integers(0, 12))
def test_point_queries_match_shapely(seed: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    obs = _random_obstacles(rng, k)
    space = RobotSpace((W, H), obs, radius=R)
    point_clr, _ = _reference(obs)
    # random points plus points right at the free threshold (hardest for the grid)
    p = rng.uniform(0, [W, H], (400, 2))
    ref = point_clr(p)
    exact = space.clearance(p, exact=True)
    # exact clearance equals the reference wherever the robot could be (>= 0)
    pos = ref >= 0
    assert np.allclose(exact[pos], ref[pos], atol=1e-9)
    assert np.all((exact < 0) == (ref < 0) | (np.abs(ref) < 1e-9))
    free = space.is_free(p)
    # conservative: never free when the reference says colliding
    assert not np.any(free & (ref < R - 1e-12))
    # and only refuses points within the documented band above the threshold
    assert not np.any(~free & (ref >= R + BAND + 1e-9))
    assert np.array_equal(space.is_free(p, exact=True), ref >= R - 1e-12) or np.all(
        np.abs(ref[space.is_free(p, exact=True) != (ref >= R)] - R) < 1e-9)
    # lower bound holds; bilinear estimate is within a cell's reach of the truth
    lb = space.clearance_lower(p)
    capped = np.minimum(ref, space.cap)
    assert np.all(lb <= capped + 1e-9)
    inside = (p[:, 0] <= 1.99) & (p[:, 1] <= 1.49)
    assert np.all(np.abs(space.clearance(p)[inside] - capped[inside]) <= 0.0072)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), k=st.integers(1, 10))
def test_segment_clearance_matches_shapely(seed: int, k: int) -> None:
    rng = np.random.default_rng(seed)
    obs = _random_obstacles(rng, k)
    space = RobotSpace((W, H), obs, radius=R)
    _, seg_clr = _reference(obs)
    a = rng.uniform(0, [W, H], (300, 2))
    b = a + rng.normal(0, 0.15, (300, 2))
    b = np.clip(b, 0, [W, H])
    ref = seg_clr(a, b)
    got = space.segment_clearance(a, b)
    pos = ref > 1e-9
    assert np.allclose(got[pos], ref[pos], atol=1e-9)
    assert np.all(got[~pos] <= 1e-9)
    assert np.array_equal(space.segment_free(a, b), got >= R)


def test_nearest_free_is_free_close_and_avoids() -> None:
    rng = np.random.default_rng(3)
    obs = _random_obstacles(rng, 8)
    space = RobotSpace((W, H), obs, radius=R)
    point_clr, _ = _reference(obs)
    ny, nx = space.shape
    jj, ii = np.mgrid[0:ny, 0:nx]
    nodes = np.stack([ii * space.resolution, jj * space.resolution], -1).reshape(-1, 2)
    ok_nodes = space.field.reshape(-1) >= R
    for q in rng.uniform(0, [W, H], (20, 2)):
        avoid = np.array([[q[0], q[1], 0.12]])
        spot = space.nearest_free(q, avoid=avoid, through_free=False)
        assert spot is not None
        assert point_clr(spot[None])[0] >= R - 1e-12
        assert np.hypot(*(spot - q)) > 0.12
        # searching through every node: the result is the Euclidean-closest valid node
        d_all = np.hypot(*(nodes - q).T)
        valid = ok_nodes & (d_all > 0.12)
        assert np.hypot(*(spot - q)) <= d_all[valid].min() + 1e-9
    # a predicate (as LAMP's "clear of the push paths") is honoured, nearest again
    for q in rng.uniform(0, [W, H], (10, 2)):
        calls: list[int] = []

        def right_of(pts: np.ndarray, q=q, calls=calls) -> np.ndarray:
            calls.append(len(pts))
            return pts[:, 0] >= q[0] + 0.3

        spot = space.nearest_free(q, accept=right_of, through_free=False)
        d_all = np.hypot(*(nodes - q).T)
        valid = ok_nodes & (nodes[:, 0] >= q[0] + 0.3)
        if not valid.any():
            assert spot is None
            continue
        assert spot is not None and spot[0] >= q[0] + 0.3
        assert np.hypot(*(spot - q)) <= d_all[valid].min() + 1e-9
        assert sum(calls) <= ok_nodes.sum()  # each node judged at most once
    # an unreachable pocket: no spot when searching from inside a sealed box
    box = [Obstacle(Rectangle((0.6, 0.02)), (1.0, 0.45, 0.0)),
           Obstacle(Rectangle((0.6, 0.02)), (1.0, 1.05, 0.0)),
           Obstacle(Rectangle((0.02, 0.62)), (0.7, 0.75, 0.0)),
           Obstacle(Rectangle((0.02, 0.62)), (1.3, 0.75, 0.0))]
    sealed = RobotSpace((W, H), box, radius=R)
    spot = sealed.nearest_free([1.0, 0.75], avoid=[[1.0, 0.75, 0.5]])
    assert spot is None
    spot = sealed.nearest_free([1.0, 0.75], avoid=[[1.0, 0.75, 0.5]], through_free=False)
    assert spot is not None and not (0.7 < spot[0] < 1.3 and 0.45 < spot[1] < 1.05)


def test_from_scene_objects_extras_cache_and_exclusion() -> None:
    clear_caches()
    obj = SceneObject(Rectangle((0.4, 0.3)), (1.0, 0.7, 0.0), (1.5, 0.7, 0.0))
    scene = Scene("s", (W, H), ((0.2, 0.2),), (obj,), (Obstacle(Circle(0.1), (0.4, 1.2, 0.0)),))
    a = RobotSpace.from_scene(scene)
    assert RobotSpace.from_scene(scene) is a
    assert not a.is_free([[1.0, 0.7]])[0]
    b = RobotSpace.from_scene(scene, object_poses=[[1.5, 0.7, 0.3]])
    assert b is not a and b.is_free([[1.0, 0.7]])[0] and not b.is_free([[1.5, 0.7]])[0]
    c = RobotSpace.from_scene(scene, exclude_objects=[0])
    assert c.is_free([[1.0, 0.7]])[0]
    e = RobotSpace.from_scene(scene, extra_obstacles=[{"type": "circle", "center": [1.7, 0.3],
                                                       "radius": 0.1}])
    assert not e.is_free([[1.7, 0.3]])[0] and a.is_free([[1.7, 0.3]])[0]
    m = RobotSpace.from_scene(scene, margin=0.05)
    assert m.threshold == pytest.approx(0.1)
    assert a.clearance([[0.4, 1.2 + 0.1 + 0.08]], exact=True)[0] == pytest.approx(0.08)
    assert not m.is_free([[0.4, 1.2 + 0.1 + 0.08]])[0] and a.is_free([[0.4, 1.38]])[0]


def test_invalid_arguments() -> None:
    scene = Scene("s", (W, H), ((0.2, 0.2),), (), ())
    with pytest.raises(ValueError, match="object_poses"):
        RobotSpace.from_scene(scene, object_poses=[[0, 0, 0]])
    with pytest.raises(ValueError, match="unknown type"):
        obstacle_from_dict({"type": "hexagon"})
    with pytest.raises(ValueError, match="radius"):
        RobotSpace((W, H), (), radius=-1.0)
    with pytest.raises(ValueError, match="points"):
        RobotSpace((W, H), ()).is_free(np.zeros((3, 3)))


def test_path_free_and_border() -> None:
    space = RobotSpace((W, H), [Obstacle(Circle(0.2), (1.0, 0.75, 0.0))], radius=R)
    assert space.path_free([[0.3, 0.3], [1.7, 0.3], [1.7, 1.2]])
    assert not space.path_free([[0.3, 0.75], [1.7, 0.75]])
    assert not space.path_free([[0.3, 0.3], [0.3, 0.04]])  # border
    # grazing the circle at exactly the threshold is allowed (exact check)
    y = 0.75 + 0.2 + R + 1e-12
    assert space.path_free([[0.5, y], [1.5, y]])
    assert not space.path_free([[0.5, y - 1e-6], [1.5, y - 1e-6]])


def _wall(gap: float) -> list[Obstacle]:
    """A wall across the map at x = 1 with an opening of ``gap`` m at its top."""
    h = H - gap
    return [Obstacle(Rectangle((0.1, h)), (1.0, h / 2, 0.0))]


def test_components_tell_the_two_sides_of_a_wall_apart():
    closed = RobotSpace((W, H), _wall(0.0), radius=R)
    left, right = np.array([[0.5, 0.7], [0.2, 0.2]]), np.array([[1.5, 0.7], [1.9, 1.4]])
    a, b = closed.components(left), closed.components(right)
    assert a[0] == a[1] != 0 and b[0] == b[1] != 0 and a[0] != b[0]
    assert closed.components(np.array([1.0, 0.7])) == 0  # inside the wall
    assert closed.components(np.array([[5.0, 0.5]]))[0] == 0  # off the map
    # a robot touching the wall (its centre R from it) takes the side it stands on
    assert closed.components(np.array([1.05 + R, 0.7])) == b[0]
    wide = RobotSpace((W, H), _wall(2 * R + 0.03), radius=R)  # a robot fits through
    assert len(set(wide.components(np.concatenate([left, right])).tolist())) == 1
    narrow = RobotSpace((W, H), _wall(2 * R - 0.02), radius=R)  # it does not
    assert len(set(narrow.components(np.concatenate([left, right])).tolist())) == 2


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000))
def test_components_agree_with_a_flood_fill(seed):
    """Reference: a breadth-first flood fill over the 8-connected free grid nodes."""
    rng = np.random.default_rng(seed)
    space = RobotSpace((W, H), _random_obstacles(rng, 6), radius=R, resolution=0.02)
    free = space.free_grid
    pts = rng.integers([0, 0], [int(W / 0.02) + 1, int(H / 0.02) + 1], size=(12, 2)) * 0.02
    ids = space.components(pts, snap=0.0)  # points on nodes: exactly their node's region
    nodes = [(int(round(y / 0.02)), int(round(x / 0.02))) for x, y in pts]
    for k, (j, i) in enumerate(nodes):
        assert (ids[k] != 0) == bool(free[j, i])
    seen = -np.ones(free.shape, dtype=int)
    for k, (j, i) in enumerate(nodes):
        if not free[j, i] or seen[j, i] >= 0:
            continue
        stack = [(j, i)]
        seen[j, i] = k
        while stack:
            y, x = stack.pop()
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    v, u = y + dy, x + dx
                    if (0 <= v < free.shape[0] and 0 <= u < free.shape[1] and free[v, u]
                            and seen[v, u] < 0):
                        seen[v, u] = k
                        stack.append((v, u))
    for a in range(len(pts)):
        for b in range(len(pts)):
            if ids[a] and ids[b]:
                same = seen[nodes[a]] == seen[nodes[b]]
                assert (ids[a] == ids[b]) == same


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), k=st.integers(0, 25),
       reach=st.floats(0.01, 0.4))
def test_obstacles_near_a_box_decide_every_segment_in_it(seed: int, k: int,
                                                          reach: float) -> None:
    """``GeometrySet.near``: for segments inside the box and thresholds up to ``reach``,
    the kept obstacles give the same ``segment_clearance >= t`` answers as all of them,
    and they are the obstacles whose bounding box comes within ``reach`` of the box."""
    from lamp.geometry.clearance_kernels import segment_clearance
    from lamp.geometry.geometry_set import GeometrySet
    from lamp.geometry.shapes import obstacle_geometry

    rng = np.random.default_rng(seed)
    obs = _random_obstacles(rng, k)
    full = GeometrySet(obs)
    x0, y0 = rng.uniform(0, [W - 0.2, H - 0.2])
    box = (x0, y0, x0 + rng.uniform(0.05, W - x0), y0 + rng.uniform(0.05, H - y0))
    sub = full.near(box, reach)
    grown = shapely.box(*box).buffer(reach, join_style="mitre")
    assert len(sub.circles) + sub.n_polygons == sum(
        shapely.box(*obstacle_geometry(o).bounds).intersects(grown) for o in obs)
    a = rng.uniform(box[:2], box[2:], (200, 2))
    b = rng.uniform(box[:2], box[2:], (200, 2))
    t = rng.uniform(1e-6, reach, 200)
    for p, q, tk in zip(a, b, t, strict=True):
        args = (W, H)
        want = segment_clearance(*p, *q, full.circles, full.verts, full.ptr, *args) >= tk
        assert (segment_clearance(*p, *q, sub.circles, sub.verts, sub.ptr, *args) >= tk) == want


def test_a_windowed_lattice_has_the_edges_it_had_with_every_obstacle() -> None:
    """``Lattice`` decides its grazing edges with the obstacles near its window only
    (``GeometrySet.near``): on a grid map (a Moving AI-like 20% of 0.25 m cells blocked,
    whose sides lattice edges graze by the hundred), window by window, the same edges as
    with every obstacle; and with none, not the same (the check is sensitive)."""
    from lamp.geometry.geometry_set import GeometrySet
    from lamp.mrmp import distance_field as DF
    from lamp.scene.mapf import _rectangles

    blocked = np.random.default_rng(3).random((24, 24)) < 0.2
    obs = [Obstacle(Rectangle((cols * 0.25, rows * 0.25)),
                    ((c0 + cols / 2) * 0.25, (24 - r0 - rows / 2) * 0.25, 0.0))
           for r0, c0, rows, cols in _rectangles(blocked)]
    near = GeometrySet.near
    for window in ((0.5, 0.5, 2.0, 2.5), (3.0, 1.0, 5.5, 4.0), None):
        space = RobotSpace((6.0, 6.0), obs, radius=R, window=window)
        lat = DF.Lattice(space, 0.05)
        refs = []
        for pick in (lambda self, box, reach: self, lambda self, box, reach: GeometrySet(())):
            try:
                GeometrySet.near = pick  # every obstacle / none
                refs.append(DF.Lattice(space, 0.05))
            finally:
                GeometrySet.near = near
        assert lat.V == refs[0].V and np.array_equal(lat.nbr, refs[0].nbr)
        assert not np.array_equal(lat.nbr, refs[1].nbr)
        if window is not None:
            assert space.geometry.near(lat.window, space.threshold).n_polygons < len(obs)
