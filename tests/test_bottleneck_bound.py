"""``straight_line_bottleneck``: the least longest straight-line distance over the
assignments of robots to goals, against brute force over every assignment."""

from itertools import permutations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.mrmp.assignment import straight_line_bottleneck


def brute(S: np.ndarray, G: np.ndarray) -> float:
    """Every injective map of goals to robots."""
    return min(max(float(np.hypot(*(G[m] - S[i]))) for m, i in enumerate(p))
               for p in permutations(range(len(S)), len(G)))


coord = st.floats(-5, 5, allow_nan=False).map(lambda v: round(v, 1))  # ties happen


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_against_brute_force(data):
    n = data.draw(st.integers(1, 6), label="robots")
    m = data.draw(st.integers(1, n), label="goals")
    S = np.array(data.draw(st.lists(st.tuples(coord, coord), min_size=n, max_size=n)))
    G = np.array(data.draw(st.lists(st.tuples(coord, coord), min_size=m, max_size=m)))
    assert straight_line_bottleneck(S, G) == pytest.approx(brute(S, G), abs=1e-12)


def test_edges():
    assert straight_line_bottleneck(np.zeros((3, 2)), np.zeros((0, 2))) == 0.0
    S = np.array([[0.0, 0.0], [10.0, 0.0]])
    # both goals are nearest the robot at 10; the other robot must cover 9 (not 11)
    assert straight_line_bottleneck(S, np.array([[9.0, 0.0], [11.0, 0.0]])) == 9.0
    with pytest.raises(ValueError):
        straight_line_bottleneck(S[:1], S)
