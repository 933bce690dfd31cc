"""D* Lite's packed tables: the same tables back, and a search packed between its calls
plans exactly as one never packed."""

from __future__ import annotations

import heapq
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_dstar_lite import chain_graph, random_graphs

from lamp.search import dstar_lite
from lamp.search.dstar_lite import DStarLite
from lamp.search.dstar_tables import PackedTables

vertices = st.one_of(st.integers(-2**40, 2**40),
                     st.tuples(st.floats(-10, 10), st.floats(-10, 10), st.floats(-3, 3)))
values = st.one_of(st.floats(0, 1e6), st.just(math.inf))


@settings(max_examples=200, deadline=None)
@given(rhs=st.dictionaries(vertices, values, max_size=40),
       g=st.dictionaries(vertices, values, max_size=20),
       queued=st.lists(st.tuples(vertices, values, values), max_size=30, unique_by=lambda e: e[0]))
def test_tables_come_back_equal(rhs, g, queued):
    entries = {v: (k1 + 1.0, k1, seq, v) for seq, (v, k1, _) in enumerate(queued)}
    packed = PackedTables.of(rhs, g, entries)
    rhs2, g2, entries2, heap = packed.tables()
    assert rhs2 == rhs and g2 == g and entries2 == entries
    assert all(entries2[e[3]] is e for e in heap) and len(heap) == len(entries)
    assert [heapq.heappop(heap) for _ in range(len(heap))] == sorted(entries.values(),
                                                                       key=lambda e: e[:3])
    ints = sum(type(v) is int for v in rhs)
    assert len(packed.rhs_keys) == ints and len(packed.rhs_rest) == len(rhs) - ints


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=random_graphs(), n_ops=st.integers(1, 20), limit=st.sampled_from([None, 4]))
def test_a_packed_search_plans_as_one_never_packed(data, n_ops, limit):
    """Plans from moving starts, virtual starts and penalties, one search packed after
    every call: the same paths, costs, expansions per call, tables and statuses."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(dstar_lite, "PACK_FROM", 0)
        _twins(*data, n_ops, limit)


def _twins(graph, rng, n_ops: int, limit: int | None) -> None:
    n = len(graph.pts)
    a, b = DStarLite(graph, max_expansions=limit), DStarLite(graph, max_expansions=limit)
    a.initialize(0)
    b.initialize(0)
    edges = list(graph.edges)
    for _ in range(n_ops):
        op = rng.integers(3)
        if op == 0 and edges:
            u, v = edges[int(rng.integers(len(edges)))]
            pen = float(rng.uniform(0.0, 20.0))
            assert a.penalize(u, v, pen) == b.penalize(u, v, pen)
        elif op == 1:
            s = int(rng.integers(n))
            assert a.plan_shortest_path(s) == b.plan_shortest_path(s)
        else:  # a virtual start joined to a few vertices
            p = tuple(float(x) for x in rng.uniform(0, 10, 2))
            join = [(int(v), float(graph.heuristic(("p", *p), int(v))) + 0.5)
                    for v in rng.choice(n, size=min(n, 3), replace=False)]
            assert a.plan_shortest_path(("p", *p), join) == b.plan_shortest_path(("p", *p), join)
        assert a.status is b.status
        assert a.stats.last_expansions == b.stats.last_expansions
        b.pack()
    b.pack()
    assert b._packed is not None and b.rhs is None  # packed: the dicts are gone
    assert a.path_cost() == b.path_cost()
    b.pack()
    assert a.plan_shortest_path(n - 1) == b.plan_shortest_path(n - 1)
    assert a.rhs == b.rhs and a._gx == b._gx
    assert sorted(a._open.values(), key=lambda e: e[:3]) == sorted(b._open.values(),
                                                                     key=lambda e: e[:3])


def test_small_searches_stay_unpacked():
    d = DStarLite(chain_graph(20))
    d.initialize(19)
    d.plan_shortest_path(0)
    d.pack()  # 20 vertices, below PACK_FROM
    assert isinstance(d.rhs, dict) and d._packed is None
