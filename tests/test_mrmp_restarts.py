"""A fleet's stalled steps (``lamp.mrmp.gspi_loop``): declared after at most
``effort.STALL_STEPS`` steps without progress (a plain reference of the rule), and
started again with other tie-breaking seeds on the same lattice; plans that do not stall
are the same with or without the restarts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fleet_plans import checked_plan
from hypothesis import example, given, settings
from hypothesis import strategies as st

import lamp.mrmp.gspi_loop as gspi_loop
from lamp.mrmp import plan_paths
from lamp.mrmp.effort import stall_limit
from lamp.mrmp.gspi_loop import restart_seed
from lamp.mrmp.result import GspiStatus
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
R = 0.05


@settings(max_examples=200, deadline=None)
@example(10, 100)
@example(10, 101)
@example(5000, 100)
@example(5000, 101)
@example(20, 200)
@given(side=st.integers(0, 20_000), n=st.integers(1, 5000))
def test_fleets_over_100_robots_stall_after_at_most_256_steps(side: int, n: int) -> None:
    """``2 * side + 10 n`` steps, and at most 256 for more than 100 robots."""
    want = 2 * side + 10 * n
    if n > 100:
        want = min(want, 256)
    assert stall_limit(side, n) == want


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), k=st.integers(1, 8), j=st.integers(1, 8))
def test_restart_seeds_are_distinct_valid_and_fixed(seed: int, k: int, j: int) -> None:
    """Each restart has its own seed, a valid one (0 <= s < 2**31), the same every
    time, and none is the search's own."""
    s = restart_seed(seed, k)
    assert 0 <= s < 2**31 and s == restart_seed(seed, k) and s != seed
    assert (s == restart_seed(seed, j)) == (k == j)


def test_a_stalled_fleet_is_solved_by_a_restart_on_the_same_lattice() -> None:
    """800 robots on random-64-64-20, seed 50: four robots enter a dead-end corridor of
    four goals in the wrong order and the 3 cm lattice stalls (its restarts switched
    off: within a few hundred steps, not the 9,000 of ``2 * side + 10 N``; the 2 cm
    lattice stalls too). With the restarts a later seed solves it on the 3 cm lattice:
    the plan passes the fleet checker, keeps one robot per goal and is the same when
    planned again."""
    gm = load_grid_map(MAPF / "random-64-64-20.map", 0.15, R)
    S, G = random_instance(gm, 800, 50)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi_loop, "RESTARTS", 0)
        plain = plan_paths(gm.scene, S, G, seed=50, lattice_step=0.03, time_limit=600.0)
    assert plain.status == GspiStatus.STALLED and plain.iterations < 1000
    plan = checked_plan(gm.scene, S, G, 50, R)
    assert plan.stats["stall_restarts"] >= 1
    assert [a["lattice_step"] for a in plan.stats["attempts"]] == [0.05, 0.03]


def test_restarts_leave_plans_that_do_not_stall_as_they_are() -> None:
    """200 robots on random-64-64-20 (seed 3): no stall, no restart, and the plan is
    the one planned with the restarts switched off, bit for bit."""
    gm = load_grid_map(MAPF / "random-64-64-20.map", 0.15, R)
    S, G = random_instance(gm, 200, 3)
    plan = plan_paths(gm.scene, S, G, seed=3, time_limit=600.0)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi_loop, "RESTARTS", 0)
        plain = plan_paths(gm.scene, S, G, seed=3, time_limit=600.0)
    assert plan.success and plan.stats["stall_restarts"] == 0
    assert np.array_equal(plan.paths, plain.paths)
    assert np.array_equal(plan.goal_of, plain.goal_of)
