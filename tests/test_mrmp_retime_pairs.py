"""The retiming's close pairs (``lamp.mrmp.retime._close_pairs``) against a brute-force
reference over every pair of states, on random plans with crowded, coinciding and
spread-out positions, and its counting sort against a stable argsort (Hypothesis)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.mrmp.retime import _close_pairs, _stable_order, _states
from lamp.mrmp.retime_pairs import segment_distance


def _reference(rob, lo, hi, seg, move, two_r) -> set[tuple[int, int]]:
    got = set()
    for a in range(len(rob)):
        for b in range(a + 1, len(rob)):
            if rob[a] == rob[b]:
                continue
            if not move[a] and not move[b] and hi[a] >= lo[b] and hi[b] >= lo[a]:
                continue
            if segment_distance(*seg[a], *seg[b]) < two_r:
                got.add((a, b))
    return got


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(1, 9), k=st.integers(0, 8),
       spread=st.sampled_from([0.05, 0.3, 1.0, 5.0]), grid=st.booleans())
def test_close_pairs_match_every_pair_checked(seed, n, k, spread, grid) -> None:
    """Every pair the brute force finds, each once as (a < b), nothing else; moves up to
    a lattice diagonal, waits, and positions snapped to a 3 cm grid (ties on cell
    borders) or anywhere."""
    rng = np.random.default_rng(seed)
    P = np.empty((k + 1, n, 2))
    P[0] = rng.uniform(0.0, spread, (n, 2))
    for s in range(1, k + 1):
        step = rng.integers(-1, 2, (n, 2)) * 0.03
        step[rng.random(n) < 0.3] = 0.0  # waits
        P[s] = P[s - 1] + step
    if grid:
        P = np.round(P / 0.03) * 0.03
    two_r = 0.1
    rob, lo, hi, seg, move, _, _, _ = _states(np.ascontiguousarray(P))
    A, B = _close_pairs(rob, lo, hi, seg, move, two_r)
    pairs = list(zip(A.tolist(), B.tolist(), strict=True))
    assert all(a < b for a, b in pairs)
    assert len(set(pairs)) == len(pairs)
    assert set(pairs) == _reference(rob, lo, hi, seg, move, two_r)


@settings(max_examples=60, deadline=None)
@given(keys=st.lists(st.integers(0, 40), max_size=300), extra=st.integers(1, 5))
def test_stable_order_is_argsort_stable(keys, extra) -> None:
    """The retiming's counting sort orders the edges as a stable argsort does."""
    key = np.array(keys, dtype=np.int64)
    got = _stable_order(key, (max(keys) if keys else 0) + extra)
    assert np.array_equal(got, np.argsort(key, kind="stable"))
