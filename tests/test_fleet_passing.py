"""``admission.passes_ahead``: a plan may go through a higher-ranked object's claim when it
passes every point of it, at the same pace, the margin ahead of the claiming object; and
``heeded_claims`` then gives it the near part only."""

from __future__ import annotations

import math

import shapely
from hypothesis import given
from hypothesis import strategies as st

from lamp.fleet.admission import heeded_claims, passes_ahead
from lamp.fleet.state import ObjectState

#: a straight claim along y = 0 from x = 0 to x = 10, 1 m wide; the claimer at x = 0
CLAIMER = shapely.LineString([(0.0, 0.0), (10.0, 0.0)])
CLAIM = CLAIMER.buffer(0.5)
REACH = 0.5


def exit_north(x: float) -> shapely.LineString:
    """A way from (x, 0) straight out of the claim to (x, 3)."""
    return shapely.LineString([(x, 0.0), (x, 3.0)])


def test_a_way_out_far_ahead_of_the_claimer_passes_ahead() -> None:
    # inside 0.5 m; the claimer comes within 0.5 m of it at x = 7.5: 0.5 + 1 <= 7.5
    assert passes_ahead(exit_north(8.0), CLAIM, CLAIMER, REACH, 1.0)


def test_a_way_next_to_the_claimer_does_not() -> None:
    # the claimer is within reach of the part at once
    assert not passes_ahead(exit_north(0.8), CLAIM, CLAIMER, REACH, 1.0)


def test_the_margin_decides_at_the_edge() -> None:
    # inside 0.5 m, the claimer comes within reach at x = 2.5: 0.5 + 2 <= 2.5, not + 2.5
    assert passes_ahead(exit_north(3.0), CLAIM, CLAIMER, REACH, 2.0)
    assert not passes_ahead(exit_north(3.0), CLAIM, CLAIMER, REACH, 2.5)


def test_a_long_way_along_the_claim_towards_the_claimer_does_not() -> None:
    # from x = 8 back along the claim to x = 3, then out: 5.5 m inside, met at x = 2.5
    way = shapely.LineString([(8.0, 0.0), (3.0, 0.0), (3.0, 3.0)])
    assert not passes_ahead(way, CLAIM, CLAIMER, REACH, 1.0)


def test_crossing_ahead_but_not_into_the_claim_nor_without_a_margin() -> None:
    across = shapely.LineString([(8.0, 3.0), (8.0, -3.0)])
    assert passes_ahead(across, CLAIM, CLAIMER, REACH, 1.0)  # inside at 2.5-3.5 m, met at 7.5
    assert not passes_ahead(across, CLAIM, CLAIMER, REACH, 5.0)
    assert not passes_ahead(shapely.LineString([(8.0, 0.0), (9.0, 0.0)]), CLAIM, CLAIMER,
                            REACH, 1.0)  # ends inside
    assert not passes_ahead(exit_north(8.0), CLAIM, CLAIMER, REACH, math.inf)


def test_a_claimer_whose_way_never_comes_near_the_part() -> None:
    claimer = shapely.LineString([(0.0, 0.0), (4.0, 0.0)])
    claim = claimer.buffer(0.5)
    assert passes_ahead(exit_north(4.3), claim, shapely.LineString([(0.0, 0.0), (2.0, 0.0)]),
                        0.1, 1.0)


def reference(x: float, margin: float) -> bool | None:
    """``passes_ahead`` of ``exit_north(x)`` worked out by hand: the way's points at y =
    0, 0.1, ... (those with y <= 0.5 inside the claim, passed after y m) against the
    claimer's points at a = 0, 0.1, ..., 10 (the first within ``REACH`` of (x, y) is when
    it comes); None where a comparison is a tie (rounding decides it)."""
    ys = [i / 10 for i in range(6)]
    grid = [i / 10 for i in range(101)]
    out = True
    for y in ys:
        comes = next((a for a in grid if math.hypot(a - x, y) <= REACH), math.inf)
        if abs(y + margin - comes) < 1e-9:
            return None
        out &= y + margin <= comes
    return out


@given(x=st.floats(0.0, 9.9), ahead=st.floats(0.0, 5.0), margin=st.floats(0.0, 5.0),
       less=st.floats(0.0, 5.0))
def test_passing_ahead_against_a_hand_reference(x, ahead, margin, less) -> None:
    """As the reference says; and monotone, as the rule means: the way's exit farther
    along the claimer's way, or a smaller margin, keeps a way that passes ahead passing
    ahead."""
    got = passes_ahead(exit_north(x), CLAIM, CLAIMER, REACH, margin)
    if (want := reference(x, margin)) is not None:
        assert got == want
    if got:
        assert passes_ahead(exit_north(min(9.9, x + ahead)), CLAIM, CLAIMER, REACH, margin)
        assert passes_ahead(exit_north(x), CLAIM, CLAIMER, REACH, max(0.0, margin - less))


def test_going_the_same_way_ahead_of_the_claimer() -> None:
    """Ahead on the claimer's way and going its way, out at the far end: it passes ahead
    when the gap exceeds the reach and the margin, whatever the length it runs inside."""
    way = shapely.LineString([(4.0, 0.0), (9.5, 0.0), (9.5, 3.0)])
    assert passes_ahead(way, CLAIM, CLAIMER, REACH, 1.0)  # 4 m ahead: 4 - 0.5 >= 1
    way = shapely.LineString([(1.2, 0.0), (9.5, 0.0), (9.5, 3.0)])
    assert not passes_ahead(way, CLAIM, CLAIMER, REACH, 1.0)  # 1.2 m: 0.7 < 1


def test_heeded_claims_gives_an_object_passing_ahead_the_near_part_only() -> None:
    near = shapely.box(0.0, -0.5, 2.0, 0.5)
    claimer = ObjectState(0, status="active", rank=0, claim=CLAIM, near=near, way=CLAIMER)
    me = ObjectState(1, status="active", rank=1, way=exit_north(8.0))
    heeded = heeded_claims([claimer, me], me, 0.0, 0.0, [0.25, 0.25], 1.0)
    assert heeded == [(0, near, near)]
    stays = heeded_claims([claimer, me], me, 0.0, 0.0, [0.25, 0.25], math.inf)
    assert stays == [(0, CLAIM, CLAIM)]
    me.way = exit_north(0.8)
    assert heeded_claims([claimer, me], me, 0.0, 0.0, [0.25, 0.25], 1.0) == [
        (0, CLAIM, CLAIM)]

