"""``lamp.scene.geodesic``: shortest paths of a disk among obstacles, never longer than a
path the disk can take, at least the straight line, and exact where it can be worked out
by hand."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.scene.geodesic import GrownObstacles

W, H = 4.0, 3.0


def _feasible_grid_path(boxes: list[shapely.Geometry], rho: float, a, b, h: float = 0.05
                        ) -> float:
    """The length of a path the disk can take (or inf): Dijkstra from ``a`` over the
    centres of an ``h`` grid to ``b``, each step a segment checked clear of the exact grown
    obstacles (Shapely buffers with 64 segments per quarter, grown a further 1e-6 so a
    step never grazes) and inside the workspace shrunk by ``rho``. No lamp code."""
    grown = shapely.union_all([g.buffer(rho + 1e-6, quad_segs=64) for g in boxes])
    room = shapely.box(rho, rho, W - rho, H - rho)
    shapely.prepare(grown)

    def ok(p, q) -> bool:
        seg = shapely.LineString([p, q])
        return room.covers(seg) and not grown.intersects(seg)

    nx, ny = int(W / h), int(H / h)
    centre = {(i, j): ((i + 0.5) * h, (j + 0.5) * h) for i in range(nx) for j in range(ny)}
    dist: dict = {"a": 0.0}
    heap = [(0.0, "a")]
    while heap:
        d, u = heapq.heappop(heap)
        if u == "b":
            return d
        if d > dist[u]:
            continue
        p = a if u == "a" else centre[u]
        if u == "a":
            i0, j0 = int(a[0] / h), int(a[1] / h)
            nbrs = [(i, j) for i in range(i0 - 1, i0 + 2) for j in range(j0 - 1, j0 + 2)]
        else:
            nbrs = [(u[0] + di, u[1] + dj) for di in (-1, 0, 1) for dj in (-1, 0, 1)
                    if di or dj]
        nbrs = [v for v in nbrs if v in centre]
        if u != "a" and math.dist(p, b) <= 1.5 * h:
            nbrs.append("b")
        for v in nbrs:
            q = b if v == "b" else centre[v]
            nd = d + math.dist(p, q)
            if nd < dist.get(v, math.inf) and ok(p, q):
                dist[v] = nd
                heapq.heappush(heap, (nd, v))
    return math.inf


def test_round_a_wall_the_length_is_the_tangents_and_the_arc() -> None:
    """A wall 0.2 m thick from the floor to y = 2.3 of a 4 x 3 m room, a disk of 0.1 m:
    the way over its top is two tangents, two arcs and the wall's thickness; the polygonal
    outline makes it shorter by less than 1%."""
    wall = shapely.box(1.9, 0.0, 2.1, 2.3)
    g = GrownObstacles([wall], 0.1, (W, H))
    c, r, a = (1.9, 2.3), 0.1, (1.0, 1.0)
    d = math.dist(a, c)
    tangent = math.sqrt(d * d - r * r)
    phi = math.atan2(a[1] - c[1], a[0] - c[0])
    touch = phi - math.acos(r / d)  # the tangent point's angle on the corner's circle
    arc = r * ((touch - math.pi / 2) % (2 * math.pi))  # from there over to the top
    exact = 2 * (tangent + arc) + 0.2
    got = g.distance(a, (3.0, 1.0))
    assert exact * 0.99 < got <= exact
    assert g.distance((1.0, 2.8), (3.0, 2.8)) == pytest.approx(2.0)  # clear: straight


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.floats(0.5, 3.3), st.floats(0.4, 2.4), st.floats(0.1, 0.8),
                          st.floats(0.1, 0.8)), min_size=1, max_size=4),
       st.floats(0.0, 0.15), st.tuples(st.floats(0.2, 3.8), st.floats(0.2, 2.8)),
       st.tuples(st.floats(0.2, 3.8), st.floats(0.2, 2.8)))
def test_never_longer_than_a_path_the_disk_can_take(boxes, rho, a, b) -> None:
    """Against a reference that shares no code: every path the grid search finds for the
    disk (clear of the exact grown obstacles, inside the room) is at least as long as the
    geodesic, which is itself at least the straight line."""
    geoms = [shapely.box(x, y, x + w, y + h) for x, y, w, h in boxes]
    grown_exact = shapely.union_all([g.buffer(rho, quad_segs=64) for g in geoms])
    room = shapely.box(rho, rho, W - rho, H - rho)
    for p in (a, b):  # the disk must fit at both ends
        if grown_exact.intersects(shapely.Point(p)) or not room.covers(shapely.Point(p)):
            return
    got = GrownObstacles(geoms, rho, (W, H)).distance(a, b)
    assert got >= math.dist(a, b) - 1e-9
    assert got <= _feasible_grid_path(geoms, rho, a, b, 0.1) + 1e-9


def test_the_tangent_pruning_changes_no_length(monkeypatch) -> None:
    """The reduced visibility graph gives the same lengths as the full one."""
    rng = np.random.default_rng(3)
    geoms = [shapely.box(x, y, x + 0.3, y + 0.6) for x, y in rng.uniform([0.5, 0.3], [3.2, 2.2], (6, 2))]
    pairs = [tuple(rng.uniform([0.1, 0.1], [3.9, 2.9], (2, 2))) for _ in range(20)]
    reduced = GrownObstacles(geoms, 0.05, (W, H))
    want = [reduced.distance(p, q) for p, q in pairs]
    monkeypatch.setattr(GrownObstacles, "_tangent", lambda self, v, other: np.ones(len(v), bool))
    full = GrownObstacles(geoms, 0.05, (W, H))
    got = [full.distance(p, q) for p, q in pairs]
    assert got == pytest.approx(want, rel=1e-12, abs=1e-12)


def test_on_random_rooms_with_detours_it_stays_below_every_disk_path() -> None:
    """Forty random rooms of four boxes, ends drawn where the disk fits: the geodesic lies
    between the straight line and a path the disk takes, in every room; and the check is
    not empty: in many rooms the way is blocked straight and the geodesic goes round."""
    rng = np.random.default_rng(7)
    detours = checked = 0
    for _ in range(40):
        geoms = [shapely.box(x, y, x + w, y + h) for x, y, w, h in
                 rng.uniform([0.5, 0.3, 0.1, 0.3], [3.2, 2.2, 0.4, 1.2], (4, 4))]
        rho = float(rng.uniform(0.0, 0.12))
        grown = shapely.union_all([g.buffer(rho, quad_segs=64) for g in geoms])
        room = shapely.box(rho, rho, W - rho, H - rho)
        a, b = (tuple(rng.uniform([0.2, 0.2], [3.8, 2.8])) for _ in range(2))
        if any(grown.intersects(shapely.Point(p)) or not room.covers(shapely.Point(p))
               for p in (a, b)):
            continue
        ref = _feasible_grid_path(geoms, rho, a, b, 0.1)
        if not math.isfinite(ref):
            continue
        got = GrownObstacles(geoms, rho, (W, H)).distance(a, b)
        checked += 1
        detours += got > math.dist(a, b) + 1e-3
        assert math.dist(a, b) - 1e-9 <= got <= ref + 1e-9
        assert got >= ref / 1.2 - 0.2  # and not far below it: it is a tight bound
    assert checked >= 15 and detours >= 5, (checked, detours)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0.5, 3.3), st.floats(0.4, 2.4), st.floats(0.1, 0.8),
                          st.floats(0.1, 0.8)), min_size=1, max_size=4),
       st.floats(0.0, 0.15), st.tuples(st.floats(0.2, 3.8), st.floats(0.2, 2.8)),
       st.tuples(st.floats(0.2, 3.8), st.floats(0.2, 2.8)))
def test_the_path_runs_from_a_to_b_clear_and_is_as_long_as_the_distance(boxes, rho, a, b
                                                                        ) -> None:
    """``path`` starts at ``a`` and ends at ``b``; its legs keep the disk clear of the
    obstacles as outlined (grazing allowed: legs may touch a grown outline); its length is
    ``distance``; None exactly when ``distance`` is inf."""
    geoms = [shapely.box(x, y, x + w, y + h) for x, y, w, h in boxes]
    g = GrownObstacles(geoms, rho, (W, H))
    grown = shapely.union_all([b_.buffer(rho, quad_segs=2).buffer(-1e-6) for b_ in geoms])
    for p in (a, b):
        if grown.intersects(shapely.Point(p)):
            return
    d, pts = g.distance(a, b), g.path(a, b)
    if not math.isfinite(d):
        assert pts is None
        return
    assert pts is not None
    assert np.allclose(pts[0], a) and np.allclose(pts[-1], b)
    assert float(np.hypot(*np.diff(pts, axis=0).T).sum()) == pytest.approx(d, rel=1e-9,
                                                                            abs=1e-9)
    assert not grown.intersects(shapely.LineString(pts))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0.5, 3.3), st.floats(0.4, 2.4), st.floats(0.1, 0.8),
                          st.floats(0.1, 0.8)), min_size=1, max_size=4),
       st.floats(0.0, 0.15), st.tuples(st.floats(0.2, 3.8), st.floats(0.2, 2.8)),
       st.lists(st.tuples(st.floats(0.2, 3.8), st.floats(0.2, 2.8)), min_size=1, max_size=6),
       st.floats(0.5, 6.0))
def test_distances_to_many_targets_are_the_distances_to_each(boxes, rho, a, targets, below
                                                             ) -> None:
    """``distances`` gives each target's ``distance``; with ``below``, those shorter than
    it exactly and the others as at least ``below`` (and never above their own)."""
    g = GrownObstacles([shapely.box(x, y, x + w, y + h) for x, y, w, h in boxes], rho, (W, H))
    t = np.asarray(targets, float)
    want = np.array([g.distance(a, p) for p in t])
    assert g.distances(a, t) == pytest.approx(want, rel=1e-12, abs=1e-12)
    cut = g.distances(a, t, below)
    short = want < below
    assert cut[short] == pytest.approx(want[short], rel=1e-12, abs=1e-12)
    assert np.all(cut[~short] >= below - 1e-12) and np.all(cut <= want + 1e-12)


def test_a_corridor_exactly_two_radii_wide_is_open_unless_merged() -> None:
    """Two walls whose grown outlines meet along an edge leave a corridor the disk fits
    through exactly (grazing both): open without ``merge`` (a lower bound for grazing
    paths too), closed with it (for paths that keep some distance)."""
    walls = [shapely.box(0.0, 2.0, 1.0, 5.0), shapely.box(1.5, 2.0, 3.0, 5.0)]
    a, b = (1.25, 1.0), (1.25, 6.0)
    assert GrownObstacles(walls, 0.25, (3.0, 7.0)).distance(a, b) == pytest.approx(5.0)
    assert GrownObstacles(walls, 0.25, (3.0, 7.0), merge=True).distance(a, b) > 5.0


@pytest.mark.parametrize("block", [1, 3, 7])
def test_the_visibility_graph_is_the_same_built_in_blocks(monkeypatch, block) -> None:
    """The vertex pairs are tested ``MATRIX_BLOCK`` rows at a time (memory): any block
    size gives the same edges, in the same order, as one block of every row."""
    import lamp.scene.geodesic as geodesic

    rng = np.random.default_rng(5)
    geoms = [shapely.box(x, y, x + 0.3, y + 0.5) for x, y in rng.uniform([0.3, 0.3], [3.3, 2.2], (7, 2))]
    monkeypatch.setattr(geodesic, "MATRIX_BLOCK", 10**6)
    whole = GrownObstacles(geoms, 0.05, (W, H), merge=True)._edges
    monkeypatch.setattr(geodesic, "MATRIX_BLOCK", block)
    blocks = GrownObstacles(geoms, 0.05, (W, H), merge=True)._edges
    assert len(whole[0]) > 50
    for a, b in zip(whole, blocks, strict=True):
        assert np.array_equal(a, b)
