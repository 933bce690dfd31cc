"""Gspi's lazy windowed goal searches (``lamp.mrmp.goal_distances``) against a plain
heap Dijkstra over the whole lattice (``Lattice.field``, which shares no code with them):
the settled values are the same floats, bit for bit, however the searches were grown."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.distance_field import get_lattice
from lamp.mrmp.goal_distances import EPS, GoalDistances, expand_to, lattice_h
from lamp.mrmp.links import link_special_vertices
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"


def _tables(n: int, instance: int, slots: int):
    """A random instance of ``n`` robots on random-32-32-20, its goals, 3 cm lattice, goal
    links and goal-distance tables (``slots`` per goal)."""
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, n, instance)
    space = RobotSpace.from_scene(gm.scene)
    lat = get_lattice(space, 0.03)
    links = link_special_vertices(space, lat, S, G, space.clearance(S, exact=True),
                                  space.clearance(G, exact=True), 0.045, {})
    return G, lat, links, GoalDistances.build(links.goal_links, G, lat, slots)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), bounds=st.lists(st.floats(0.0, 2.5), min_size=1,
                                                    max_size=3),
       queries=st.integers(0, 30), room=st.sampled_from([0.0, 1.0, 1.2, 2.0]))
def test_settled_values_are_the_full_dijkstra_bit_for_bit(seed: int, bounds: list[float],
                                                          queries: int, room: float) -> None:
    """After expansions to growing bounds and point queries in any order (windows opened,
    grown, given room beyond the bound and resumed), every node closer to its goal than
    the largest bound is settled, and every settled value equals the whole-lattice heap
    Dijkstra's float exactly (the same sums of edge lengths: the assignment's costs and
    the plans depend on them)."""
    G, lat, links, hs = _tables(6, seed % 40, 12)
    rng = np.random.default_rng(seed)
    for b in sorted(bounds):
        for m in range(len(G)):
            expand_to(m, b, lat.nbr, lat.dlen, hs, room * b)
        for v in rng.integers(0, lat.V, queries).tolist():  # point queries grow windows
            lattice_h(int(rng.integers(0, len(G))), v, lat.nbr, lat.dlen, hs)
    for m, (nodes, cost) in enumerate(links.goal_links):
        ref = lat.field(nodes, cost + EPS) if len(nodes) else np.full(lat.V, np.inf)
        a0, b0, na, nbw, _ = hs.win[m].tolist()
        a, b = lat.va - a0, lat.vb - b0
        inside = (a >= 0) & (a < na) & (b >= 0) & (b < nbw)
        j = (b + 1) * (na + 2) + a + 1
        settled = np.zeros(lat.V, bool)
        settled[inside] = hs.done[m][j[inside]] == 1
        assert settled[ref < max(bounds)].all()
        got = hs.dist[m][j[settled]]
        assert np.array_equal(got, ref[settled])  # same floats (inf only where ref is)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), bounds=st.lists(st.floats(0.0, 2.5), min_size=1,
                                                    max_size=3),
       room=st.sampled_from([0.0, 1.0, 1.2, 2.0]))
def test_windows_hold_the_lattice_edges_inside_a_settled_ring(seed: int,
                                                              bounds: list[float],
                                                              room: float) -> None:
    """Every window, opened and grown to random bounds, is laid out as the searches
    assume: inside, each entry's edge bits are the lattice's at its index, its value
    never -inf, and finite where settled; the ring of one entry around it is
    settled, holds -inf and has no edges (a plain loop over the window as reference)."""
    G, lat, links, hs = _tables(6, seed % 40, 12)
    emask = lat.edge_mask
    for b in sorted(bounds):
        for m in range(len(G)):
            expand_to(m, b, lat.nbr, lat.dlen, hs, room * b)
    for m in range(len(G)):
        a0, b0, na, nbw, _ = hs.win[m].tolist()
        P = na + 2
        d, dn, em = hs.dist[m], hs.done[m], hs.em[m]
        assert len(d) == len(dn) == len(em) == P * (nbw + 2)
        for j in range(len(d)):
            b, a = divmod(j, P)
            if 1 <= a <= na and 1 <= b <= nbw:
                assert em[j] == emask[b - 1 + b0, a - 1 + a0]
                assert dn[j] in (0, 1) and d[j] > -np.inf
                assert dn[j] == 0 or d[j] < np.inf  # settled: reached, so finite
            else:
                assert dn[j] == 1 and em[j] == 0 and d[j] == -np.inf


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), which=st.lists(st.integers(0, 19), max_size=4),
       change=st.sampled_from(["strided", "readonly", "fortran", "float32", "same"]))
def test_goal_distances_numba_type_is_the_tuple_rule(seed: int, which: list[int],
                                                     change: str) -> None:
    """The type kept for a GoalDistances by its fields' kinds is the one Numba's tuple
    rule gives, for tables as built and with random fields made strided, read-only,
    Fortran-ordered or of another dtype (any of which changes the type), typed in any
    order; and compiled calls given it run."""
    from numba.core.typing.typeof import Purpose, typeof, typeof_impl

    G, lat, links, hs = _tables(4, seed % 40, 8)
    fields = list(hs)
    for k in which:
        x = fields[k]
        if type(x) is not np.ndarray or change == "same":
            continue
        if change == "strided" and x.ndim >= 1 and x.shape[0] > 1:
            x = np.repeat(x, 2, axis=0)[::2]
        elif change == "readonly":
            x = x.copy()
            x.setflags(write=False)
        elif change == "fortran" and x.ndim == 2:
            x = np.asfortranarray(np.concatenate([x, x], axis=1))[:, ::2]
        elif change == "float32" and x.dtype == np.float64:
            x = x.astype(np.float32)
        fields[k] = x
    val = GoalDistances(*fields)
    for _ in range(2):  # the second time from the kept types
        for purpose in (Purpose.argument, Purpose.constant):
            want = typeof_impl.dispatch(tuple)(val, _ctx(purpose))
            assert typeof(val, purpose) == want
    assert typeof(hs, Purpose.argument) == typeof_impl.dispatch(tuple)(hs, _ctx(
        Purpose.argument))
    expand_to(0, 0.3, lat.nbr, lat.dlen, hs)  # a compiled call given the tables


def _ctx(purpose):
    from numba.core.typing.typeof import _TypeofContext

    return _TypeofContext(purpose)
