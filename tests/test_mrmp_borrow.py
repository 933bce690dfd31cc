"""Borrowed views (``lamp.mrmp.borrow``): the same data and type without reference counts."""

from __future__ import annotations

import numba as nb
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from numba.typed import List

from lamp.mrmp.borrow import borrowed
from lamp.mrmp.gspi_kernels import Graph


@nb.njit(cache=False)
def _write_through(a: np.ndarray, k: int, v: float) -> tuple[float, int, int]:
    b = borrowed(a)
    b.flat[k] = v
    return b.sum(), b.shape[0], b.ndim


@nb.njit(cache=False)
def _list_through(lst, k: int) -> tuple[int, float]:
    b = borrowed(lst)
    b[k] = b[k] * 2.0  # replaces the item in the original list
    b[0][0] = -1.0  # writes into the item itself
    return len(b), b[k].sum()


@nb.njit(cache=False)
def _tuple_through(gr: tuple, hs: tuple) -> tuple:
    (g2, h2) = borrowed((gr, hs))
    g2[0][0, 0] = 9.0
    return g2[2].sum(), h2[0], h2[1][1], len(h2[2])


@nb.njit(cache=False)
def _bind_many(a: np.ndarray, n: int) -> float:
    b = borrowed(a)
    s = 0.0
    for i in range(n):
        s += _helper(b, i)
    return s


@nb.njit(cache=False, inline="always")
def _helper(x: np.ndarray, i: int) -> float:
    s = 0.0
    for k in range(2):
        s += x[(i + k) % x.shape[0]]
    return s


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 6), st.integers(1, 5), st.booleans(), st.data())
def test_borrowed_arrays_share_data_shape_and_writes(rows: int, cols: int, fortran: bool,
                                                     data: st.DataObject) -> None:
    a = np.arange(rows * cols, dtype=float).reshape(rows, cols)
    if fortran:
        a = np.asfortranarray(a)
    k = data.draw(st.integers(0, rows * cols - 1))
    want = a.copy()
    want.flat[k] = 7.5
    total, n0, nd = _write_through(a, k, 7.5)
    assert np.array_equal(a, want)  # the write went to the caller's array
    assert (total, n0, nd) == (want.sum(), rows, 2)
    # a strided view borrowed: its own elements, written through to the array
    v = a[::2]
    j = data.draw(st.integers(0, v.size - 1))
    want_v = v.copy()
    want_v.flat[j] = -2.0
    total, n0, _ = _write_through(v, j, -2.0)
    assert np.array_equal(v, want_v) and (total, n0) == (want_v.sum(), v.shape[0])


def test_borrowed_typed_list_reads_and_replaces_items_of_the_original() -> None:
    lst = List([np.ones(3), np.full(2, 2.0)])
    n, s = _list_through(lst, 1)
    assert (n, s) == (2, 8.0)
    assert np.array_equal(lst[1], [4.0, 4.0]) and lst[0][0] == -1.0


def test_borrowed_named_tuples_keep_members_and_other_values() -> None:
    coords = np.zeros((2, 2))
    gr = Graph(coords, np.zeros((2, 8), np.int64), np.arange(8.0), np.zeros(3, np.int64),
               np.zeros(0, np.int64))
    hs = (3.5, np.array([1, 2, 3]), List([np.ones(1), np.ones(2)]))
    s, f, second, n = _tuple_through(gr, hs)
    assert (s, f, second, n) == (28.0, 3.5, 2, 2)
    assert coords[0, 0] == 9.0


def test_a_helper_bound_in_a_loop_reads_the_borrowed_array() -> None:
    a = np.arange(5.0)
    assert _bind_many(a, 10) == sum(a[i % 5] + a[(i + 1) % 5] for i in range(10))
    assert np.array_equal(a, np.arange(5.0))  # nothing written, the array intact
