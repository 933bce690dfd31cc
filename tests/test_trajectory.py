"""Synchronised trajectory utilities: densify keeps shape, endpoints, synchrony and step bound."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from lamp.contract.trajectory import MAX_STEP, concat, densify, hold, straight_moves

coords = st.floats(-3.0, 3.0, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(st.tuples(st.integers(1, 4), st.integers(1, 6)).flatmap(
    lambda nt: arrays(float, (nt[0], nt[1], 2), elements=coords)))
def test_densify_bounds_steps_and_keeps_original_rows(paths):
    dense = densify(paths)
    assert dense.shape[0] == paths.shape[0]
    if paths.shape[1] > 1:
        steps = np.linalg.norm(np.diff(dense, axis=1), axis=2)
        assert steps.max() <= MAX_STEP + 1e-9
    # every original row appears, in order
    idx = 0
    for t in range(paths.shape[1]):
        while idx < dense.shape[1] and not np.allclose(dense[:, idx], paths[:, t], atol=1e-9):
            idx += 1
        assert idx < dense.shape[1], "an original row is missing"
    np.testing.assert_allclose(dense[:, 0], paths[:, 0])
    np.testing.assert_allclose(dense[:, -1], paths[:, -1])


def test_densify_points_lie_on_original_segments():
    paths = np.array([[[0.0, 0.0], [0.1, 0.0]], [[1.0, 1.0], [1.0, 1.05]]])
    dense = densify(paths)
    assert dense.shape[1] == 6  # 0.1 m in 0.02 m steps
    np.testing.assert_allclose(dense[0, :, 1], 0.0)
    np.testing.assert_allclose(dense[1, :, 0], 1.0)
    assert np.all(np.diff(dense[0, :, 0]) > 0)


def test_concat_drops_joint_row_and_hold_repeats():
    a = straight_moves(np.zeros((2, 2)), np.full((2, 2), 0.05))
    b = hold(a[:, -1], 3)
    c = concat(a, b)
    assert c.shape[1] == a.shape[1] + 2
    np.testing.assert_allclose(c[:, -1], a[:, -1])


def test_retime_keeps_endpoints_and_step_bound_with_fewer_rows():
    from lamp.contract.trajectory import retime

    t = np.linspace(0.0, 1.0, 20)
    push = np.stack([np.stack([0.1 * t, 0.0 * t], axis=1), np.stack([0.1 * t, 0.2 + 0 * t], axis=1)])
    out = retime(push)
    assert out.shape[1] == 6  # 0.1 m in 0.02 m rows
    np.testing.assert_allclose(out[:, 0], push[:, 0])
    np.testing.assert_allclose(out[:, -1], push[:, -1])
    assert np.linalg.norm(np.diff(out, axis=1), axis=2).max() <= MAX_STEP + 1e-9
