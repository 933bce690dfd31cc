"""``lamp.contract.robots``: the two "same robot configuration" relations, as documented."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment

from lamp.contract.robots import robot_state_key, robots_match

coords = st.floats(-5.0, 5.0, allow_nan=False, allow_infinity=False)


def configs(n: int):
    return st.lists(st.tuples(coords, coords), min_size=n, max_size=n).map(np.array)


@settings(max_examples=200, deadline=None)
@given(n=st.integers(1, 5), data=st.data(), tol=st.floats(1e-3, 0.2))
def test_robots_match_is_the_ordered_max_distance(n, data, tol):
    a = data.draw(configs(n))
    b = data.draw(configs(n))
    worst = max(float(np.hypot(*(a[i] - b[i]))) for i in range(n))  # the reference
    assert robots_match(a, b, tol) == (worst <= tol)
    assert robots_match(a, b, tol) == robots_match(b, a, tol)
    assert robots_match(a, b, worst)  # exact at the tolerance
    assert robots_match(a, a, 0.0)


def test_robots_match_needs_the_same_team():
    assert not robots_match(np.zeros((2, 2)), np.zeros((3, 2)), 1.0)


@settings(max_examples=200, deadline=None)
@given(n=st.integers(1, 5), data=st.data(), tol=st.floats(0.01, 0.2))
def test_equal_keys_mean_anonymous_match_within_a_cell(n, data, tol):
    a = data.draw(configs(n))
    perm = data.draw(st.permutations(range(n)))
    assert robot_state_key(a, tol) == robot_state_key(a[list(perm)], tol)
    # a configuration with the same key: each robot moved within its own cell
    jitter = data.draw(st.lists(st.tuples(st.floats(-0.49, 0.49), st.floats(-0.49, 0.49)),
                                min_size=n, max_size=n))
    cells = np.round(a / tol)
    b = (cells + np.array(jitter)) * tol
    if robot_state_key(b, tol) != robot_state_key(a, tol):
        return  # float rounding at a cell edge: nothing to check
    d = np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])
    rows, cols = linear_sum_assignment(d)
    # paired optimally, every robot lies within one cell diagonal of its partner
    assert d[rows, cols].max() <= tol * np.sqrt(2) + 1e-9
