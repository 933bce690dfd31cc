"""Long pushes (``lamp.planners.long_push``): what runs as one segment, and that merging
changes nothing about what the robots execute."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp import solve
from lamp.contract.trajectory import concat, straight_moves
from lamp.contract.transition import Transition
from lamp.geometry import se2
from lamp.planners.config import PlannerConfig
from lamp.planners.long_push import approach_travel, continues, merge, take_long_push
from lamp.suites.registry import suite_scenes


def _push(q_from, step, robots, move_to=None) -> Transition:
    """Two robots push a box by ``step`` (dx, dy); a third stands by. ``move_to``: where
    the approach takes the robots first (default: nowhere, they are in place)."""
    q_from = np.asarray(q_from, float)
    q_to = q_from + np.array([*step, 0.0])
    start = np.asarray(robots, float)
    ends = start if move_to is None else np.asarray(move_to, float)
    move = straight_moves(start, ends)
    shift = np.zeros_like(ends)
    shift[:2] = step
    manip = straight_moves(ends, ends + shift)
    contacts = ends[:2].copy()
    pushes_local = se2.inverse_transform_points(q_from, manip[:2])
    return Transition(q_from, q_to, contacts, pushes_local, move, manip, edge=(0, 1))


ROBOTS = np.array([[0.5, 0.9], [0.5, 1.1], [0.2, 0.2]])


def _chain(n: int, step=(0.1, 0.0)) -> list[Transition]:
    out, q, r = [], np.array([0.75, 1.0, 0.0]), ROBOTS.copy()
    for _ in range(n):
        t = _push(q, step, r)
        out.append(t)
        q, r = t.q_to, t.robot_end
    return out


def test_continues_needs_the_same_formation():
    a, b = _chain(2)
    assert continues(a, b, 0.02)
    # an approach that moves a robot 5 cm is a re-approach
    moved = b.robot_start.copy()
    moved[0] += [0.0, -0.05]
    c = _push(b.q_from, (0.1, 0.0), b.robot_start, move_to=moved)
    assert approach_travel(c) > 0.049 and not continues(a, c, 0.02)
    assert continues(a, c, 0.06)
    # a transition that does not start where the last one ended cannot continue it
    d = _push(b.q_from, (0.1, 0.0), b.robot_start + [0.0, 0.001])
    assert not continues(a, d, 0.02)


@settings(max_examples=25, deadline=None)
@given(n=st.integers(1, 6), dx=st.floats(-0.2, 0.2), dy=st.floats(-0.2, 0.2))
def test_merge_executes_exactly_the_parts(n, dx, dy):
    chain = _chain(n, (dx, dy))
    merged = merge(chain)
    assert np.array_equal(merged.robot_paths, concat(*[t.robot_paths for t in chain]))
    assert np.array_equal(merged.q_from, chain[0].q_from)
    assert np.array_equal(merged.q_to, chain[-1].q_to)
    # the push paths, in the first pose's frame, are the pushers' merged paths
    world = se2.transform_points(merged.q_from, merged.pushes_local)
    assert np.allclose(world, merged.manip[:2])
    assert np.allclose(merged.pushes_local[:, 0], se2.inverse_transform_points(
        merged.q_from, merged.contacts))


def test_take_long_push_stops_at_the_length_and_the_formation():
    chain = _chain(8)  # 8 x 0.1 m
    pending = chain[1:]
    taken = take_long_push(chain[0], pending, 0.02, 0.5)
    assert len(taken) == 5 and len(pending) == 3  # 0.5 m of planned motion
    moved = pending[0].robot_start.copy()
    moved[1] += [0.0, 0.05]
    pending[0] = _push(pending[0].q_from, (0.1, 0.0), pending[0].robot_start, move_to=moved)
    assert take_long_push(chain[5], pending, 0.02, 5.0) == [chain[5]]


def _turns(n: int, dtheta: float) -> list[Transition]:
    """``n`` turns in place by ``dtheta`` each, two robots on the box's corners."""
    out, q, r = [], np.array([0.75, 1.0, 0.0]), ROBOTS.copy()
    for _ in range(n):
        q_to = q + np.array([0.0, 0.0, dtheta])
        c, s = np.cos(dtheta), np.sin(dtheta)
        ends = r.copy()
        ends[:2] = q[:2] + (r[:2] - q[:2]) @ np.array([[c, s], [-s, c]])
        manip = straight_moves(r, ends)
        t = Transition(q, q_to, r[:2].copy(), se2.inverse_transform_points(q, manip[:2]),
                       straight_moves(r, r), manip, edge=(0, 1))
        out.append(t)
        q, r = t.q_to, t.robot_end
    return out


@settings(max_examples=25, deadline=None)
@given(n=st.integers(1, 6), dtheta=st.floats(-0.8, 0.8).filter(lambda v: abs(v) > 1e-3),
       max_turn=st.floats(0.0, 2.0))
def test_take_long_push_bounds_the_summed_turn(n, dtheta, max_turn):
    """A turn in place moves the origin by nothing: the length bound alone would take
    every turn; the turn bound takes the longest head whose summed |turn| fits (at least
    the first)."""
    chain = _turns(n, dtheta)
    assert all(continues(a, b, 0.02) for a, b in zip(chain, chain[1:], strict=False))
    pending = chain[1:]
    taken = take_long_push(chain[0], pending, 0.02, 1.0, max_turn)
    fits = max(1, min(n, int((max_turn + 1e-9) // abs(dtheta))))
    assert len(taken) == fits and len(pending) == n - fits
    assert len(take_long_push(chain[0], chain[1:], 0.02, 1.0)) == n  # no turn bound


def test_long_pushes_mean_fewer_segments_on_a_suite_scene():
    scene = next(iter(suite_scenes("random")))
    whole = solve(scene, "lazy", 0, model="geometric")
    single = solve(scene, "lazy", 0, model="geometric",
                   config=PlannerConfig.of(long_push_length=0.0))
    assert whole.success and single.success
    assert whole.segments < single.segments
