"""The repair's spatial hash (``lamp.mrmp.repair_hash``): its cell-start table against
a plain rebuild and against brute force, through random moves of robots."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.mrmp.gspi_kernels import conflict
from lamp.mrmp.repair_hash import (
    build_hash,
    cell,
    clear_of,
    gather,
    hash_rows,
    move_ok,
    set_key,
)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(1, 40), rows=st.integers(2, 6),
       moves=st.integers(0, 60), span=st.floats(0.15, 1.5))
def test_table_follows_moves_and_checks_match_brute_force(seed, n, rows, moves,
                                                          span) -> None:
    """After random key changes the table is the one a rebuild gives, and every motion's
    check (with and without the table, and through the robots gathered for its start)
    is the brute-force check over all robots."""
    rng = np.random.default_rng(seed)
    V = 6 * n + 5
    coords = rng.random((V, 2)) * span
    VX = rng.integers(0, V, size=(rows, n))
    two_r, cs = 0.1, 0.1 + 2 * 0.05 + 1e-6
    hh, x0, y0, ny = build_hash(VX, coords, cs, True)
    assert hh[2].shape[0] == rows
    for _ in range(moves):  # another vertex for a robot in a row, near its old one
        t, i = int(rng.integers(rows)), int(rng.integers(n))
        VX[t, i] = int(rng.integers(V))
        set_key(t, i, cell(coords[VX[t, i], 0], coords[VX[t, i], 1], x0, y0, cs, ny), hh)
    fresh, *_ = build_hash(VX, coords, cs, True)
    assert np.array_equal(hh[0], fresh[0]) and np.array_equal(hh[2], fresh[2])
    bare = (hh[0], hh[1], np.zeros((0, 0), np.int32))
    skip = rng.random(n) < 0.2
    none = np.zeros(0, np.bool_)
    gv0 = V - 4
    for t in range(rows - 1):
        for _ in range(20):
            i = int(rng.integers(n))
            a = VX[t, i]
            # only motions short enough for the cells (as in the repair)
            near = np.nonzero(np.hypot(*(coords - coords[a]).T) <= 0.05)[0]
            b = int(rng.choice(near))
            want = np.zeros(n, np.bool_)
            for k in range(n):
                if k != i and not skip[k]:
                    u, w = VX[t, k], VX[t + 1, k]
                    if np.hypot(*(coords[u] - coords[w])) > 0.05:
                        continue  # such a motion is never in a repaired plan
                    want[k] = conflict(*coords[a], *coords[b], *coords[u], *coords[w],
                                       two_r, b >= gv0 and w >= gv0)
            for h in (hh, bare):
                found = np.zeros(n, np.bool_)
                move_ok(i, t, a, b, VX, coords, gv0, h, x0, y0, cs, ny, two_r, skip, found)
                long_ = np.array([np.hypot(*(coords[VX[t, k]] - coords[VX[t + 1, k]])) > 0.05
                                  for k in range(n)])
                assert np.array_equal(found & ~long_, want)
                ok = move_ok(i, t, a, b, VX, coords, gv0, h, x0, y0, cs, ny, two_r,
                             skip | long_, none)
                assert ok == (not want.any())
                # the robots gathered once for vertex a answer the same for any short move
                buf = np.empty((n, 5))
                got = gather(i, t, a, VX, coords, gv0, h, x0, y0, cs, ny, two_r + 0.05 + 1e-6,
                             skip | long_, buf)
                assert clear_of(*coords[a], *coords[b], b >= gv0, buf, got, two_r) == ok


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(1, 60), rows=st.integers(1, 8),
       span=st.floats(0.05, 3.0), table=st.booleans(), outside=st.booleans())
def test_hash_rows_is_a_stable_sort_with_its_table(seed, n, rows, span, table,
                                                   outside) -> None:
    """``hash_rows`` (counting sorts when the table is wanted and every key is inside it,
    else merge sorts): each row's keys sorted stably, as ``np.argsort(kind="stable")``
    orders them, and the table's entry ``kk`` the row's count of keys below ``kk``; many
    robots on a few cells (ties) included; a point outside the bounds takes the merge
    sorts (same order, table counted from the sorted keys)."""
    rng = np.random.default_rng(seed)
    X = np.round(rng.random((rows, n)) * span, 1)  # rounded: many equal keys
    Y = np.round(rng.random((rows, n)) * span, 1)
    if outside:
        X[0, 0] = span + 1.0
    cs = 0.21
    (sk, so, first), ny = hash_rows(X, Y, 0.0, 0.0, span, span, cs, table)
    for t in range(rows):
        keys = np.array([cell(X[t, k], Y[t, k], 0.0, 0.0, cs, ny) for k in range(n)])
        order = np.argsort(keys, kind="stable")
        assert np.array_equal(so[t], order) and np.array_equal(sk[t], keys[order])
        if table:
            ncell = (int(span / cs) + 4) * ny + 4
            want = np.searchsorted(keys[order], np.arange(ncell), side="left")
            assert np.array_equal(first[t], want)
    assert first.shape[0] == (rows if table else 0)
