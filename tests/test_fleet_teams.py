"""``teams.balanced_teams`` against a brute force over every matching, and ``allocate``
with goals: the same objects start with the same team sizes as the nearest-first rule."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from lamp.errors import InputError
from lamp.fleet.config import FleetConfig
from lamp.fleet.teams import allocate, balanced_teams


def _values(teams, robots, objects, hauls):
    """Each (robot, object) pair's distance plus haul."""
    return [math.dist(robots[i], objects[k][:2]) + hauls[k] for k, t in teams.items() for i in t]


@settings(max_examples=120, deadline=None)
@given(st.integers(0, 2**31 - 1), st.lists(st.integers(1, 3), min_size=1, max_size=3),
       st.integers(0, 1))
def test_balanced_teams_is_a_least_bottleneck_then_least_squares_matching(seed, sizes, spare):
    rng = np.random.default_rng(seed)
    n = sum(sizes) + spare
    robots = rng.uniform(0, 10, (n + 2, 2))
    pool = sorted(rng.choice(n + 2, n, replace=False).tolist())
    objects = np.c_[rng.uniform(0, 10, (len(sizes), 2)), np.zeros(len(sizes))]
    hauls = {k: float(h) for k, h in enumerate(rng.uniform(0, 10, len(sizes)))}
    want = dict(enumerate(sizes))
    slots = [k for k, s in want.items() for _ in range(s)]
    assume(len(slots) <= 6)  # the brute force below tries up to 7!/1 matchings
    teams = balanced_teams(want, pool, robots, objects, hauls)
    assert {k: len(t) for k, t in teams.items()} == want
    used = [i for t in teams.values() for i in t]
    assert len(used) == len(set(used)) and set(used) <= set(pool)
    assert all(t == sorted(t) for t in teams.values())
    # reference: every assignment of distinct pool robots to the slots
    best = (math.inf, math.inf)
    for chosen in itertools.permutations(pool, len(slots)):
        v = [math.dist(robots[i], objects[k][:2]) + hauls[k]
             for i, k in zip(chosen, slots, strict=True)]
        best = min(best, (max(v), sum(x * x for x in v)))
    got = _values(teams, robots, objects, hauls)
    assert max(got) <= best[0] + 1e-9
    assert sum(x * x for x in got) <= best[1] + 1e-6


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 5), st.integers(0, 12), st.booleans())
def test_allocate_with_goals_starts_the_same_teams_sizes_balanced(seed, n_obj, n_free, moving):
    rng = np.random.default_rng(seed)
    robots = rng.uniform(0, 10, (14, 2))
    objects = np.c_[rng.uniform(0, 10, (n_obj, 2)), np.zeros(n_obj)]
    goals = np.c_[rng.uniform(0, 10, (n_obj, 2)), np.zeros(n_obj)]
    free = sorted(rng.choice(14, n_free, replace=False).tolist())
    nearest = allocate(list(range(n_obj)), free, robots, objects, moving)
    balanced = allocate(list(range(n_obj)), free, robots, objects, moving, goals)
    assert list(balanced) == list(nearest)  # the same objects start, in the same order
    assert sorted(len(t) for t in balanced.values()) == sorted(len(t) for t in nearest.values())
    used = [i for t in balanced.values() for i in t]
    assert len(used) == len(set(used)) and set(used) <= set(free)
    hauls = {k: math.dist(objects[k][:2], goals[k][:2]) for k in nearest}
    if len(nearest) == n_obj:  # no leftovers joined: the bottleneck is no worse
        assert (max(_values(balanced, robots, objects, hauls), default=0.0)
                <= max(_values(nearest, robots, objects, hauls), default=0.0) + 1e-9)


def test_balance_teams_and_reach_cut_are_zero_or_one() -> None:
    assert FleetConfig(balance_teams=1).balance_teams == 1
    assert FleetConfig(reach_cut=1).reach_cut == 1 and FleetConfig().reach_cut == 0
    with pytest.raises(InputError, match="fleet_balance_teams: 0 or 1, got 2"):
        FleetConfig(balance_teams=2)
    with pytest.raises(InputError, match="fleet_reach_cut: 0 or 1, got 3"):
        FleetConfig(reach_cut=3)


def test_order_in_way_and_follow_are_zero_or_one_and_off_by_default() -> None:
    assert FleetConfig().order_in_way == 0 and FleetConfig().follow == 0
    assert FleetConfig(order_in_way=1).order_in_way == 1 and FleetConfig(follow=1).follow == 1
    with pytest.raises(InputError, match="fleet_order_in_way: 0 or 1, got 2"):
        FleetConfig(order_in_way=2)
    with pytest.raises(InputError, match="fleet_follow: 0 or 1, got 2"):
        FleetConfig(follow=2)
