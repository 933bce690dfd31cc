"""Watched pushes (``lamp.planners.watch``) and the simulator's ``stop`` (``Simulator.execute``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry import se2
from lamp.planners.watch import WATCH_CLEARANCE, PushWatch, deviation, watched
from lamp.scene.loader import scene_from_dict
from lamp.sim import Simulator

coord = st.floats(-3.0, 3.0, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
pose = st.tuples(coord, coord, angle).map(np.array)
paths = st.lists(pose, min_size=2, max_size=5).map(np.array)


def reference(path: np.ndarray, q: np.ndarray, n: int = 4001) -> tuple[np.ndarray, np.ndarray]:
    """Brute force: the least position distance over sampled points of each piece, and the
    least heading distance over sampled headings of the piece's (short-way) rotation."""
    t = np.linspace(0.0, 1.0, n)
    dpos, drot = [], []
    for a, b in zip(path[:-1], path[1:], strict=True):
        xy = a[:2] + t[:, None] * (b[:2] - a[:2])
        dpos.append(np.hypot(*(xy - q[:2]).T).min())
        th = a[2] + t * se2.wrap_angle(b[2] - a[2])
        drot.append(np.abs(se2.wrap_angle(q[2] - th)).min())
    return np.array(dpos), np.array(drot)


@settings(max_examples=150, deadline=None)
@given(paths, pose)
def test_deviation_matches_brute_force(path, q):
    dpos, drot = deviation(path, q)
    ref_pos, ref_rot = reference(path, q)
    seg = np.hypot(*np.diff(path[:, :2], axis=0).T)
    turn = np.abs(se2.wrap_angle(np.diff(path[:, 2])))
    assert np.all(dpos <= ref_pos + 1e-9)  # the exact minimum is never above a sample
    assert np.allclose(dpos, ref_pos, atol=seg / 4000 + 1e-9)
    assert np.all(drot <= ref_rot + 1e-9)
    assert np.allclose(drot, ref_rot, atol=turn / 4000 + 1e-9)


@settings(max_examples=100, deadline=None)
@given(paths, st.floats(0.0, 1.0))
def test_deviation_is_zero_on_the_path(path, s):
    for a, b in zip(path[:-1], path[1:], strict=True):
        q = se2.interpolate(a, b, np.array([s]))[0]
        dpos, drot = deviation(np.stack([a, b]), q)
        assert dpos[0] < 1e-9 and drot[0] < 1e-9


@settings(max_examples=100, deadline=None)
@given(paths, pose, st.floats(0.01, 0.5), st.floats(0.01, 0.5))
def test_watch_fires_exactly_when_no_piece_explains_the_pose(path, q, mp, mr):
    watch = PushWatch(path, 1, mp, mr)
    dpos, drot = reference(path, q)
    poses = np.stack([np.zeros(3), q])
    fired = watch(poses)
    explained = (dpos <= mp - 1e-6) & (drot <= mr - 1e-6)
    unexplained = (dpos > mp + 1e-6) | (drot > mr + 1e-6)
    if explained.any():
        assert not fired
    elif unexplained.all():
        assert fired


def test_watch_rejects_bad_input():
    with pytest.raises(ValueError, match="path"):
        PushWatch(np.zeros((1, 3)), 0, 0.1, 0.1)
    with pytest.raises(ValueError, match="max_rotation"):
        PushWatch(np.zeros((2, 3)), 0, 0.1, 0.0)


def _push_scene() -> Simulator:
    return Simulator(scene_from_dict({
        "format": "lamp-scene/1", "name": "watch", "workspace": [2.0, 1.0],
        "robots": {"radius": 0.05, "starts": [[0.3, 0.5]]},
        "obstacles": [],
        "objects": [{"type": "rectangle", "size": [0.2, 0.2], "start": [0.5, 0.5, 0.0],
                     "goal": [1.5, 0.5, 0.0]}],
    }))


def _straight(a, b, step=0.01):
    n = int(math.ceil(np.hypot(*(np.subtract(b, a))) / step))
    return np.linspace(a, b, n + 1)[None]


def test_stop_ends_the_push_and_holds_the_robots():
    path = _straight([0.3, 0.5], [1.0, 0.5])
    free = _push_scene().execute(path)
    sim = _push_scene()
    out = sim.execute(path, stop=lambda poses: poses[0, 0] > 0.6)
    assert free.stopped_at is None and free.object_poses[0, 0] > 0.9
    assert out.stopped_at is not None and out.stopped_at < free.steps
    assert 0.6 < out.object_poses[0, 0] < 0.7  # stopped soon after the condition held
    assert out.robot_positions[0, 0] < 0.6  # the robot held where it was
    assert out.robot_errors[0] > 0.3


def test_a_stop_that_never_fires_changes_nothing():
    path = _straight([0.3, 0.5], [1.0, 0.5])
    free = _push_scene().execute(path)
    calls = []
    watched = _push_scene().execute(path, stop=lambda poses: calls.append(1) and False)
    assert calls and watched.stopped_at is None
    np.testing.assert_array_equal(free.object_poses, watched.object_poses)
    np.testing.assert_array_equal(free.robot_positions, watched.robot_positions)
    assert free.steps == watched.steps


def test_only_straight_pushes_through_tight_places_are_watched():
    straight = np.array([[0.0, 0.0, 0.3], [0.2, 0.0, 0.31], [0.4, 0.0, 0.29]])
    turning = straight.copy()
    turning[-1, 2] = 0.5
    assert watched(straight, WATCH_CLEARANCE - 1e-3)
    assert not watched(straight, WATCH_CLEARANCE)
    assert not watched(turning, 0.0)
    wrapped = np.array([[0.0, 0.0, math.pi - 0.01], [0.2, 0.0, -math.pi + 0.01]])
    assert watched(wrapped, 0.0)
