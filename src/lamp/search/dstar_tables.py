"""D* Lite's tables in arrays, for a search that waits between calls (``DStarLite.pack``).

A search keeps ``rhs``, the ``g`` values that differ from it and its queue in dicts: some
110 bytes a vertex for ``rhs`` and 200 for a queued one (the int and float objects, the
key tuple, the dict slots). Between two calls nothing reads them, and an object of a
fleet spends most of its life there, its segment waiting or running. :class:`PackedTables`
holds the same tables in NumPy arrays: 16 bytes a vertex and 32 a queued one. Vertices
that are not ints (a virtual start, a pose tuple) stay in small dicts beside them.

Guarantee (``tests/test_dstar_tables.py``): :meth:`PackedTables.tables` gives back dicts
equal to those packed, and a queue whose entries are those of the live ones packed (the
same keys and sequence numbers; stale entries are left out), so the order in which
vertices leave the queue is unchanged.
"""

from __future__ import annotations

import heapq
from collections.abc import Hashable
from dataclasses import dataclass
from itertools import compress, repeat
from operator import is_not

import numpy as np

__all__ = ["PackedTables"]

Entry = tuple[float, float, int, Hashable]


def _others(table: dict) -> tuple[dict, dict]:
    """(the entries of ``table`` whose key is an int, the others), found at C speed."""
    others = list(compress(table, map(is_not, map(type, table), repeat(int))))
    if not others:
        return table, {}
    ints = dict(table)
    return ints, {k: ints.pop(k) for k in others}


def _split(table: dict[Hashable, float]) -> tuple[np.ndarray, np.ndarray, dict]:
    """(int keys, their values, the entries whose key is not an int)."""
    ints, rest = _others(table)
    n = len(ints)
    return (np.fromiter(ints, dtype=np.int64, count=n),
            np.fromiter(ints.values(), dtype=np.float64, count=n), rest)


@dataclass(frozen=True)
class PackedTables:
    """``rhs``, ``g`` where it differs from ``rhs``, and the queue's live entries."""

    rhs_keys: np.ndarray
    rhs_values: np.ndarray
    rhs_rest: dict[Hashable, float]
    g_keys: np.ndarray
    g_values: np.ndarray
    g_rest: dict[Hashable, float]
    #: the queued int vertices' two key components, sequence numbers and the vertices
    queue_k1: np.ndarray
    queue_k2: np.ndarray
    queue_seq: np.ndarray
    queue_vertex: np.ndarray
    queue_rest: tuple[Entry, ...]

    @classmethod
    def of(cls, rhs: dict[Hashable, float], g: dict[Hashable, float],
           queued: dict[Hashable, Entry]) -> PackedTables:
        """The tables of a search: ``rhs``, ``g`` (``DStarLite._gx``) and its queued
        vertices' current entries ``(k1, k2, seq, vertex)``."""
        rk, rv, rr = _split(rhs)
        gk, gv, gr = _split(g)
        ints, others = _others(queued)
        rest = tuple(others.values())
        entries = ints.values()
        cols = list(zip(*entries, strict=True)) or [(), (), (), ()]
        k1, k2, seq, vertex = (np.fromiter(c, dtype=t, count=len(c)) for c, t in zip(
            cols, (np.float64, np.float64, np.int64, np.int64), strict=True))
        return cls(rk, rv, rr, gk, gv, gr, k1, k2, seq, vertex, rest)

    @property
    def nbytes(self) -> int:
        """Bytes of the arrays (the dicts of other vertices not counted)."""
        return sum(a.nbytes for a in (self.rhs_keys, self.rhs_values, self.g_keys,
                                      self.g_values, self.queue_k1, self.queue_k2,
                                      self.queue_seq, self.queue_vertex))

    def tables(self) -> tuple[dict[Hashable, float], dict[Hashable, float],
                              dict[Hashable, Entry], list[Entry]]:
        """``rhs``, ``g``, the queued vertices' entries and the queue (a heap of those
        entries), as dicts and a list again."""
        rhs = dict(zip(self.rhs_keys.tolist(), self.rhs_values.tolist(), strict=True))
        rhs.update(self.rhs_rest)
        g = dict(zip(self.g_keys.tolist(), self.g_values.tolist(), strict=True))
        g.update(self.g_rest)
        entries = list(zip(self.queue_k1.tolist(), self.queue_k2.tolist(),
                           self.queue_seq.tolist(), self.queue_vertex.tolist(), strict=True))
        entries.extend(self.queue_rest)
        queued = {e[3]: e for e in entries}
        heapq.heapify(entries)
        return rhs, g, queued, entries
