"""A queue of loads in one aisle starts from its head (``teams.standing_ahead``)."""

from __future__ import annotations

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.fleet.teams import corridor, least_conflict_order, standing_ahead
from lamp.geometry.shapes import to_shapely
from lamp.scene.model import Rectangle

BOX = Rectangle((0.4, 0.4))


def _queue(xs: list[float], goal_x: float = 20.0):
    """Boxes at ``xs`` on the line y = 1, each going to (goal_x, 1)."""
    poses = {k: np.array([x, 1.0, 0.0]) for k, x in enumerate(xs)}
    goals = {k: np.array([goal_x, 1.0, 0.0]) for k in poses}
    ways = {k: corridor(BOX, poses[k], goals[k], 0.05) for k in poses}
    bodies = {k: to_shapely(BOX, poses[k]) for k in poses}
    return poses, goals, ways, bodies


@settings(max_examples=40)
@given(st.lists(st.floats(0.0, 15.0), min_size=1, max_size=6).map(
    lambda xs: sorted({round(x, 1) for x in xs})).filter(
    lambda xs: all(b - a >= 0.6 for a, b in zip(xs, xs[1:], strict=False))),
    st.randoms(use_true_random=False))
def test_every_load_behind_another_on_its_way_has_it_ahead(xs, rnd):
    """Loads queued on one line towards one goal beyond them: ``j`` is ahead of ``k``
    exactly when it stands nearer the goal; and the order puts the head first, then each
    next one, whatever the file order."""
    xs = list(xs)
    rnd.shuffle(xs)
    poses, goals, ways, bodies = _queue(xs)
    ahead = standing_ahead(ways, bodies, poses, goals)
    for k in poses:
        assert ahead[k] == {j for j in poses if xs[j] > xs[k]}
    order = least_conflict_order(sorted(poses), ways, [], None, ahead)
    assert [xs[k] for k in order] == sorted(xs, reverse=True)


def test_beside_or_beyond_the_goal_is_not_ahead():
    """A body off the way, and one past the goal on its line, are not ahead."""
    poses = {0: np.array([1.0, 1.0, 0.0]), 1: np.array([5.0, 3.0, 0.0]),
             2: np.array([12.0, 1.0, 0.0])}
    goals = {0: np.array([10.0, 1.0, 0.0]), 1: np.array([5.0, 6.0, 0.0]),
             2: np.array([14.0, 1.0, 0.0])}
    ways = {k: corridor(BOX, poses[k], goals[k], 0.05) for k in poses}
    bodies = {k: to_shapely(BOX, poses[k]) for k in poses}
    assert standing_ahead(ways, bodies, poses, goals) == {0: set(), 1: set(), 2: set()}


@settings(max_examples=60)
@given(st.integers(0, 2**31 - 1), st.integers(1, 7))
def test_an_object_starts_after_those_ahead_of_it(seed, n):
    """With ``ahead`` acyclic and no goal in any way, every object starts after each one
    standing ahead of it, whatever the corridors."""
    rng = np.random.default_rng(seed)
    cands = sorted(rng.choice(20, n, replace=False).tolist())
    rank = {k: r for r, k in enumerate(rng.permutation(cands).tolist())}
    ahead = {k: {j for j in cands if rank[j] < rank[k] and rng.random() < 0.4} for k in cands}
    corridors = {k: shapely.box(*(xy := rng.uniform(0, 5, 2)), *(xy + 2)) for k in cands}
    order = least_conflict_order(cands, corridors, [], None, ahead)
    assert sorted(order) == cands
    for k in cands:
        assert all(order.index(j) < order.index(k) for j in ahead[k])
