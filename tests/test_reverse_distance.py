"""ReverseDistance (resumable backward Dijkstra) against SciPy's Dijkstra from scratch."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from test_dstar_lite import distances_to_goal, random_graphs

from lamp.search.reverse_distance import ReverseDistance


@settings(max_examples=150, deadline=None)
@given(data=random_graphs(), order_seed=st.integers(0, 2**31 - 1))
def test_any_query_order_gives_exact_costs_to_goal(data, order_seed) -> None:
    graph, rng = data
    n = len(graph.pts)
    goal = int(rng.integers(n))
    reference = distances_to_goal(n, graph.edges, goal)
    rd = ReverseDistance(graph, goal)
    queries = np.random.default_rng(order_seed).permutation(np.repeat(np.arange(n), 2))
    for u in queries:  # every vertex twice, in random order: resumed and cached answers
        assert np.isclose(rd.distance(int(u)), reference[u]) or rd.distance(int(u)) == reference[u]
    assert rd.n_settled <= n
