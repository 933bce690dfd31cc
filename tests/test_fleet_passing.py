"""``admission.passes_ahead``: a plan may go through a higher-ranked object's claim when it
passes every point of it, at the same pace, the margin ahead of the claiming object, or
leave a claim it stands in by its way; never towards the claiming object (head-on); and
``heeded_claims`` then gives it the near part only."""

from __future__ import annotations

import math

import shapely
from hypothesis import given
from hypothesis import strategies as st

from lamp.fleet.admission import heeded_claims, passes_ahead
from lamp.fleet.state import ObjectState, ObjectStatus

#: a straight claim along y = 0 from x = 0 to x = 10, 1 m wide; the claimer at x = 0
CLAIMER = shapely.LineString([(0.0, 0.0), (10.0, 0.0)])
CLAIM = CLAIMER.buffer(0.5)
REACH = 0.5


def across(x: float) -> shapely.LineString:
    """A way from (x, -3) straight across the claim to (x, 3): inside from 2.5 to 3.5 m."""
    return shapely.LineString([(x, -3.0), (x, 3.0)])


def line(*points: tuple[float, float]) -> shapely.LineString:
    return shapely.LineString(points)


def test_crossing_far_ahead_of_the_claimer_passes_ahead() -> None:
    # inside until 3.5 m of travel; the claimer comes within 0.5 m at about x - 0.5
    assert passes_ahead(across(8.0), CLAIM, CLAIMER, REACH, 1.0)


def test_crossing_just_ahead_of_the_claimer_does_not() -> None:
    assert not passes_ahead(across(2.0), CLAIM, CLAIMER, REACH, 1.0)


def test_the_margin_decides_at_the_edge() -> None:
    # at x = 6 the way is 2.5 m of travel ahead at every point inside (rounded to 0.1 m)
    assert passes_ahead(across(6.0), CLAIM, CLAIMER, REACH, 2.0)
    assert not passes_ahead(across(6.0), CLAIM, CLAIMER, REACH, 3.0)


def test_standing_in_the_claim_it_leaves_by_its_way_whatever_the_gap() -> None:
    out = line((0.8, 0.0), (0.8, 3.0))  # beside the claimer, out sideways
    assert passes_ahead(out, CLAIM, CLAIMER, REACH, 1.0)
    assert not passes_ahead(out, CLAIM, CLAIMER, REACH, math.inf)  # off


def test_never_towards_the_claimer() -> None:
    """Head-on: standing in the claim, or coming in far ahead, running along it towards
    the claimer before leaving: no."""
    assert not passes_ahead(line((8.0, 0.0), (3.0, 0.0), (3.0, 3.0)), CLAIM, CLAIMER,
                            REACH, 1.0)
    assert not passes_ahead(line((9.5, 3.0), (9.5, 0.0), (8.0, 0.0), (8.0, 3.0)), CLAIM,
                            CLAIMER, REACH, 0.0)


def test_going_the_same_way_ahead_of_the_claimer() -> None:
    """In ahead on the claimer's way, along it and out at the far end: it passes ahead
    when it comes in far enough ahead."""
    assert passes_ahead(line((6.0, -1.0), (6.0, 0.0), (9.5, 0.0), (9.5, 3.0)), CLAIM,
                        CLAIMER, REACH, 1.0)
    assert not passes_ahead(line((2.0, -1.0), (2.0, 0.0), (9.5, 0.0), (9.5, 3.0)), CLAIM,
                            CLAIMER, REACH, 1.0)


def test_not_beside_the_claim_nor_into_it() -> None:
    assert not passes_ahead(line((8.0, 1.0), (8.0, 3.0)), CLAIM, CLAIMER, REACH, 1.0)
    assert not passes_ahead(line((8.0, 3.0), (8.0, 0.0)), CLAIM, CLAIMER, REACH, 1.0)


def reference(x: float, margin: float) -> bool | None:
    """``passes_ahead`` of ``across(x)`` worked out by hand: its points 0.1 m apart (those
    within 0.5 m of y = 0 inside the claim, reached after their distance from (x, -3))
    against the claimer's points 0.1 m apart from x = 0 (the first within ``REACH`` of a
    point is when the claimer comes to it); None where a comparison is a tie."""
    grid = [i / 10 for i in range(101)]
    out = True
    for i in range(61):
        s, y = i / 10, i / 10 - 3.0
        if abs(abs(y) - 0.5) < 1e-6:
            return None  # on the claim's edge
        if abs(y) > 0.5:
            continue
        comes = next((a for a in grid if math.hypot(a - x, y) <= REACH), math.inf)
        if abs(s + margin - comes) < 1e-6:
            return None
        out &= s + margin <= comes
    return out


@given(x=st.floats(1.0, 9.0), ahead=st.floats(0.0, 5.0), margin=st.floats(0.0, 5.0),
       less=st.floats(0.0, 5.0))
def test_passing_ahead_against_a_hand_reference(x, ahead, margin, less) -> None:
    """As the reference says; and monotone, as the rule means: the crossing farther along
    the claimer's way, or a smaller margin, keeps a way that passes ahead passing."""
    got = passes_ahead(across(x), CLAIM, CLAIMER, REACH, margin)
    if (want := reference(x, margin)) is not None:
        assert got == want
    if got:
        assert passes_ahead(across(min(9.0, x + ahead)), CLAIM, CLAIMER, REACH, margin)
        assert passes_ahead(across(x), CLAIM, CLAIMER, REACH, max(0.0, margin - less))


def test_heeded_claims_gives_an_object_passing_ahead_the_near_part_only() -> None:
    near = shapely.box(0.0, -0.5, 2.0, 0.5)
    claimer = ObjectState(0, status=ObjectStatus.ACTIVE, rank=0, claim=CLAIM, near=near, way=CLAIMER)
    me = ObjectState(1, status=ObjectStatus.ACTIVE, rank=1, way=across(8.0))
    heeded = heeded_claims([claimer, me], me, 0.0, 0.0, [0.25, 0.25], 1.0)
    assert heeded == [(0, near, near)]
    stays = heeded_claims([claimer, me], me, 0.0, 0.0, [0.25, 0.25], math.inf)
    assert stays == [(0, CLAIM, CLAIM)]
    me.way = across(2.0)
    assert heeded_claims([claimer, me], me, 0.0, 0.0, [0.25, 0.25], 1.0) == [
        (0, CLAIM, CLAIM)]


@given(xs=st.lists(st.floats(0.5, 9.5), min_size=1, max_size=12),
       margin=st.floats(0.0, 4.0))
def test_heeded_claims_remembers_the_same_answers(xs, margin) -> None:
    """With a memo kept across calls (the fleet's), ``heeded_claims`` answers every
    crossing as it does without one: the remembered answers and ways' points are the
    ones ``passes_ahead`` finds afresh."""
    near = shapely.box(0.0, -0.5, 2.0, 0.5)
    claimer = ObjectState(0, status=ObjectStatus.ACTIVE, rank=0, claim=CLAIM, near=near, way=CLAIMER)
    memo: dict = {}
    ways = [across(x) for x in xs]
    for way in ways + ways:  # each way twice: the second time from the memo
        me = ObjectState(1, status=ObjectStatus.ACTIVE, rank=1, way=way)
        args = ([claimer, me], me, 0.0, 0.0, [0.25, 0.25], margin)
        assert heeded_claims(*args, memo=memo) == heeded_claims(*args)
