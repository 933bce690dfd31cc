"""The lattice's packed, tiled store of node and edge states (``lattice_primitives``
module docstring)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.object_space import ObjectSpace
from lamp.scene.model import Circle, Obstacle, Rectangle
from lamp.search.lattice import ObjectLattice
from lamp.search.lattice_primitives import (
    EDGE_TILE,
    HALF,
    PRIMITIVES,
    REVERSE,
    SLOT,
    STORE_DTYPE,
    edge_word,
    edge_words,
    node_words,
)

PAGE_WORDS = 4096 // np.dtype(STORE_DTYPE).itemsize


def test_each_edge_has_one_place_and_the_pairs_share_it():
    """The two directions of every edge (``p`` and ``REVERSE[p]``) are kept in one place:
    one in the word of the node it leaves, the other in the word of the node it reaches,
    and the 13 pairs take the 13 places of ``HALF``."""
    assert len(HALF) == len(PRIMITIVES) // 2
    for p in range(len(PRIMITIVES)):
        s, r = SLOT[p], SLOT[REVERSE[p]]
        assert (s >= 0) != (r >= 0) and s == -1 - r
    assert sorted(s for s in SLOT if s >= 0) == list(range(len(HALF)))


@settings(max_examples=40)
@given(st.integers(1, 13), st.integers(1, 13), st.integers(1, 5))
def test_every_node_has_its_own_word_inside_the_store(n_i, n_j, n_k):
    """``edge_word`` maps the nodes one to one into ``range(edge_words(...))``."""
    words = [edge_word(i, j, k, n_j, n_k)
             for i in range(n_i) for j in range(n_j) for k in range(n_k)]
    assert len(set(words)) == n_i * n_j * n_k
    assert min(words) >= 0 and max(words) < edge_words(n_i, n_j, n_k)
    ids = np.arange(n_i * n_j * n_k, dtype=np.int64)  # node id order: (i, j, k), k fastest
    assert node_words(ids, n_j, n_k).tolist() == words


@settings(max_examples=30)
@given(st.integers(0, 250), st.integers(0, 250), st.integers(8, 60), st.booleans())
def test_a_straight_run_of_cells_touches_a_page_per_tile_at_most(i0, j0, run, along_x):
    """Every heading of ``run`` cells in a row along either axis of a 300 x 300 cell,
    16-heading lattice lies in at most two pages per tile crossed (stored by node id, a run
    along x would take a page per cell)."""
    n_j, n_k = 300, 16
    cells = [(i0 + s, j0) if along_x else (i0, j0 + s) for s in range(run)]
    pages = {edge_word(i, j, k, n_j, n_k) // PAGE_WORDS for i, j in cells for k in range(n_k)}
    tiles = -(-run // EDGE_TILE) + 1
    assert len(pages) <= 2 * tiles


def test_successors_do_not_depend_on_the_order_nodes_are_visited():
    """Two lattices, one visited in a random order and one in its reverse, list the same
    successors for every node: no node's states land in another's bits."""
    obstacles = (Obstacle(Circle(0.2), (1.0, 0.8, 0.0)),
                 Obstacle(Rectangle((0.1, 0.9)), (1.9, 1.1, 0.4)))
    space = ObjectSpace(Rectangle((0.3, 0.16)), (2.6, 2.1), obstacles)
    a, b = ObjectLattice(space, (2.2, 0.4, 0.7)), ObjectLattice(space, (2.2, 0.4, 0.7))
    nodes = np.random.default_rng(3).choice(a.n_nodes, 1500, replace=False).tolist()
    got_a = {u: sorted(a.successors(u)) for u in nodes}
    got_b = {u: sorted(b.successors(u)) for u in reversed(nodes)}
    assert got_a == got_b
    assert any(got_a.values()) and not all(got_a.values())  # free and blocked nodes met
    for u, out in got_a.items():  # an edge listed from one end is listed from the other
        for v, cost in out:
            assert (u, cost) in b.successors(v)
