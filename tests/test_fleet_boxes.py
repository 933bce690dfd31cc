"""Admission's box tests (``spacetime.apart``): every answer found from two boxes is the
answer the full test gives (``compatible``, ``meets_moving``, ``meets_standing``,
``passes_ahead``), on random segments from touching to far apart."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lamp.fleet import admission, spacetime
from lamp.fleet.admission import (
    ends_box,
    heeded_claims,
    meets_moving,
    meets_standing,
    passes_ahead,
)
from lamp.fleet.regions import claims
from lamp.fleet.segments import Segment
from lamp.fleet.spacetime import apart, compatible, reach_box
from lamp.fleet.state import ObjectState, ObjectStatus
from lamp.scene import scene_from_dict
from lamp.scene.model import Rectangle

R = 0.05
BOX = Rectangle((0.3, 0.2))


def _segment(rng, index: int, centre) -> Segment:
    n = int(rng.integers(1, 4))
    start = np.asarray(centre) + rng.uniform(-0.6, 0.6, (n, 2))
    end = start + rng.uniform(-0.8, 0.8, (n, 2))
    t = int(rng.integers(2, 30))
    rows = start[:, None] + (end - start)[:, None] * np.linspace(0, 1, t)[None, :, None]
    q0 = np.r_[np.asarray(centre) + rng.uniform(-0.3, 0.3, 2), rng.uniform(-3, 3)]
    q1 = q0 + np.r_[rng.uniform(-0.4, 0.4, 2), rng.uniform(-0.5, 0.5)]
    cursor = int(rng.integers(0, t)) if index == 0 else 0
    return Segment(index, list(range(n)), rows, np.array([q0, q1]), None, BOX, R, cursor=cursor)


def _without_boxes(monkeypatch: pytest.MonkeyPatch, fn, *args):
    """``fn(*args)`` with every box test answering "not apart" (the full tests run)."""
    with monkeypatch.context() as m:
        m.setattr(spacetime, "apart", lambda *a: False)
        m.setattr(admission, "apart", lambda *a: False)
        return fn(*args)


def test_apart_is_a_gap_along_an_axis() -> None:
    a = np.array([0.0, 0.0, 1.0, 1.0])
    assert apart(a, np.array([1.2, 0.0, 2.0, 1.0]), 0.1)
    assert not apart(a, np.array([1.2, 0.0, 2.0, 1.0]), 0.2)
    assert apart(a, np.array([0.0, -2.0, 1.0, -0.5]), 0.4)
    assert not apart(a, np.array([0.5, 0.5, 2.0, 2.0]), 0.0)


@settings(max_examples=120, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 4.0))
def test_box_answers_are_the_full_tests_answers(monkeypatch, seed, gap) -> None:
    rng = np.random.default_rng(seed)
    a = _segment(rng, 0, (0.0, 0.0))
    b = _segment(rng, 1, (gap, 0.3 * gap))
    for s in (a, b):  # the box holds every row left and every object space
        box = reach_box(s)
        rows = s.rows[:, s.cursor:].reshape(-1, 2)
        assert np.all(rows >= box[:2] - 1e-12) and np.all(rows <= box[2:] + 1e-12)
    assert compatible(a, b) == _without_boxes(monkeypatch, compatible, a, b)
    assert compatible(b, a) == _without_boxes(monkeypatch, compatible, b, a)

    plan = np.array([[gap, 1.0, 0.0], [gap + 0.8, 1.2, 0.3], [gap + 1.5, 0.4, 0.5]])
    full, near, way = claims(BOX, plan, [gap + 2.0, 0.0, 0.0], R)
    higher = [(2, full, near)]
    mine = shapely.LineString(np.vstack([b.poses[:, :2], [[gap + 3.0, -1.0]]]))
    for args in ((b, [], higher, mine), (b, [], higher), (b, [a], higher, mine)):
        assert meets_moving(*args) == _without_boxes(monkeypatch, meets_moving, *args)
    for w in (mine, way):
        args = (w, full, way, 0.6, 1.0)
        assert passes_ahead(*args) == _without_boxes(monkeypatch, passes_ahead, *args)

    robots = np.vstack([rng.uniform(-1.0, 1.0 + gap, (8, 2)), [[15.0, 15.0]]])
    scene = scene_from_dict({
        "format": "lamp-scene/1", "name": "boxes", "workspace": [20.0, 20.0],
        "robots": {"radius": R, "starts": [[1.0 + 0.2 * i, 15.0] for i in range(9)]}, "obstacles": [],
        "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [5.0 + k, 1.0, 0.0],
                     "goal": [5.0 + k, 3.0, 0.0]} for k in range(3)]})
    poses = np.c_[rng.uniform(-0.5, 0.5 + gap, (3, 2)), rng.uniform(-3, 3, 3)]
    moving = {int(i) for i in rng.choice(9, size=int(rng.integers(0, 4)), replace=False)}
    args = (b, scene, poses, robots, [0, 1, 2], moving)
    assert meets_standing(*args) == _without_boxes(monkeypatch, meets_standing, *args)


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 6.0), st.floats(0.5, 3.0))
def test_claims_missing_the_segments_box_give_the_same_admission(seed, gap, margin) -> None:
    """``heeded_claims(box=ends_box(seg))`` gives claims far from the segment whole
    without asking ``passes_ahead``; ``meets_moving`` answers as with every claim's own
    part (near where the segment's object passes ahead)."""
    rng = np.random.default_rng(seed)
    seg = _segment(rng, 1, (0.0, 0.0))
    plan = np.array([[gap, 1.0, 0.0], [gap + 0.8, 1.2, 0.3], [gap + 1.5, 0.4, 0.5]])
    full, near, way = claims(BOX, plan, [gap + 2.0, 0.0, 0.0], R)
    claimer = ObjectState(0, status=ObjectStatus.ACTIVE, rank=0, claim=full, near=near,
                          way=way)
    mine = shapely.LineString(np.vstack([seg.poses[:, :2], [[gap + 3.0, -1.0]]]))
    me = ObjectState(1, status=ObjectStatus.ACTIVE, rank=1, way=mine)
    args = ([claimer, me], me, 0.0, 0.0, [0.3, 0.3], margin)
    boxed = heeded_claims(*args, box=ends_box(seg))
    plain = heeded_claims(*args)
    assert meets_moving(seg, [], boxed, mine) == meets_moving(seg, [], plain, mine)
    if apart(ends_box(seg), np.asarray(full.bounds, float), 0.0):
        assert boxed == [(0, full, full)]
    else:
        assert boxed == plain


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_a_segments_ends_are_kept_with_their_rows(seed) -> None:
    """``Segment.ends`` is asked at every event a segment waits: the second answer is the
    first (kept), and once its rows are replaced (a rejoin) it is the new rows' ends, as
    built from scratch."""
    from lamp.fleet.regions import swept

    rng = np.random.default_rng(seed)
    seg = _segment(rng, 1, (1.0, 1.0))
    first = seg.ends()
    assert seg.ends() is first
    seg.rows = seg.rows + rng.uniform(-0.2, 0.2, (seg.rows.shape[0], 1, 2))
    again = seg.ends()
    want = (swept(BOX, seg.poses[:1], seg.rows[:, :1], R),
            swept(BOX, seg.poses[-1:], seg.rows[:, -1:], R))
    assert again is not first
    assert all(a.equals(b) for a, b in zip(again, want, strict=True))
