"""The obstacles' bucket grid (lamp.mrmp.obstacle_grid): the same segment decisions and
the same point clearances, bit for bit, as measuring against every obstacle."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.clearance_kernels import points_clearance, segments_clearance
from lamp.geometry.geometry_set import GeometrySet
from lamp.mrmp.distance_field import clear_segments
from lamp.mrmp.obstacle_grid import get_grid, grid_clear_segments, grid_points_clearance
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle

W, H = 3.0, 2.0


def _geometry(rng: np.random.Generator, n: int) -> GeometrySet:
    """Circles, rotated rectangles and triangles, some reaching past the border."""
    obs = []
    for _ in range(n):
        x, y, th = rng.uniform(-0.3, W + 0.3), rng.uniform(-0.3, H + 0.3), rng.uniform(0, 6.3)
        kind = rng.integers(3)
        if kind == 0:
            obs.append(Obstacle(Circle(float(rng.uniform(0.01, 0.3))), (x, y, th)))
        elif kind == 1:
            obs.append(Obstacle(Rectangle((float(rng.uniform(0.01, 0.6)),
                                           float(rng.uniform(0.01, 0.6)))), (x, y, th)))
        else:
            pts = rng.uniform(-0.2, 0.2, (3, 2))
            obs.append(Obstacle(Polygon(tuple(map(tuple, pts.tolist()))), (x, y, th)))
    return GeometrySet(obs)


def _grid_args(g: GeometrySet) -> tuple:
    grid = get_grid(g)
    return (g.circles, g.verts, g.ptr, W, H, grid.ptr, grid.idx, grid.box, grid.nx, grid.ny,
            grid.cell)


@settings(max_examples=40)
@given(st.integers(0, 2**31 - 1), st.integers(0, 40))
def test_segment_decisions_match_all_obstacles(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    g = _geometry(rng, n)
    K = 400
    a = rng.uniform(-0.1, [W + 0.1, H + 0.1], (K, 2))
    b = a + rng.normal(0.0, 1.0, (K, 2)) * rng.choice([0.0, 0.02, 0.1, 1.0], (K, 1))
    need = rng.uniform(1e-4, 0.4, K)
    ref = segments_clearance(a, b, g.circles, g.verts, g.ptr, W, H) >= need - 1e-12
    c, v, p, *rest = _grid_args(g)
    got = grid_clear_segments(a, b, need, c, v, p, *rest)
    assert np.array_equal(ref, got)
    # the caller's way (many segments go through the grid) decides the same
    assert np.array_equal(clear_segments(g, (W, H), a, b, need), ref)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(0, 400), st.integers(1, 64))
def test_few_segments_among_many_obstacles_decide_the_same(seed: int, n: int,
                                                           k: int) -> None:
    """A few segments among hundreds of obstacles (through the grid beyond
    ``FEW_PAIRS`` segment-obstacle pairs) decide as against every obstacle."""
    rng = np.random.default_rng(seed)
    g = _geometry(rng, n)
    a = rng.uniform(-0.1, [W + 0.1, H + 0.1], (k, 2))
    b = a + rng.normal(0.0, 1.0, (k, 2)) * rng.choice([0.0, 0.02, 0.1, 1.0], (k, 1))
    need = rng.uniform(1e-4, 0.4, k)
    ref = segments_clearance(a, b, g.circles, g.verts, g.ptr, W, H) >= need - 1e-12
    assert np.array_equal(clear_segments(g, (W, H), a, b, need), ref)


@settings(max_examples=40)
@given(st.integers(0, 2**31 - 1), st.integers(0, 40))
def test_point_clearance_bit_for_bit(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    g = _geometry(rng, n)
    pts = rng.uniform(-0.2, [W + 0.2, H + 0.2], (300, 2))
    ref = points_clearance(pts, g.circles, g.verts, g.ptr, W, H)
    got = grid_points_clearance(pts, *_grid_args(g))
    assert np.array_equal(ref, got)


def test_grid_is_kept_per_geometry() -> None:
    g = _geometry(np.random.default_rng(1), 5)
    assert get_grid(g) is get_grid(g)
    assert get_grid(GeometrySet(())).idx.size == 0
