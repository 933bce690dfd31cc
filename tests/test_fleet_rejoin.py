"""``Segment.rejoin``, its slack (``fleet_rejoin_slack``) and its limit
(``fleet_rejoin_limit``): robots off their rows move straight back to them; a segment
whose robots' moves back would take more than the slack's share of its planned rows, or
(with a limit) that had to rejoin that many times (they push what does not give, and
every event set them back), ends there, so its loop sees the stall and plans anew
(``Fleet._advance``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fleet_fakes import fleet_at_starts
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.fleet.config import REJOIN_SLACK
from lamp.fleet.segments import REJOIN_GAP, Segment
from lamp.fleet.state import ObjectStatus
from lamp.scene import scene_from_dict
from lamp.scene.model import Rectangle

BOX = Rectangle((0.4, 0.3))
LIMIT = 10
R = 0.1


def _segment(start=(0.0, 0.0), n: int = 20) -> Segment:
    """One robot's segment: 0.02 m rows along x from ``start``."""
    rows = np.array(start, float) + np.outer(0.02 * np.arange(1, n + 1), [1.0, 0.0])
    return Segment(0, [0], rows[None], np.array([[1.0, 1.0, 0.0]] * 2), None, BOX, R)


def test_a_robot_within_the_gap_keeps_its_rows() -> None:
    seg = _segment()
    rows = seg.rows.copy()
    seg.rejoin(np.array([[0.02, REJOIN_GAP * 0.9]]), 0.02)
    np.testing.assert_array_equal(seg.rows, rows)
    assert seg.rejoined == 0 and not seg.done


def test_a_nudged_robot_moves_straight_back_to_its_next_row() -> None:
    seg = _segment()
    seg.cursor = 5
    nxt = seg.rows[0, 5].copy()
    seg.rejoin(np.array([nxt + [0.0, 0.1]]), 0.02)
    steps = np.hypot(*np.diff(np.vstack([nxt + [0.0, 0.1], seg.rows[0]]), axis=0).T)
    assert seg.cursor == 0 and seg.rejoined == 1 and not seg.done
    assert steps.max() <= 0.02 + 1e-9  # paced at the row step, back onto the old rows
    np.testing.assert_allclose(seg.rows[0, -15:], _segment().rows[0, 5:])


def test_the_limit_th_rejoin_ends_the_segment_where_it_stands() -> None:
    seg = _segment(n=200)
    for i in range(1, LIMIT):
        seg.rejoin(seg.rows[:, seg.cursor] + [0.0, 0.1], 0.02, LIMIT)
        assert seg.rejoined == i and not seg.done
        seg.cursor += 2  # a little progress, then held back again
    rows = seg.rows.copy()
    seg.rejoin(seg.rows[:, seg.cursor] + [0.0, 0.1], 0.02, LIMIT)
    assert seg.done and seg.stopped_at is not None
    np.testing.assert_array_equal(seg.rows, rows)


def test_without_a_limit_or_a_slack_it_rejoins_for_ever() -> None:
    seg = _segment(n=20)
    for i in range(1, 3 * LIMIT):
        seg.rejoin(seg.rows[:, seg.cursor] + [0.0, 0.1], 0.02, 0, math.inf)
        assert seg.rejoined == i and not seg.done
    assert seg.added > seg.planned


def test_the_rejoin_past_the_slack_ends_the_segment_where_it_stands() -> None:
    """The default slack: rows inserted up to the planned rows go, the next move back
    that would take them past it ends the segment, its rows as they were."""
    seg = _segment(n=20)
    back = 6  # rows to move 0.1 m back at 0.02 m a row, the robot's own row included
    for i in range(1, int(REJOIN_SLACK * seg.planned) // back + 1):
        seg.rejoin(seg.rows[:, seg.cursor] + [0.0, 0.1], 0.02)
        assert not seg.done and seg.added == i * back
    rows = seg.rows.copy()
    seg.rejoin(seg.rows[:, seg.cursor] + [0.0, 0.1], 0.02)
    assert seg.done and seg.stopped_at is not None and seg.added <= REJOIN_SLACK * seg.planned
    np.testing.assert_array_equal(seg.rows, rows)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 40), slack=st.floats(0.0, 3.0),
       events=st.lists(st.tuples(st.floats(0.0, 0.3), st.floats(-math.pi, math.pi),
                                 st.integers(1, 30)), min_size=1, max_size=400))
def test_a_segment_held_back_ends_within_its_slack(n: int, slack: float,
                                                    events: list[tuple[float, float, int]]
                                                    ) -> None:
    """Whatever sets the robot back at each event (a gap in any direction) and however
    few rows each event runs (at least one), ``added`` never passes ``slack * planned``
    and the segment is done within ``(1 + slack) * planned`` events."""
    seg = _segment(n=n)
    ran = 0
    for gap, angle, rows in events * 50:
        if seg.done:
            break
        seg.rejoin(seg.rows[:, seg.cursor] + gap * np.array([math.cos(angle), math.sin(angle)]),
                   0.02, 0, slack)
        assert seg.added <= slack * seg.planned
        if seg.done:
            break
        seg.cursor += min(rows, seg.remaining)
        ran += 1
    assert seg.done
    assert ran <= (1 + slack) * seg.planned


@pytest.mark.parametrize("limit, slack", [(LIMIT, math.inf), (0, 0.5)])
def test_the_fleet_hands_a_segment_ended_so_back_to_its_loop_stopped(limit: int,
                                                                     slack: float) -> None:
    """By the limit or by the slack, nothing runs in that event: the loop gets its reply
    (stopped, like a push the watch stopped) and goes on."""
    scene = scene_from_dict({
        "format": "lamp-scene/1", "name": "rejoin", "workspace": [4.0, 3.0],
        "robots": {"starts": [[0.5, 0.5], [0.5, 1.0]]},
        "objects": [{"type": "rectangle", "size": [0.4, 0.3], "start": [2.0, 1.5, 0.0],
                     "goal": [3.0, 1.5, 0.0]}]})
    fleet = fleet_at_starts(scene, rejoin_limit=limit, rejoin_slack=slack)
    o = fleet.objects[0]
    o.status, o.team, o.rank = ObjectStatus.ACTIVE, [0], 0
    seg = _segment(start=(0.5, 0.7))  # its next row 0.22 m from the robot at (0.5, 0.5)
    seg.rejoined = limit - 1  # the limit-th rejoin; or 12 rows back, over half of 20
    o.running = seg
    fleet._advance()
    assert o.running is None and o.ready
    assert o.reply is not None and o.reply.stopped_at is not None
    assert fleet.clock == 0.0 and fleet.stats.counts["events"] == 0 and fleet.stats.counts["jammed"] == 1
