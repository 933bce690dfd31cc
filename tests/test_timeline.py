"""The fleet timeline (``lamp.viz.timeline``): a robot's spans tile the recorded time, each
sample interval lies in a span of its own kind (against a per-interval reference), and
neighbouring spans differ."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.viz.timeline import IDLE, MOVING_FRACTION, robot_spans

SPEED = 0.25


def _reference_kind(times, positions, team, j, i):
    """The kind of sample interval j of robot i, computed on its own."""
    who = int(team[j + 1, i])
    if who < 0:
        return IDLE, False
    step = float(np.hypot(*(positions[j + 1, i] - positions[j, i])))
    return who, step > MOVING_FRACTION * SPEED * (times[j + 1] - times[j])


@settings(max_examples=120, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 40), st.integers(1, 4))
def test_spans_tile_the_time_and_match_every_interval(seed, samples, robots) -> None:
    rng = np.random.default_rng(seed)
    dt = rng.choice([0.0, 0.08, 0.08, 0.3], samples)  # some repeated sample times
    times = np.r_[0.0, np.cumsum(dt)] + rng.uniform(0, 10)
    positions = np.cumsum(rng.choice([0.0, 0.0, 0.002, 0.02], (samples + 1, robots, 2)),
                          axis=0)
    team = rng.integers(-1, 3, (samples + 1, robots))
    team = np.where(rng.random(team.shape) < 0.6, np.roll(team, 1, axis=0), team)
    spans = robot_spans(times, positions, team, SPEED)
    assert len(spans) == robots
    positive = np.flatnonzero(np.diff(times) > 0)
    for i, row in enumerate(spans):
        if len(positive) == 0:
            assert row == []
            continue
        assert row[0].start == times[0] and row[-1].end == times[-1]
        for a, b in zip(row[:-1], row[1:], strict=True):
            assert a.end == b.start and a.start < a.end
            assert (a.object, a.moving) != (b.object, b.moving)  # maximal spans
        for j in positive:
            inside = [s for s in row if s.start <= times[j] and times[j + 1] <= s.end]
            assert len(inside) == 1
            assert (inside[0].object, inside[0].moving) == _reference_kind(
                times, positions, team, j, i)


def test_an_idle_robot_is_idle_even_when_shoved() -> None:
    times = np.array([0.0, 1.0, 2.0])
    positions = np.array([[[0, 0]], [[0.5, 0]], [[0.5, 0]]], float)
    spans = robot_spans(times, positions, np.array([[-1], [-1], [2]]), SPEED)
    assert [(s.object, s.moving) for s in spans[0]] == [(IDLE, False), (2, False)]
