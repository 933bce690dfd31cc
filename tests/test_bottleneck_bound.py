"""``lamp.mrmp.bottleneck``: the least longest distance over the assignments of robots to
goals, straight or round the obstacles, against brute force over every assignment; and
``GrownObstacles.distance_matrix`` against its pairwise ``distance``."""

import math
from itertools import permutations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.mrmp.assignment import straight_line_bottleneck
from lamp.mrmp.bottleneck import geodesic_bottleneck, matrix_bottleneck
from lamp.scene.geodesic import GrownObstacles


def brute(S: np.ndarray, G: np.ndarray) -> float:
    """Every injective map of goals to robots."""
    return min(max(float(np.hypot(*(G[m] - S[i]))) for m, i in enumerate(p))
               for p in permutations(range(len(S)), len(G)))


coord = st.floats(-5, 5, allow_nan=False).map(lambda v: round(v, 1))  # ties happen


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_against_brute_force(data):
    n = data.draw(st.integers(1, 6), label="robots")
    m = data.draw(st.integers(1, n), label="goals")
    S = np.array(data.draw(st.lists(st.tuples(coord, coord), min_size=n, max_size=n)))
    G = np.array(data.draw(st.lists(st.tuples(coord, coord), min_size=m, max_size=m)))
    assert straight_line_bottleneck(S, G) == pytest.approx(brute(S, G), abs=1e-12)


def test_edges():
    assert straight_line_bottleneck(np.zeros((3, 2)), np.zeros((0, 2))) == 0.0
    S = np.array([[0.0, 0.0], [10.0, 0.0]])
    # both goals are nearest the robot at 10; the other robot must cover 9 (not 11)
    assert straight_line_bottleneck(S, np.array([[9.0, 0.0], [11.0, 0.0]])) == 9.0
    with pytest.raises(ValueError):
        straight_line_bottleneck(S[:1], S)


def brute_matrix(C: np.ndarray) -> float:
    """Every injective map of rows (goals) to columns (robots)."""
    M, N = C.shape
    return min(max(C[m, i] for m, i in enumerate(p)) for p in permutations(range(N), M))


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_matrix_against_brute_force_with_unreachable_pairs(data):
    n = data.draw(st.integers(1, 6), label="robots")
    m = data.draw(st.integers(1, n), label="goals")
    cost = st.one_of(st.just(math.inf), st.integers(0, 9).map(float))  # ties and gaps
    C = np.array(data.draw(st.lists(st.lists(cost, min_size=n, max_size=n),
                                    min_size=m, max_size=m)))
    assert matrix_bottleneck(C) == brute_matrix(C)


W, H = 4.0, 3.0
box = st.tuples(st.floats(0.3, 3.4), st.floats(0.3, 2.4), st.floats(0.1, 1.2),
                st.floats(0.1, 0.6))
point = st.tuples(st.floats(0.1, 3.9), st.floats(0.1, 2.9))


def _free(geoms, rho, pts):
    """The points where the disk fits (clear of the grown boxes, inside the room)."""
    grown = shapely.union_all([g.buffer(rho) for g in geoms])
    room = shapely.box(rho, rho, W - rho, H - rho)
    return np.array([p for p in pts if room.covers(shapely.Point(p))
                     and not grown.intersects(shapely.Point(p))]).reshape(-1, 2)


@settings(max_examples=40, deadline=None)
@given(st.lists(box, min_size=1, max_size=4), st.floats(0.0, 0.1),
       st.lists(point, min_size=2, max_size=12), st.floats(0.3, 6.0))
def test_distance_matrix_is_each_pair_s_distance(boxes, rho, pts, below):
    """Below ``below`` each entry is the pair's own ``distance``; at or above it, between
    ``below`` (or the straight line) and that distance."""
    geoms = [shapely.box(x, y, x + w, y + h) for x, y, w, h in boxes]
    g = GrownObstacles(geoms, rho, (W, H), merge=True)
    P = _free(geoms, rho, pts)
    if len(P) < 2:
        return
    A, B = P[: len(P) // 2], P[len(P) // 2:]
    for cap in (below, math.inf):
        D = g.distance_matrix(A, B, below=cap)
        for i, a in enumerate(A):
            for j, b in enumerate(B):
                true = g.distance(a, b)
                if true < cap:
                    assert D[i, j] == pytest.approx(true, rel=1e-9, abs=1e-9)
                else:
                    assert min(cap, true) - 1e-9 <= D[i, j] <= true + 1e-9


@settings(max_examples=40, deadline=None)
@given(st.lists(box, min_size=1, max_size=4), st.floats(0.0, 0.1),
       st.lists(point, min_size=2, max_size=10), st.data())
def test_geodesic_bottleneck_against_brute_force(boxes, rho, pts, data):
    """The brute force over every assignment of the pairs' ``distance``; never below the
    straight-line bottleneck."""
    geoms = [shapely.box(x, y, x + w, y + h) for x, y, w, h in boxes]
    g = GrownObstacles(geoms, rho, (W, H), merge=True)
    P = _free(geoms, rho, pts)
    if len(P) < 2:
        return
    m = data.draw(st.integers(1, len(P) // 2), label="goals")
    S, G = P[m:], P[:m]
    C = np.array([[g.distance(s, q) for s in S] for q in G])
    got = geodesic_bottleneck(g, S, G)
    assert got == pytest.approx(brute_matrix(C), rel=1e-9, abs=1e-9)
    assert got >= straight_line_bottleneck(S, G) - 1e-12


def test_geodesic_bottleneck_round_a_wall():
    """Two robots west of a wall, two goals east of it: both must go round the wall's end,
    so the bound is the better of the two assignments' longer way round, far above the
    straight lines'; with no wall the two bounds agree."""
    wall = shapely.box(1.9, 0.0, 2.1, 2.5)
    S = np.array([[1.0, 0.5], [1.0, 1.0]])
    G = np.array([[3.0, 0.5], [3.0, 1.0]])
    g = GrownObstacles([wall], 0.05, (W, H), merge=True)
    straight = straight_line_bottleneck(S, G)
    got = geodesic_bottleneck(g, S, G)
    assert straight == pytest.approx(2.0)
    d = [[g.distance(s, q) for q in G] for s in S]
    assert got == pytest.approx(min(max(d[0][0], d[1][1]), max(d[0][1], d[1][0])))
    assert got > 1.8 * straight
    assert geodesic_bottleneck(GrownObstacles([], 0.05, (W, H)), S, G) == pytest.approx(straight)


def test_distance_matrix_goes_round_in_many_rooms():
    """Thirty random rooms of five boxes: the matrix agrees with ``distance`` pair by pair,
    and the check is not empty: many pairs go round an obstacle, some beyond the cap."""
    rng = np.random.default_rng(11)
    detours = capped = 0
    for _ in range(30):
        geoms = [shapely.box(x, y, x + w, y + h) for x, y, w, h in
                 rng.uniform([0.3, 0.3, 0.1, 0.1], [3.4, 2.4, 1.2, 0.8], (5, 4))]
        g = GrownObstacles(geoms, 0.05, (W, H), merge=True)
        P = _free(geoms, 0.05, rng.uniform([0.1, 0.1], [3.9, 2.9], (16, 2)))
        A, B = P[: len(P) // 2], P[len(P) // 2:]
        D = g.distance_matrix(A, B, below=2.5)
        for i, a in enumerate(A):
            for j, b in enumerate(B):
                true = g.distance(a, b)
                if true < 2.5:
                    assert D[i, j] == pytest.approx(true, rel=1e-9, abs=1e-9)
                    detours += true > math.dist(a, b) + 1e-3
                else:
                    capped += 1
                    assert max(2.5, math.dist(a, b)) - 1e-9 <= D[i, j] <= true + 1e-9
    assert detours >= 20 and capped >= 20, (detours, capped)
