"""The fleet's object status machine (``lamp.fleet.state``) against its table of moves, and
the contracts that replaced run-time probing of executors."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from lamp.contract.runner import ALONE, LoopEnd, LoopHooks
from lamp.fleet.state import TRANSITIONS, IllegalTransition, ObjectState, ObjectStatus

SRC = Path(__file__).resolve().parents[1] / "src" / "lamp"


@given(st.lists(st.sampled_from(list(ObjectStatus)), max_size=8))
def test_every_move_follows_the_table_or_raises_and_changes_nothing(moves) -> None:
    """A reference walk over ``TRANSITIONS``: each move is allowed exactly when the table
    says so; an illegal one raises ``IllegalTransition`` and leaves the status as it was."""
    o = ObjectState(0)
    want = ObjectStatus.WAITING
    for m in moves:
        if m in TRANSITIONS[want]:
            o.move_to(m)
            want = m
        else:
            with pytest.raises(IllegalTransition, match="object 0"):
                o.move_to(m)
        assert o.status is want


def test_the_table_is_the_schedule_s_life_cycle() -> None:
    """waiting -> active -> placed | failed; waiting -> failed (given up); placed or
    failed -> waiting only (its next task), and only those two are done."""
    W, A, P, F = (ObjectStatus.WAITING, ObjectStatus.ACTIVE, ObjectStatus.PLACED,
                  ObjectStatus.FAILED)
    assert dict(TRANSITIONS) == {W: {A, F}, A: {P, F}, P: {W}, F: {W}}
    assert [s.done for s in (W, A, P, F)] == [False, False, True, True]


def test_resume_ends_a_wait_and_sets_the_answer() -> None:
    o = ObjectState(3, blocked_at=(1, 2))
    assert o.held_up
    o.resume(replan=False)
    assert o.blocked_at is None and o.ready and o.replan is False and not o.held_up
    o.resume()
    assert o.replan is True


def test_a_loop_alone_is_told_nothing_and_asks_nothing() -> None:
    """``ALONE``: the team never changes, a failed plan is the planner's to handle, and
    announcing a segment has no effect."""
    import numpy as np

    assert ALONE.team_changed() is False and ALONE.plan_failed() is False
    assert ALONE.announce(np.zeros((2, 3)), np.zeros((0, 3))) is None
    seen = []
    hooks = LoopHooks(plan_failed=lambda: seen.append(1) or True)
    assert hooks.plan_failed() and seen == [1] and not hooks.team_changed()
    assert {e.value for e in LoopEnd} == {"finished", "no plan", "world changed",
                                          "team changed"}


#: Executor abilities that once were probed by name.
PROBED = {"announce", "plan_failed", "team_changed", "failed", "true_object_poses",
          "declined", "stopped_at", "objects_left"}


def test_no_module_probes_an_executor_s_abilities_by_name() -> None:
    """The executor's abilities are contracts (``WorldExecutor``, ``Execution``,
    ``LoopHooks``), not found at run time: no ``getattr``/``hasattr`` names one."""
    bad = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id in ("getattr", "hasattr") and len(node.args) >= 2
                    and isinstance(node.args[1], ast.Constant) and node.args[1].value in PROBED):
                bad.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert bad == []


@given(st.lists(st.tuples(st.integers(0, 3), st.sampled_from(["running", "claim"]),
                          st.integers(0, 3), st.booleans()), max_size=40))
def test_waits_count_every_meets_note_by_object_and_reason(notes) -> None:
    """``FleetStats.report``'s ``waits``: per object, each "meets" reason noted and how
    often, most frequent first; other notes are not counted."""
    from collections import Counter
    from types import SimpleNamespace

    from lamp.fleet.stats import FleetStats

    stats = FleetStats(2)
    expect = [Counter() for _ in range(4)]
    for k, kind, j, meets in notes:
        stats.note(1.0, "meets" if meets else "handed", k, f"{kind} {j}")
        if meets:
            expect[k][f"{kind} {j}"] += 1
    objects = [SimpleNamespace(index=k, placed_at_s=None) for k in range(4)]
    waits = stats.report(objects, {}, 1.0)["waits"]  # type: ignore[arg-type]
    assert [Counter(w) for w in waits] == expect
    for w in waits:
        assert list(w.values()) == sorted(w.values(), reverse=True)


def test_every_count_the_schedule_makes_is_one_it_reports() -> None:
    """Each ``stats.count("name")`` in ``lamp.fleet`` names one of ``COUNTS`` (a name not
    there raises ``KeyError`` in the middle of a run, on the first event that counts it)."""
    from lamp.fleet.stats import COUNTS

    named = set()
    for path in (SRC / "fleet").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr == "count" and node.args
                    and isinstance(node.args[0], ast.Constant)
                    and isinstance(node.args[0].value, str)):
                named.add((path.name, node.args[0].value))
    assert {"halted", "jammed", "blocked"} <= {n for _, n in named}  # the walk finds them
    assert {(f, n) for f, n in named if n not in COUNTS} == set()
