"""``planners.series.LoopSeries``: each next loop gets what the earlier ones left, the
series runs out at its limits and names them, and the outcome merges every loop."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lamp.contract.result import ObjectResult
from lamp.contract.runner import LoopEnd, ObjectOutcome
from lamp.planners.config import PlannerConfig
from lamp.planners.series import LoopSeries


def _loop(segments: int, planning: float, end: LoopEnd = LoopEnd.WORLD_CHANGED,
          verify: int = 0, expansions: int = 0) -> ObjectOutcome:
    result = ObjectResult(success=False, final_pose=[0.0, 0.0, 0.0], goal=[1.0, 0.0, 0.0],
                          position_error=1.0, orientation_error=0.0, left_workspace=False,
                          segments=segments, full_horizon_plan=False,
                          failure_reason="the world changed around the plan", replans=1,
                          planning_time_s=planning, verify_calls=verify,
                          search_expansions=expansions)
    return ObjectOutcome(result, [planning / max(1, segments)] * segments, 10 * segments,
                         end=end)


@given(st.lists(st.tuples(st.integers(0, 30), st.floats(0.0, 50.0)), min_size=1, max_size=6),
       st.integers(1, 80), st.floats(1.0, 200.0))
def test_each_loop_gets_what_the_others_left_and_the_series_names_its_limit(
        loops, limit, planning_limit) -> None:
    """Against a plain running sum: ``config`` gives max(1, limit - used) segments and
    max(1e-3, limit - spent) s; ``ran_out`` is the first limit reached in the order
    planning, segments, loops, and becomes the last loop's failure reason; the outcome
    sums segments, makespan and planning and counts each extra loop as a replan."""
    series = LoopSeries(limit, planning_limit)
    used = spent = 0.0
    for n, (segments, planning) in enumerate(loops, 1):
        cfg = series.config(PlannerConfig())
        assert cfg.loop.max_segments == max(1, limit - int(used))
        assert cfg.loop.planning_time_limit == max(1e-3, planning_limit - spent)
        series.add(_loop(segments, planning))
        used, spent = used + segments, spent + planning
        why = series.ran_out()
        want = ("planning time limit" if spent >= planning_limit else
                f"segment limit reached ({limit})" if used >= limit else
                f"plan-anew limit reached ({limit} loops)" if n > limit else "")
        assert why == want
        if why:
            assert series.parts[-1].result.failure_reason == why
            break
    out = series.outcome(np.array([0.02, 0.0, 0.0]), np.array([0.0, 0.0, 0.0]))
    assert out.result.segments == used and out.makespan == 10 * used
    assert out.result.replans == 2 * len(series.parts) - 1
    assert out.result.success and out.result.failure_reason == ""  # judged on the true pose
    assert out.end is LoopEnd.WORLD_CHANGED


def test_without_a_planning_limit_only_the_segments_are_shared() -> None:
    series = LoopSeries(5)
    series.add(_loop(3, 1e9, LoopEnd.TEAM_CHANGED))
    cfg = series.config(PlannerConfig.of(planning_time_limit=7.0))
    assert cfg.loop.max_segments == 2 and cfg.loop.planning_time_limit == 7.0
    assert series.ran_out() == ""
    series.add(_loop(2, 0.0, LoopEnd.FINISHED))
    assert series.ran_out() == "segment limit reached (5)"
    assert series.outcome(np.array([3.0, 0.0, 0.0]), np.zeros(3)).end is LoopEnd.FINISHED


def test_the_count_budgets_do_not_shrink_with_the_clock() -> None:
    """Planning time spent (wall clock) shrinks the next loop's time limit, never its
    count budgets, which stay those the base derives from its own limit."""
    base = PlannerConfig.of(planning_time_limit=300.0)
    series = LoopSeries(50, 300.0)
    series.add(_loop(3, 123.4))
    cfg = series.config(base)
    assert cfg.loop.planning_time_limit == pytest.approx(300.0 - 123.4)
    assert cfg.lazy_expansions == base.lazy_expansions == 300_000
    assert cfg.lazy_verify_calls == base.lazy_verify_calls == 24_000
    assert cfg.astar_expansions == base.astar_expansions


@given(st.lists(st.tuples(st.integers(0, 9_000), st.integers(0, 200_000)), min_size=1,
                max_size=5), st.booleans())
def test_the_count_budgets_bound_the_object_not_each_loop(loops, timed) -> None:
    """LAMP-Lazy's per-object Verify budget (``lazy_verify_calls``) is shared by the
    loops: each next loop gets max(1, budget - what the earlier loops counted), with or
    without a planning limit, and the whole expansion budget (each loop searches anew);
    the outcome sums the counts."""
    base = PlannerConfig.of(planning_time_limit=300.0)
    series = LoopSeries(10**6, 300.0 if timed else None)
    verify = expansions = 0
    for v, e in loops:
        cfg = series.config(base)
        assert cfg.lazy_verify_calls == max(1, 24_000 - verify)
        assert cfg.lazy_expansions == 300_000
        series.add(_loop(1, 0.0, verify=v, expansions=e))
        verify, expansions = verify + v, expansions + e
    out = series.outcome(np.zeros(3), np.zeros(3)).result
    assert (out.verify_calls, out.search_expansions) == (verify, expansions)
