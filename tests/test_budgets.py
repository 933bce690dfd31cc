"""Deterministic budgets: planners stop on counts, wall time is only an outer cap.

Under simulated load (every ``time.perf_counter`` reading runs 8x fast, so each
wall-clock limit fires 8x earlier) a run gives the same result; a count that runs out
says which one in the plan's status and the object's failure reason.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import lamp
from lamp.contract.plan import Plan, PlanStatus
from lamp.planners.config import PlannerConfig
from lamp.planners.lamp_astar import LampAStar
from lamp.planners.lazy import LazyPlanner
from lamp.planners.task import ManipulationTask
from lamp.scene import scene_from_dict

TIME_KEYS = {"planning_time_s", "total_planning_time_s", "median_planning_time_s",
             "wall_time_s", "executed_planning_time_s", "unexecuted_planning_time_s",
             "planning_time_per_segment_s"}

SCENE = {
    "format": "lamp-scene/1", "name": "budgets", "workspace": [2.4, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [{"type": "rectangle", "center": [1.3, 0.75], "size": [0.1, 0.9]},
                  {"type": "circle", "center": [0.6, 1.6], "radius": 0.15}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.8, 1.0, 0.0],
                 "goal": [1.8, 0.55, 1.5708]}],
}


@pytest.fixture(scope="module")
def proposer():
    from lamp.manip import GeometricProposer

    return GeometricProposer()


def strip_times(d: dict) -> dict:
    d = {k: v for k, v in d.items() if k not in TIME_KEYS}
    d["objects"] = [{k: v for k, v in o.items() if k != "planning_time_s"} for o in d["objects"]]
    return d


def loaded_clock(monkeypatch, factor: float) -> None:
    """Make ``time.perf_counter`` (what every planner module reads) run ``factor`` x fast."""
    real = time.perf_counter
    t0 = real()
    monkeypatch.setattr(time, "perf_counter", lambda: t0 + (real() - t0) * factor)


@pytest.mark.parametrize("planner", ["lazy", "astar"])
def test_same_result_under_load(planner, proposer, monkeypatch):
    scene = scene_from_dict(SCENE)
    # a planning limit that the run keeps well inside even when it is 8x shorter and the
    # machine is busy (60 s at 8x left LAMP-A* 7.5 s of real time: too little beside two
    # CPU-bound processes); the counts, not the clock, end the search
    calm = lamp.solve(scene, planner, seed=1, model=proposer, time_limit=600.0).to_dict()
    assert calm["stats"]["gspi_calls"] > 0 and calm["stats"]["gspi_timeouts"] == 0
    loaded_clock(monkeypatch, 8.0)
    busy = lamp.solve(scene, planner, seed=1, model=proposer, time_limit=600.0).to_dict()
    assert strip_times(busy) == strip_times(calm)


def test_same_result_on_a_maze_under_heavy_load(proposer, monkeypatch):
    """A suite maze (about 70 Gspi calls of up to ~50 ms) under a 25x fast clock: the
    former 1 s Gspi limit (40 ms at that speed) cut some calls short and changed the run;
    the counts do not depend on the clock."""
    from importlib.resources import files

    from lamp.scene import load_scene

    scene = load_scene(files("lamp.suites") / "data" / "maze" / "maze-03.yaml")
    calm = lamp.solve(scene, "lazy", seed=0, model=proposer).to_dict()
    assert calm["success"] and calm["stats"]["gspi_timeouts"] == 0
    loaded_clock(monkeypatch, 25.0)
    busy = lamp.solve(scene, "lazy", seed=0, model=proposer).to_dict()
    assert strip_times(busy) == strip_times(calm)


def test_the_clock_is_still_an_outer_cap(proposer, monkeypatch):
    """A clock 10^6 x fast ends the search on the deadline, and the status says so."""
    scene = scene_from_dict(SCENE)
    loaded_clock(monkeypatch, 1e6)
    res = lamp.solve(scene, "lazy", seed=1, model=proposer, time_limit=60.0).to_dict()
    assert not res["success"]
    assert res["objects"][0]["failure_reason"] == PlanStatus.TIME_LIMIT.reason


def _task(proposer, config: PlannerConfig) -> ManipulationTask:
    scene = scene_from_dict(SCENE)
    poses = np.array([o.start for o in scene.objects], float)
    return ManipulationTask(scene, 0, poses, proposer, config, seed=1)


def test_lazy_verify_budget_names_itself(proposer):
    task = _task(proposer, PlannerConfig.of(max_verify_calls=2))
    plan = LazyPlanner.from_task(task).plan(task.object_poses[0], task.scene.robot_starts_array)
    assert plan.status is PlanStatus.BUDGET_EXHAUSTED and plan.limit == "max_verify_calls"
    assert plan.reason == "no plan found: max_verify_calls exhausted"
    assert task.stats.verify_calls == 2  # counted from the call's start, never past it


def test_lazy_object_verify_budget_spans_the_calls_and_ends_the_loop(proposer):
    """``lazy_max_object_verify`` bounds the Verify calls of all an object's plan calls
    (the per-call ``max_verify_calls`` starts afresh each call): the call that reaches
    it names it, the next makes none, and the closed loop ends for good on it (no retry,
    no wait for the world) with the object's verdict naming it."""
    from lamp.planners.config import LAZY_VERIFY_RATE

    task = _task(proposer, PlannerConfig())
    q_O, q_R = task.object_poses[0], task.scene.robot_starts_array
    assert LazyPlanner.from_task(task).plan(q_O, q_R).solved
    used = task.stats.verify_calls
    assert used > 1
    short = _task(proposer, PlannerConfig.of(lazy_max_object_verify=used - 1))
    planner = LazyPlanner.from_task(short)
    plan = planner.plan(q_O, q_R)
    assert plan.limit == "lazy_max_object_verify" and plan.spent
    assert plan.reason == "no plan found: lazy_max_object_verify exhausted"
    assert short.stats.verify_calls == used - 1  # never past it
    assert planner.plan(q_O, q_R).spent and short.stats.verify_calls == used - 1
    assert not Plan.failed(PlanStatus.BUDGET_EXHAUSTED, limit="max_verify_calls").spent
    assert PlannerConfig.of(planning_time_limit=30.0).lazy_verify_calls == round(
        30 * LAZY_VERIFY_RATE)
    res = lamp.solve(scene_from_dict(SCENE), "lazy", seed=1, model=proposer,
                     config=PlannerConfig.of(lazy_max_object_verify=used - 1)).to_dict()
    obj = res["objects"][0]
    assert obj["failure_reason"] == "no plan found: lazy_max_object_verify exhausted"
    assert obj["verify_calls"] == used - 1 and obj["segments"] == 0
    ok = lamp.solve(scene_from_dict(SCENE), "lazy", seed=1, model=proposer).to_dict()
    assert ok["objects"][0]["verify_calls"] == ok["stats"]["verify_calls"] > 0


def test_astar_expansion_budget_names_itself(proposer):
    task = _task(proposer, PlannerConfig.of(astar_max_expansions=3))
    plan = LampAStar.from_task(task).plan(task.object_poses[0], task.scene.robot_starts_array)
    assert plan.status is PlanStatus.BUDGET_EXHAUSTED and plan.limit == "astar_max_expansions"
    cfg = PlannerConfig.of(astar_max_expansions=3, planning_time_limit=500.0)
    res = lamp.solve(scene_from_dict(SCENE), "astar", seed=1, model=proposer, config=cfg)
    assert res.to_dict()["objects"][0]["failure_reason"] == \
        "no plan found: astar_max_expansions exhausted"


def test_astar_budget_is_per_object_and_follows_the_limit(proposer):
    """The expansions of one object's searches add up (like its cumulative planning
    limit); ``clear`` restores the budget; by default the budget is
    ``ASTAR_EXPANSION_RATE`` per second of the planning limit, whichever way it is set."""
    from lamp.pipeline.registry import get
    from lamp.planners.config import ASTAR_EXPANSION_RATE

    task = _task(proposer, PlannerConfig.of(astar_max_expansions=1000))
    astar = LampAStar.from_task(task)
    q_O, q_R = task.object_poses[0], task.scene.robot_starts_array
    assert astar.plan(q_O, q_R).solved
    used = astar.expanded
    assert 0 < used < 1000
    smaller = _task(proposer, PlannerConfig.of(astar_max_expansions=used + 1))
    astar.config, astar.verifier = smaller.config, smaller.verifier
    assert astar.plan(q_O, q_R).limit == "astar_max_expansions"  # only 1 left
    assert astar.expanded == used + 1
    astar.clear()
    assert astar.plan(q_O, q_R).solved and astar.expanded == used
    assert get("astar").default_config().astar_expansions == round(500 * ASTAR_EXPANSION_RATE)
    assert PlannerConfig.of(planning_time_limit=30.0).astar_expansions == round(
        30 * ASTAR_EXPANSION_RATE)
    assert PlannerConfig.of(planning_time_limit=float("inf")).astar_expansions > 10**9

def test_lazy_expansion_budget_is_per_object_and_names_itself(proposer):
    """D* Lite's expansions over all of one object's plan calls add up in
    ``stats.search_expansions``; a budget one short of what a plan needs ends the call
    on the count (never past it), and by default the budget is ``LAZY_EXPANSION_RATE``
    per second of the planning limit."""
    from lamp.pipeline.registry import get
    from lamp.planners.config import LAZY_EXPANSION_RATE

    task = _task(proposer, PlannerConfig())
    q_O, q_R = task.object_poses[0], task.scene.robot_starts_array
    ref = LazyPlanner.from_task(task).plan(q_O, q_R)
    used = task.stats.search_expansions
    assert ref.solved and used > 0 and task.stats.max_plan_expansions == used
    exact = _task(proposer, PlannerConfig.of(lazy_max_expansions=used))
    plan = LazyPlanner.from_task(exact).plan(q_O, q_R)
    assert plan.solved and exact.stats.search_expansions == used
    assert [t.q_to.tolist() for t in plan.transitions] == [t.q_to.tolist() for t in ref.transitions]
    short = _task(proposer, PlannerConfig.of(lazy_max_expansions=used - 1))
    planner = LazyPlanner.from_task(short)
    plan = planner.plan(q_O, q_R)
    assert plan.status is PlanStatus.BUDGET_EXHAUSTED and plan.limit == "lazy_max_expansions"
    assert plan.reason == "no plan found: lazy_max_expansions exhausted"
    assert short.stats.search_expansions == used - 1
    assert len(planner.dstar.rhs) == 1  # the spent search gave its tables back
    assert planner.plan(q_O, q_R).limit == "lazy_max_expansions"  # nothing left: no search
    assert short.stats.search_expansions == short.stats.max_plan_expansions == used - 1
    total = type(task.stats)()
    total.add(task.stats)
    total.add(short.stats)  # counts add up, maxima stay maxima
    assert total.search_expansions == 2 * used - 1 and total.max_plan_expansions == used
    assert get("lazy").default_config().lazy_expansions == round(
        get("lazy").default_config().loop.planning_time_limit * LAZY_EXPANSION_RATE)
    assert PlannerConfig.of(planning_time_limit=30.0).lazy_expansions == round(
        30 * LAZY_EXPANSION_RATE)
    assert PlannerConfig.of(planning_time_limit=float("inf")).lazy_expansions > 10**9
    res = lamp.solve(scene_from_dict(SCENE), "lazy", seed=1, model=proposer,
                     config=PlannerConfig.of(lazy_max_expansions=1)).to_dict()
    assert res["objects"][0]["failure_reason"] == "no plan found: lazy_max_expansions exhausted"


def test_solve_time_limit_sets_the_astar_budget(proposer, monkeypatch):
    """``lamp.solve``'s ``time_limit`` stands for a budget of expansions: with the clock
    stopped (so that no wall-clock limit can fire) a limit worth one expansion ends the
    search on the count."""
    from lamp.planners.config import ASTAR_EXPANSION_RATE

    monkeypatch.setattr(time, "perf_counter", lambda: 0.0)
    res = lamp.solve(scene_from_dict(SCENE), "astar", seed=1, model=proposer,
                     time_limit=1.0 / ASTAR_EXPANSION_RATE).to_dict()
    assert res["objects"][0]["failure_reason"] == "no plan found: astar_max_expansions exhausted"
    assert res["stats"]["verify_calls"] > 0


@pytest.mark.parametrize("field, value", [("max_verify_calls", 0), ("astar_max_expansions", -1),
                                          ("lazy_max_expansions", 0),
                                          ("lazy_max_object_verify", 0),
                                          ("max_plan_iterations", 1.5),
                                          ("gspi_time_limit", 0.0)])
def test_config_rejects_bad_budgets(field, value):
    with pytest.raises(ValueError, match=field):
        PlannerConfig.of(**{field: value})


@pytest.mark.parametrize("limit", [0.0, -1.0, float("nan")])
def test_solve_rejects_a_bad_time_limit(limit, proposer):
    with pytest.raises(ValueError, match="planning_time_limit"):
        lamp.solve(scene_from_dict(SCENE), "lazy", model=proposer, time_limit=limit)
