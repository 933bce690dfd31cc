"""The memory benchmark's counting (``benchmarks/fleet_memory.py``): an array counts the
pages it has resident, however it was allocated, and an inventory finds the arrays the
project's objects hold, each once."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCH))
from fleet_memory import HEAP_BELOW, PAGE, inventory, resident_in  # noqa: E402

from lamp.fleet.turns import share_malloc_arenas  # noqa: E402
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


def test_a_large_numpy_zeros_counts_its_written_pages_and_its_header():
    """With the fleet's malloc settings (``share_malloc_arenas``: blocks of 128 kB or more
    mapped on their own), a 1 MB ``np.zeros`` is resident only where written, and in the
    page holding the allocator's header before it."""
    assert share_malloc_arenas()
    a = np.zeros(256 * PAGE, np.uint8)
    first = a.ctypes.data // PAGE
    assert resident_in(a.ctypes.data, a.nbytes) == PAGE  # the header's page
    for p in (3, 100, 200):
        a[p * PAGE] = 1
    written = {first, *((a.ctypes.data + p * PAGE) // PAGE for p in (3, 100, 200))}
    assert resident_in(a.ctypes.data, a.nbytes) == len(written) * PAGE


class _Holder:
    """Stands in for a project class: the inventory counts classes of ``lamp.`` modules."""


_Holder.__module__ = "lamp.test_holder"


def test_inventory_counts_each_array_once_by_its_holder():
    """Arrays held directly, in a dict or a list, and views of one of them: each buffer
    once, small ones (on the heap) by size, large ones by their resident pages."""
    assert share_malloc_arenas()
    big = np.zeros(4 * HEAP_BELOW, np.uint8)  # mapped on its own, its header's page resident
    for p in (0, 1, 2):
        big[p * PAGE] = 1  # in the header's page and the next two
    small = np.ones(1000)
    h = _Holder()
    h.big, h.view, h.parts, h.table = big, big[10:], [small, small[::2]], {"a": small}
    found = inventory()["lamp.test_holder._Holder"]
    assert found[2] == 1  # one instance
    assert found[0] == 3 * PAGE + small.nbytes
