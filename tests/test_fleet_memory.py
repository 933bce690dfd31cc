"""The memory benchmark's counting (``benchmarks/fleet_memory.py``): a large array counts
the pages it has resident, and an inventory finds the arrays the project's objects hold,
each once."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCH))
from fleet_memory import HEAP_BELOW, PAGE, inventory, resident_in  # noqa: E402

from lamp.geometry.distance_tiles import lazy_zeros  # noqa: E402


@settings(max_examples=20, deadline=None)
@given(st.lists(st.integers(0, 255), min_size=1, max_size=12, unique=True))
def test_resident_pages_are_the_pages_written(pages):
    """A lazily mapped zero buffer (``lazy_zeros``, page-aligned) has exactly the pages
    written resident, one byte in each; counting reads nothing, so it faults nothing in."""
    a = lazy_zeros((256 * PAGE,), np.uint8)
    assert resident_in(a.ctypes.data, a.nbytes) == 0
    for p in pages:
        a[p * PAGE + 7] = 1
    assert resident_in(a.ctypes.data, a.nbytes) == len(pages) * PAGE
    assert resident_in(a.ctypes.data, a.nbytes) == len(pages) * PAGE


class _Holder:
    """Stands in for a project class: the inventory counts classes of ``lamp.`` modules."""


_Holder.__module__ = "lamp.test_holder"


def test_inventory_counts_each_array_once_by_its_holder():
    """Arrays held directly, in a dict or a list, and views of one of them: each buffer
    once, small ones (on the heap) by size, large ones by their resident pages (over a
    lazy mapping here, so that they are exactly the pages written; a large block from
    the heap may be resident whole, and counts so)."""
    big = lazy_zeros((4 * HEAP_BELOW,), np.uint8)
    for p in (0, 5, 9):
        big[p * PAGE] = 1  # three pages written
    small = np.ones(1000)
    h = _Holder()
    h.big, h.view, h.parts, h.table = big, big[10:], [small, small[::2]], {"a": small}
    found = inventory()["lamp.test_holder._Holder"]
    assert found[2] == 1  # one instance
    assert found[0] == 3 * PAGE + small.nbytes
