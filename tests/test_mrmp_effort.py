"""The timed repair's effort by plan (``lamp.mrmp.effort``): the rule against a plain
reference, and a crowded plan repaired harder inside ``plan_paths``."""

from __future__ import annotations

from pathlib import Path

import pytest
from fleet_plans import checked_plan, row_makespan
from hypothesis import example, given, settings
from hypothesis import strategies as st

import lamp.mrmp.gspi as gspi
from lamp.mrmp import plan_paths
from lamp.mrmp.effort import timed_effort
from lamp.mrmp.timed_repair import timed_budget
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
R = 0.05


@settings(max_examples=200, deadline=None)
@example(100, 2.0, 1.0)
@example(101, 2.0, 1.0)
@example(400, 2.0, 1.0)
@example(401, 2.0, 1.0)
@example(200, 1.45, 1.0)
@example(200, 1.4500001, 1.0)
@example(200, 2.0, 0.0)
@given(n=st.integers(1, 2000), makespan=st.floats(0.0, 10.0), floor=st.floats(0.0, 5.0))
def test_only_fleets_of_101_to_400_robots_far_above_the_floor_are_repaired_harder(
        n, makespan, floor) -> None:
    """The defaults (no arguments) unless 100 < n <= 400, the floor known and the
    makespan above 1.45 times it; then groups of 8 and four times the states."""
    got = timed_effort(n, makespan, floor)
    if 100 < n <= 400 and floor > 0.0 and makespan > 1.45 * floor:
        assert got == {"budget": 4 * timed_budget(n), "group": 8}
        assert got["budget"] == 20_000
    else:
        assert got == {}


def test_a_crowded_plan_far_above_the_floor_is_repaired_harder() -> None:
    """200 robots on random-32-32-20, seed 2 (retimed makespan above 1.45 times the
    floor): the plan passes the fleet checker, every goal keeps one robot, a second
    call gives the same plan, and it ends well before the one repaired with the
    defaults (0.81 m against 1.02 m)."""
    gm = load_grid_map(MAPF / "random-32-32-20.map", 0.15, R)
    S, G = random_instance(gm, 200, 2)
    plan = checked_plan(gm.scene, S, G, 2, R)
    assert plan.stats["timed_groups"] >= 1
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "timed_effort", lambda *args: {})
        plain = plan_paths(gm.scene, S, G, seed=2, time_limit=600.0)
    assert plain.success and plain.stats["timed_groups"] == 0
    assert row_makespan(plan.paths) < row_makespan(plain.paths) - 0.1
