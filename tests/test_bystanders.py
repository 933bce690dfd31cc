"""Bystanders (``lamp.planners.bystanders``): robots left out of an approach hold still far
outside the window the others plan in; and Verify with one robot of the team 25 m away
routes only the robots near the object, in a window of their size."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.manip import GeometricProposer
from lamp.planners.bystanders import bystanders, standing_on_goal
from lamp.planners.config import PlannerConfig
from lamp.planners.task import ManipulationTask
from lamp.scene.model import Obstacle, Rectangle, Scene, SceneObject


def bbox_window(margin: float):
    """A window like ``ManipulationTask.window``: the points' box grown by ``margin``
    around a fixed object at (5, 5)."""
    def window_of(points: np.ndarray) -> tuple[float, float, float, float]:
        pts = np.vstack([np.asarray(points, float).reshape(-1, 2), [[5.0, 5.0]]])
        lo, hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
    return window_of


def box_distance(window, p) -> float:
    x0, y0, x1, y1 = window
    return float(np.hypot(max(x0 - p[0], 0.0, p[0] - x1), max(y0 - p[1], 0.0, p[1] - y1)))


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 12), st.floats(0.1, 2.0), st.floats(0.05, 1.0), st.integers(0, 2**31 - 1))
def test_bystanders_hold_outside_the_movers_window(n, margin, pad, seed) -> None:
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0.0, 30.0, (n, 2))
    movers = rng.random(n) < 0.3
    candidates = ~movers & (rng.random(n) < 0.8)
    window_of = bbox_window(margin)
    out = bystanders(window_of, pos, movers, candidates, pad)
    assert not (out & ~candidates).any()  # only candidates hold
    window = window_of(pos[~out])
    for i in np.flatnonzero(out):  # the guarantee: farther than pad from the window
        assert box_distance(window, pos[i]) > pad - 1e-12
    # and the movers are the least closed set: each one is a mover, not a candidate, or
    # inside the window of the movers before it joined grown by pad on every side
    # (Chebyshev distance below pad; replayed one step at a time)
    moving = movers | ~candidates
    while True:
        x0, y0, x1, y1 = window_of(pos[moving])
        cheb = np.maximum.reduce([x0 - pos[:, 0], pos[:, 0] - x1, y0 - pos[:, 1],
                                  pos[:, 1] - y1])
        near = (cheb < pad) & ~moving
        if not near.any():
            break
        moving |= near
    assert (moving == ~out).all()


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 6), st.integers(1, 6), st.integers(0, 2**31 - 1))
def test_standing_on_goal_gives_each_goal_once(n, m, seed) -> None:
    rng = np.random.default_rng(seed)
    grid = rng.integers(0, 3, (n, 2)).astype(float)
    goals = rng.integers(0, 3, (m, 2)).astype(float)
    own = standing_on_goal(grid, goals)
    used = [j for j in own.tolist() if j >= 0]
    assert len(used) == len(set(used))
    for i, j in enumerate(own.tolist()):
        if j >= 0:
            assert (goals[j] == grid[i]).all()
        else:  # every goal where it stands was given to an earlier robot
            assert all(j2 in used[:] for j2 in np.flatnonzero((goals == grid[i]).all(axis=1)))


def strip_task() -> ManipulationTask:
    """A 3 x 30 m strip: a box near the top, one robot beside it, one 25 m away behind a
    wall across the strip."""
    wall = Obstacle(Rectangle((3.0, 0.2)), (1.5, 15.0, 0.0))
    scene = Scene("strip", (3.0, 30.0), ((1.5, 26.3), (1.5, 2.0)),
                  (SceneObject(Rectangle((0.4, 0.3)), (1.5, 27.0, 0.0), (1.5, 28.0, 0.0)),),
                  (wall,))
    return ManipulationTask(scene, 0, scene.object_starts(), GeometricProposer(),
                            PlannerConfig(), seed=0)


def test_verify_leaves_the_far_robot_out_of_the_approach() -> None:
    task = strip_task()
    verifier = task.verifier
    spaces = []
    route = verifier.route

    def spy(q_object, starts, goals, space, time_limit):
        spaces.append((len(starts), space.window))
        return route(q_object, starts, goals, space, time_limit)

    verifier.route = spy
    q_R = np.array(task.scene.robot_starts, float)
    trans = verifier.verify(np.array([1.5, 27.0, 0.0]), np.array([1.5, 27.2, 0.0]), q_R)
    assert trans is not None
    # the far robot never moves: every row of its approach and push is where it stood
    assert np.allclose(trans.move[1], q_R[1]) and np.allclose(trans.manip[1], q_R[1])
    # no approach was tried for two contacts (the far robot cannot reach them: dropped
    # before Gspi), and the one planned was for the near robot alone, in a window that
    # ends well before the far robot
    assert verifier.stats.gspi_calls == 1 == verifier.stats.gspi_success
    for n, window in spaces:
        assert n == 1 and window[1] > 2.0 + 2 * task.robot_radius


def test_unreachable_is_the_wide_windows_answer_and_builds_it_only_when_needed() -> None:
    """``Verifier._unreachable`` answers as Hall's condition over the window of all the
    robots does (a plain reference below), for contacts all round the box; a proposal
    whose contacts the robot beside the box covers never builds that wide window's space
    (the far robot, behind the wall, would widen it to 25 m of strip)."""
    from collections import Counter

    task = strip_task()
    verifier = task.verifier
    q_from = np.array([1.5, 27.0, 0.0])
    q_R = np.array(task.scene.robot_starts, float)
    wide = task.window(q_from, q_R)
    asked = []
    real = task.robot_space_at

    def spy(q_object, window=None):
        asked.append(window)
        return real(q_object, window)

    task.robot_space_at = spy  # type: ignore[method-assign]
    unreachable = verifier._unreachable(q_from, q_R)
    one = np.array([[[-0.26, 0.0], [-0.2, 0.0]]])  # one contact, left of the box
    assert not unreachable(one) and wide not in asked
    space = real(q_from, wide)
    held = Counter(space.components(q_R).tolist())
    rng = np.random.default_rng(0)
    for _ in range(40):
        b = int(rng.integers(1, 4))
        angles = rng.uniform(0, 2 * np.pi, b)
        contacts = np.c_[0.3 * np.cos(angles), 0.25 * np.sin(angles)]
        pushes = np.repeat(contacts[:, None, :], 2, axis=1)
        world = contacts + q_from[:2]  # the box stands unrotated
        need = Counter(space.components(world).tolist())
        expect = any(n > held.get(c, 0) for c, n in need.items())
        assert unreachable(pushes) == expect
    assert asked.count(wide) <= 1  # built at most once, for the proposals that needed it
