"""The landmark potential (``lamp.search.landmark``): conservative passability, its
Lipschitz bound along every lattice edge, its distances against a plain Dijkstra, and the
lattice heuristic it strengthens (a lower bound that prunes the search, same path costs)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.shapes import obstacle_geometry
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle
from lamp.search.dstar_lite import DStarLite
from lamp.search.landmark import inscribed_radius, route_length, route_path
from lamp.search.lattice import ObjectLattice

SHAPES = (
    Rectangle((0.16, 0.08)),
    Circle(0.06),
    Polygon(((-0.08, -0.05), (0.1, -0.04), (0.02, 0.09))),
)


def random_lattice(seed: int, landmark: bool = True) -> ObjectLattice:
    rng = np.random.default_rng(seed)
    obstacles = []
    for _ in range(int(rng.integers(0, 5))):
        pose = (*rng.uniform(0, 1.0, 2), float(rng.uniform(-math.pi, math.pi)))
        if rng.random() < 0.5:
            obstacles.append(Obstacle(Circle(float(rng.uniform(0.03, 0.12))), pose))
        else:
            obstacles.append(Obstacle(Rectangle(tuple(rng.uniform(0.03, 0.4, 2))), pose))
    shape = SHAPES[int(rng.integers(len(SHAPES)))]
    space = ObjectSpace(shape, (1.0, 0.8), obstacles, float(rng.choice([0.0, 0.02])))
    anchor = (*rng.uniform(0.1, 0.7, 2), float(rng.uniform(-math.pi, math.pi)))
    mark = rng.uniform([0.0, 0.0], [1.0, 0.8]) if landmark else None
    return ObjectLattice(space, anchor, step=0.1, n_headings=8, max_rotation=0.8, landmark=mark)


def test_inscribed_radius():
    assert inscribed_radius(ObjectSpace(Rectangle((0.4, 0.3)), (1, 1))) == pytest.approx(0.15, abs=1e-5)
    assert inscribed_radius(ObjectSpace(Rectangle((0.4, 0.3)), (1, 1), [], 0.05)) == (
        pytest.approx(0.2, abs=1e-5))
    assert inscribed_radius(ObjectSpace(Circle(0.1), (1, 1))) == pytest.approx(0.1, rel=1e-3)
    assert inscribed_radius(ObjectSpace(Circle(0.1), (1, 1))) <= 0.1
    off = Polygon(((0.2, 0.2), (0.3, 0.2), (0.3, 0.3)))  # the origin is outside
    assert inscribed_radius(ObjectSpace(off, (1, 1))) == 0.0


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_valid_nodes_are_passable_and_potential_is_lipschitz_on_edges(seed):
    lat = random_lattice(seed)
    pot = lat.potential
    valid = np.nonzero(lat.validate_all_nodes())[0]
    cells = valid // lat.n_headings
    assert np.all(pot.passable.reshape(-1)[cells])
    for u in valid:
        for v, _ in lat.successors(int(u)):
            (i, j, _), (i2, j2, _) = lat.ijk(int(u)), lat.ijk(v)
            step_cost = lat.step * math.hypot(i2 - i, j2 - j)
            du = pot.values[int(u) // lat.n_headings]
            dv = pot.values[v // lat.n_headings]
            assert abs(du - dv) <= step_cost + 1e-9


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_potential_is_the_grid_distance_from_the_landmark(seed):
    """Against scipy's Dijkstra on the 8-connected passable grid, seeded like the
    potential (octile distance from the landmark to the passable cells around it)."""
    lat = random_lattice(seed)
    pot = lat.potential
    n_i, n_j = pot.shape
    ok = pot.passable.reshape(-1)
    rows, cols, vals = [], [], []
    for i in range(n_i):
        for j in range(n_j):
            for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
                i2, j2 = i + di, j + dj
                if 0 <= i2 < n_i and 0 <= j2 < n_j and ok[i * n_j + j] and ok[i2 * n_j + j2]:
                    rows.append(i * n_j + j)
                    cols.append(i2 * n_j + j2)
                    vals.append(lat.step * math.hypot(di, dj))
    n = n_i * n_j + 1  # + one source joined to the seed cells
    src = n - 1
    for c, o in pot._near(*lat.landmark, max(pot.radius, lat.step * math.sqrt(2))):
        rows.append(src)
        cols.append(c)
        vals.append(o + 1.0)  # shifted by 1 so that a zero seed cost stays an edge
    mat = csr_matrix((vals, (rows, cols)), shape=(n, n))
    ref = dijkstra(mat, directed=False, indices=src)[:-1] - 1.0
    reach = np.isfinite(ref) & ok
    np.testing.assert_allclose(pot.values[reach], ref[reach], atol=1e-9)
    assert np.all(pot.values[~reach] == pot.unreachable)
    if reach.any():
        assert pot.unreachable > pot.values[reach].max()


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), x=st.floats(0.0, 1.0), y=st.floats(0.0, 0.8))
def test_off_grid_positions_stay_within_the_octile_bound_of_their_neighbours(seed, x, y):
    lat = random_lattice(seed)
    pot = lat.potential
    cells = pot._near(x, y, pot.radius)
    d = pot.at(x, y)
    hi = max((pot.values[c] - o for c, o in cells), default=-math.inf)
    lo = min((pot.values[c] + o for c, o in cells), default=math.inf)
    if hi <= lo:
        for c, o in cells:
            assert abs(d - pot.values[c]) <= o + 1e-9
    # on a grid position: exactly the grid value
    i, j = min(int(x / 0.1), pot.shape[0] - 1), min(int(y / 0.1), pot.shape[1] - 1)
    gx, gy = pot.origin[0] + i * pot.step, pot.origin[1] + j * pot.step
    assert pot.at(gx, gy) == pot.values[i * pot.shape[1] + j]


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_landmark_heuristic_is_admissible_and_consistent(seed):
    """Plain Dijkstra from a few nodes: the strengthened heuristic never exceeds the
    cheapest lattice path cost, is consistent on every edge, and is at least the octile
    metric alone."""
    lat = random_lattice(seed)
    plain = random_lattice(seed, landmark=False)
    valid = np.nonzero(lat.validate_all_nodes())[0]
    if len(valid) == 0:
        return
    rows, cols, vals = [], [], []
    for u in valid:
        for v, c in lat.successors(int(u)):
            rows.append(int(u))
            cols.append(v)
            vals.append(c)
    mat = csr_matrix((vals, (rows, cols)), shape=(lat.n_nodes, lat.n_nodes))
    rng = np.random.default_rng(seed)
    targets = rng.choice(valid, size=min(3, len(valid)), replace=False)
    dist = dijkstra(mat, indices=targets)
    for row, t in enumerate(targets):
        t = int(t)
        reach = valid[np.isfinite(dist[row, valid])]
        for u in reach:
            h = lat.heuristic(int(u), t)
            assert h <= dist[row, u] + 1e-9
            assert h >= plain.heuristic(int(u), t) - 1e-12
            for v, c in lat.successors(int(u)):
                assert h <= c + lat.heuristic(v, t) + 1e-9


def test_landmark_prunes_the_search_with_the_same_path_cost():
    """A wall with a gap between start and goal: the octile metric alone sends the search
    into the dead end in front of the wall; the potential sees the detour."""
    wall = Obstacle(Rectangle((0.1, 1.6)), (1.0, 0.7, 0.0))
    space = ObjectSpace(Rectangle((0.16, 0.08)), (2.0, 2.0), [wall])
    goal, start = (1.7, 0.8, 0.0), (0.3, 0.8, 0.0)
    results = []
    for landmark in (None, start[:2]):
        lat = ObjectLattice(space, goal, landmark=landmark)
        d = DStarLite(lat)
        d.initialize(lat.goal_node)
        node = lat.nearest_nodes(start, 1e-6)[0][0]
        assert d.plan_shortest_path(node)
        results.append((d.path_cost(), d.stats.last_expansions))
    (c_plain, n_plain), (c_mark, n_mark) = results
    assert c_mark == pytest.approx(c_plain, rel=1e-12)
    assert n_mark < 0.5 * n_plain


def test_bad_landmark():
    space = ObjectSpace(Circle(0.1), (1.0, 1.0))
    with pytest.raises(ValueError, match="landmark"):
        ObjectLattice(space, (0.5, 0.5, 0.0), landmark=(math.nan, 0.2))


def _octile(a, b) -> float:
    dx, dy = abs(b[0] - a[0]), abs(b[1] - a[1])
    return max(dx, dy) + (math.sqrt(2.0) - 1.0) * min(dx, dy)


@settings(max_examples=25, deadline=None)
@given(sx=st.floats(0.2, 3.8), sy=st.floats(0.2, 1.8), gx=st.floats(0.2, 3.8),
       gy=st.floats(0.2, 1.8))
def test_route_length_on_an_open_map_is_the_octile_distance(sx, sy, gx, gy):
    space = ObjectSpace(Circle(0.1), (4.0, 2.0))
    got = route_length(space, (sx, sy), (gx, gy), 0.1)
    assert got is not None
    assert abs(got - _octile((sx, sy), (gx, gy))) <= 0.1 + 1e-9
    assert got >= math.hypot(gx - sx, gy - sy) - 0.1


WALL = Obstacle(Rectangle((0.1, 1.6)), (2.0, 0.8, 0.0))  # x 1.95-2.05, y 0-1.6


def test_route_length_goes_round_a_wall():
    space = ObjectSpace(Circle(0.1), (4.0, 2.0), [WALL])
    got = route_length(space, (1.0, 0.5), (3.0, 0.5), 0.1)
    # the centre crosses x = 2 above the wall: at least the two straight legs to (2, 1.6)
    detour = 2 * math.hypot(1.0, 1.1)
    assert got is not None and detour - 0.1 <= got <= detour * 1.09 + 0.3
    # the same wall, from start to a goal on its own side: the open-map distance
    assert route_length(space, (1.0, 0.5), (1.0, 1.5), 0.1) == pytest.approx(1.0, abs=0.1)


def test_route_length_is_none_when_a_wall_cuts_the_map():
    cut = Obstacle(Rectangle((0.1, 2.0)), (2.0, 1.0, 0.0))
    space = ObjectSpace(Circle(0.1), (4.0, 2.0), [cut])
    assert route_length(space, (1.0, 0.5), (3.0, 0.5), 0.1) is None
    # a gap narrower than the object's inscribed disk does not let it through either
    gap = [Obstacle(Rectangle((0.1, 0.95)), (2.0, 0.475, 0.0)),
           Obstacle(Rectangle((0.1, 0.95)), (2.0, 1.525, 0.0))]  # a 0.1 m slit at y = 1
    assert route_length(ObjectSpace(Circle(0.1), (4.0, 2.0), gap), (1.0, 0.5), (3.0, 0.5),
                        0.1) is None


@settings(max_examples=25, deadline=None)
@given(sx=st.floats(0.2, 3.8), sy=st.floats(0.2, 1.8), gx=st.floats(0.2, 3.8),
       gy=st.floats(0.2, 1.8), wall=st.booleans())
def test_route_path_joins_start_to_goal_by_passable_neighbours_at_the_route_length(
        sx, sy, gx, gy, wall):
    space = ObjectSpace(Circle(0.1), (4.0, 2.0), [WALL] if wall else [])
    if not (space.pose_free((sx, sy, 0.0)) and space.pose_free((gx, gy, 0.0))):
        return
    path = route_path(space, (sx, sy), (gx, gy), 0.1)
    length = route_length(space, (sx, sy), (gx, gy), 0.1)
    assert (path is None) == (length is None)
    assert path is not None  # the wall leaves a way round it
    assert np.allclose(path[0], (sx, sy)) and np.allclose(path[-1], (gx, gy))
    inner = path[1:-1]
    steps = np.abs(np.diff(inner, axis=0))
    assert np.all(steps <= 0.1 + 1e-9) and np.all(steps.max(axis=1) >= 0.1 - 1e-9)
    walls = [obstacle_geometry(WALL)] if wall else []
    for x, y in inner:  # the disk passes there (touching at most)
        assert 0.1 - 1e-6 <= x <= 3.9 + 1e-6 and 0.1 - 1e-6 <= y <= 1.9 + 1e-6
        assert all(w.distance(shapely.Point(x, y)) >= 0.1 - 1e-6 for w in walls)
    total = float(np.sum(np.hypot(*np.diff(path, axis=0).T)))
    assert abs(total - length) <= 0.2 + 1e-9 + 0.1 * (math.sqrt(2) - 1) * 2


def test_route_path_goes_round_a_wall_and_is_none_across_a_cut():
    space = ObjectSpace(Circle(0.1), (4.0, 2.0), [WALL])
    path = route_path(space, (1.0, 0.5), (3.0, 0.5), 0.1)
    crossing = path[np.argmin(np.abs(path[:, 0] - 2.0))]
    assert crossing[1] >= 1.6 + 0.1 - 1e-9  # above the wall's end by the disk's radius
    cut = Obstacle(Rectangle((0.1, 2.0)), (2.0, 1.0, 0.0))
    assert route_path(ObjectSpace(Circle(0.1), (4.0, 2.0), [cut]), (1.0, 0.5), (3.0, 0.5),
                      0.1) is None


@settings(max_examples=25, deadline=None)
@given(sx=st.floats(0.25, 1.7), sy=st.floats(0.25, 1.75), gx=st.floats(2.3, 3.75),
       gy=st.floats(0.25, 1.75))
def test_route_length_is_none_for_any_goal_beyond_a_wall_off_the_grid_too(sx, sy, gx, gy):
    """A goal off the grid beside a wall is valued by the positions on its own side only."""
    cut = Obstacle(Rectangle((0.1, 2.0)), (2.0, 1.0, 0.0))
    space = ObjectSpace(Circle(0.2), (4.0, 2.0), [cut])
    assert route_length(space, (sx, sy), (gx, gy), 0.1) is None
    assert route_path(space, (sx, sy), (gx, gy), 0.1) is None
    back = route_length(space, (gx, gy), (3.8 - (gx - 2.3), sy), 0.1)
    assert back is not None  # the same side: a route
