"""Distance grids over a shared base of static obstacles (``distance_tiles.shared_tiles``):
the same values as a grid of all the obstacles, and only the tiles the grid's own
obstacles change held by the grid."""

from __future__ import annotations

import gc

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pages import resident_bytes
from test_object_space import object_shapes
from test_object_space import obstacles as object_obstacles

from lamp.geometry.distance_tiles import TILE, DistanceTiles, shared_tiles
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.primitives import Circle, Obstacle

WS = (2.0, 2.0)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(static=st.lists(object_obstacles(), min_size=0, max_size=5),
       own=st.lists(object_obstacles(), min_size=0, max_size=3),
       cap=st.sampled_from([0.05, 0.15, 0.5]), seed=st.integers(0, 2**31 - 1))
def test_grid_over_a_base_reads_as_a_grid_of_all_obstacles(static, own, cap, seed) -> None:
    static = tuple(static)
    base = DistanceTiles(WS, static, 0.004, cap=cap, full_grid_cells=0, slotted=True)
    over = DistanceTiles(WS, own, 0.004, cap=cap, full_grid_cells=0, base=base)
    ref = DistanceTiles(WS, static + tuple(own), 0.004, cap=cap, full_grid_cells=0)
    rng = np.random.default_rng(seed)
    p = rng.uniform(0.0, 2.0, size=(300, 2))
    over.ensure(p, 0.05)
    ref.ensure(p, 0.05)
    ny, nx = ref.shape
    rows = np.minimum((p[:, 1] / 0.004).astype(int), ny - 1)
    cols = np.minimum((p[:, 0] / 0.004).astype(int), nx - 1)
    np.testing.assert_array_equal(over.values(rows, cols), ref.values(rows, cols))
    # every filled tile is the grid's own exactly where one of its own obstacles comes
    # within the halo; elsewhere it is the base's
    filled = over.table != -1
    assert ((over.table >= 0) | (over.table <= -2))[filled].all()
    assert over.nbytes == int((over.table >= 0).sum()) * TILE * TILE * 4 + over.table.nbytes
    if not own:
        assert not (over.table >= 0).any()


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(shape=object_shapes, static=st.lists(object_obstacles(), min_size=1, max_size=5),
       other=object_obstacles(), seed=st.integers(0, 2**31 - 1))
def test_object_space_over_the_static_base_answers_as_alone(shape, static, other,
                                                             seed) -> None:
    """A large map (tiles filled on demand): spaces given their static obstacles share
    their tiles and answer every query exactly as a space of their own."""
    ws = (40.0, 40.0)
    static = tuple(Obstacle(o.shape, (o.pose[0] + 19.0, o.pose[1] + 19.0, o.pose[2]))
                   for o in static)
    other = Obstacle(other.shape, (other.pose[0] + 19.0, other.pose[1] + 19.0, other.pose[2]))
    obstacles = (*static, other)
    shared = ObjectSpace(shape, ws, obstacles, static=static)
    alone = ObjectSpace(shape, ws, obstacles)
    assert shared.grid.capped and shared.grid._base is not None and alone.grid._base is None
    rng = np.random.default_rng(seed)
    a = rng.uniform([19.0, 19.0, -3.0], [21.0, 21.0, 3.0], size=(60, 3))
    b = a + rng.uniform([-0.4, -0.4, -1.0], [0.4, 0.4, 1.0], size=(60, 3))
    np.testing.assert_array_equal(shared.clearance(a), alone.clearance(a))
    np.testing.assert_array_equal(shared.pose_free(a), alone.pose_free(a))
    np.testing.assert_array_equal(shared.motions_free(a, b), alone.motions_free(a, b))


def test_spaces_of_one_map_share_one_base_and_hold_only_their_changes() -> None:
    ws = (40.0, 40.0)
    static = tuple(Obstacle(Circle(0.3), (5.0 + 3 * i, 20.0, 0.0)) for i in range(10))
    box = Circle(0.2)
    far = Obstacle(box, (35.0, 35.0, 0.0))
    one = ObjectSpace(box, ws, (*static, far), static=static)
    two = ObjectSpace(box, ws, (*static, Obstacle(box, (20.0, 20.0, 0.0))), static=static)
    assert one.grid._base is two.grid._base
    line = np.stack([np.linspace(4.0, 34.0, 200), np.full(200, 19.5), np.zeros(200)], axis=1)
    one.clearance(line)
    two.clearance(line)
    own_one, own_two = int((one.grid.table >= 0).sum()), int((two.grid.table >= 0).sum())
    shared = int((one.grid.table <= -2).sum())
    assert own_one == 0 and shared > 20  # its other obstacle is far from the line
    assert 0 < own_two <= 9  # tiles within the halo of the obstacle at (20, 20)
    assert one.grid.nbytes < two.grid.nbytes < shared * TILE * TILE * 4
    # the base lives while a grid over it does, and no longer
    cap = one.grid.cap
    assert shared_tiles(ws, static, 0.004, cap) is one.grid._base
    del one, two
    gc.collect()
    fresh = shared_tiles(ws, static, 0.004, cap)
    assert int((fresh.table != -1).sum()) == 0


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(static=st.lists(object_obstacles(), min_size=1, max_size=5),
       owns=st.lists(st.lists(object_obstacles(), min_size=0, max_size=2), min_size=1,
                     max_size=3),
       kept=st.integers(1, 5), seed=st.integers(0, 2**31 - 1))
def test_a_base_over_its_budget_hands_tiles_back_and_reads_the_same(static, owns, kept,
                                                                      seed) -> None:
    """A base keeping ``kept`` tiles, several grids over it queried in turn, by ``ensure``
    and ``ensure_point``: every read right after its ``ensure`` equals a grid of all the
    obstacles with no budget; the base holds at most ``kept`` tiles or those of the
    largest single call, and hands back the others' pages (they read as zeros)."""
    static = tuple(static)
    base = DistanceTiles(WS, static, 0.004, cap=0.15, full_grid_cells=0, slotted=True)
    base.keep(kept * TILE * TILE * 4)
    grids = [DistanceTiles(WS, tuple(own), 0.004, cap=0.15, full_grid_cells=0, base=base)
             for own in owns]
    refs = [DistanceTiles(WS, static + tuple(own), 0.004, cap=0.15, full_grid_cells=0)
            for own in owns]
    rng = np.random.default_rng(seed)
    ny, nx = refs[0].shape
    largest, singles = 0, []
    for _ in range(16):
        k = int(rng.integers(len(grids)))
        centre = rng.uniform(0.0, 2.0, size=2)
        p = centre + rng.uniform(-0.3, 0.3, size=(int(rng.integers(1, 40)), 2))
        p = np.clip(p, 0.0, 1.999)
        if singles and rng.random() < 0.3:  # a point asked for before (it may be handed back)
            k, p = singles[int(rng.integers(len(singles)))]
        if len(p) == 1 or rng.random() < 0.3:
            p = p[:1]
            singles.append((k, p))
            grids[k].ensure_point(float(p[0, 0]), float(p[0, 1]), 0.05)
        else:
            grids[k].ensure(p, 0.05)
        refs[k].ensure(p, 0.05)
        rows = np.minimum((p[:, 1] / 0.004).astype(int), ny - 1)
        cols = np.minimum((p[:, 0] / 0.004).astype(int), nx - 1)
        np.testing.assert_array_equal(grids[k].values(rows, cols), refs[k].values(rows, cols))
        largest = max(largest, int((base._used == base._tick).sum()))
        assert base._n <= max(kept, largest) and base._n == int((base.table >= 0).sum())
    for flat in np.flatnonzero(base.table.ravel() == -1):  # handed back: no pages held
        assert resident_bytes(base._store[flat]) == 0
        assert not base._store[flat].any()


def test_a_grid_keeping_a_budget_read_directly_keeps_the_tiles_it_reads() -> None:
    """A slotted grid with a budget of one tile, asked directly for points over two tiles:
    both are kept for that call (its reads see values, not -inf); a later call for a
    third tile hands both back."""
    static = (Obstacle(Circle(0.2), (0.5, 0.5, 0.0)),)
    grid = DistanceTiles(WS, static, 0.004, cap=0.15, full_grid_cells=0, slotted=True)
    ref = DistanceTiles(WS, static, 0.004, cap=0.15, full_grid_cells=0)
    grid.keep(TILE * TILE * 4)
    p = np.array([[0.3, 0.3], [0.3, 0.3 + TILE * 0.004]])
    grid.ensure(p, 0.01)
    ref.ensure(p, 0.01)
    rows, cols = (p[:, 1] / 0.004).astype(int), (p[:, 0] / 0.004).astype(int)
    np.testing.assert_array_equal(grid.values(rows, cols), ref.values(rows, cols))
    assert grid._n == 2
    grid.ensure(p[:1], 0.01)
    grid.ensure(p[:1] + [TILE * 0.004, 0.0], 0.01)
    assert grid._n == 1 and grid.table[0, 1] >= 0
    assert grid.table[0, 0] == grid.table[1, 0] == -1
    assert resident_bytes(grid._store[0]) == resident_bytes(grid._store[4]) == 0
