"""Point pairs within a distance (lamp.mrmp.near_pairs): the k-d tree finds exactly the
pairs, in the order and with the distances, of the dense matrix."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.mrmp.near_pairs import DENSE, NearPairs, near_pairs


def _dense(A: np.ndarray, B: np.ndarray, r: float, strict: bool):
    D = np.hypot(A[:, None, 0] - B[None, :, 0], A[:, None, 1] - B[None, :, 1])
    a, b = np.nonzero(r > D if strict else r >= D)
    return a, b, D[a, b]


@settings(max_examples=60)
@given(st.integers(0, 2**31 - 1), st.integers(0, 200), st.integers(1, 200),
       st.floats(0.0, 3.0), st.booleans(), st.booleans())
def test_pairs_as_the_dense_matrix(seed: int, na: int, nb: int, r: float, strict: bool,
                                   grid: bool) -> None:
    rng = np.random.default_rng(seed)
    # grid points: many pairs exactly at the radius
    A = rng.integers(0, 20, (na, 2)) * 0.15 if grid else rng.uniform(0, 5, (na, 2))
    B = rng.integers(0, 20, (nb, 2)) * 0.15 if grid else rng.uniform(0, 5, (nb, 2))
    r = round(r / 0.15) * 0.15 if grid else r
    want = _dense(A, B, r, strict)
    got = near_pairs(A, B, r, strict)
    for w, g in zip(want, got, strict=True):
        assert np.array_equal(w, g)


def test_straight_lines_of_a_fleet() -> None:
    rng = np.random.default_rng(3)
    S = rng.uniform(0, 9, (300, 2))
    G = rng.uniform(0, 9, (250, 2))
    E = NearPairs(S, G)
    assert len(S) * len(G) > DENSE  # the k-d tree
    D = np.hypot(G[:, None, 0] - S[None, :, 0], G[:, None, 1] - S[None, :, 1])
    assert E.nearest() == D.min(axis=1).max()
    for bound in (0.1, 0.7, 2.0):
        for strict in (True, False):
            for w, g in zip(_dense(G, S, bound, strict), E.within(bound, strict), strict=True):
                assert np.array_equal(w, g)


def test_growing_and_shrinking_bounds_give_the_pairs_of_each() -> None:
    rng = np.random.default_rng(5)
    S = rng.integers(0, 60, (400, 2)) * 0.15
    G = rng.integers(0, 60, (300, 2)) * 0.15
    E = NearPairs(S, G)
    for bound in (0.3, 0.45, 0.3, 0.6, 1.5, 0.15, 0.9):
        for strict in (True, False):
            for w, g in zip(_dense(G, S, bound, strict), E.within(bound, strict), strict=True):
                assert np.array_equal(w, g)
