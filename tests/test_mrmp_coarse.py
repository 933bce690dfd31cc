"""Gspi's fast paths at fleet scale: the coarse block graph and the fleet assignment over
it, the settled-value reads compiled into the step kernels, and neighbour lists cut
from larger ones."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fleet_checker import check_fleet_plan
from hypothesis import given, settings
from hypothesis import strategies as st
from mrmp_checker import check_plan

import lamp.mrmp.assignment as assignment
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp import plan_paths
from lamp.mrmp.coarse import BLOCK, get_coarse
from lamp.mrmp.distance_field import get_lattice
from lamp.mrmp.goal_distances import GoalDistances, expand_to, hval
from lamp.mrmp.heuristic_reads import hval_fast, hval_in, read_in, read_settled
from lamp.mrmp.links import link_special_vertices
from lamp.mrmp.neighbours import neighbour_lists, within
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
R = 0.05


def _setup(seed: int, n: int):
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, n, seed)
    space = RobotSpace.from_scene(gm.scene)
    lat = get_lattice(space, 0.03)
    c_s = space.clearance(S, exact=True)
    c_g = space.clearance(G, exact=True)
    links = link_special_vertices(space, lat, S, G, c_s, c_g, 0.045, {})
    hs = GoalDistances.build(links.goal_links, G, lat, 2 * n)
    return gm, S, G, lat, links, hs


def test_block_graph_is_symmetric_and_its_blocks_hold_their_nodes() -> None:
    _, _, _, lat, _, _ = _setup(0, 40)
    cg = get_coarse(lat)
    assert get_coarse(lat) is cg  # built once per lattice
    assert cg.unit == pytest.approx(BLOCK * lat.step)
    B = len(cg.rep)
    assert cg.block.min() == 0 and cg.block.max() == B - 1
    # every node's block is the square of BLOCK x BLOCK lattice indices it lies in
    key = (lat.vb // BLOCK) * 10_000 + lat.va // BLOCK
    for p in range(0, B, 7):
        assert len(np.unique(key[cg.block == p])) == 1
    for p in range(B):
        for s in range(8):
            q = cg.nbr[p, s]
            if q >= 0:
                assert p in cg.nbr[q].tolist()
                assert cg.wlen[p, s] == pytest.approx(cg.unit * (np.sqrt(2) if s in (0, 2, 5, 7)
                                                                 else 1.0))


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(32, 90), extra=st.integers(0, 10))
def test_coarse_assignment_gives_every_goal_a_robot_at_its_exact_distance(
        seed: int, n: int, extra: int) -> None:
    """Forced onto the coarse graph: every goal gets exactly one robot, each cost is the
    pair's exact lattice distance, the bound their largest; never below the exact B*."""
    used = []
    inner = assignment._coarse_bottleneck

    def spy(*args):
        got = inner(*args)
        used.append(got is not None)
        return got

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(assignment, "COARSE_NODES", -1.0)
        mp.setattr(assignment, "_coarse_bottleneck", spy)
        _coarse_case(seed, n, extra)
    assert used == [True]  # the first assign call took the coarse way


def _coarse_case(seed: int, n: int, extra: int) -> None:
    gm, S, G, lat, links, hs = _setup(seed, n + extra)
    G = G[:n]
    hs = GoalDistances.build(links.goal_links[:n], G, lat, 2 * (n + extra))
    N, M = len(S), len(G)
    got = assignment.assign(links.graph, lat.V, hs, S, G, np.zeros(M, bool), "bottleneck",
                            None, np.inf, get_coarse(lat))
    assert got.goal is not None
    held = got.goal >= 0
    assert sorted(got.goal[held].tolist()) == list(range(M))
    ref = GoalDistances.build(links.goal_links[:n], G, lat, 2 * (n + extra))
    exact = np.array([hval(int(got.goal[i]), lat.V + i, links.graph, lat.V, lat.V + N, ref)
                      for i in np.nonzero(held)[0]])
    assert np.array_equal(got.cost[held], exact)
    assert got.bound == exact.max()
    hs2 = GoalDistances.build(links.goal_links[:n], G, lat, 2 * (n + extra))
    best = assignment.assign(links.graph, lat.V, hs2, S, G, np.zeros(M, bool), "bottleneck",
                             None, np.inf, None)
    assert got.bound >= best.bound - 1e-12


def test_fleet_plan_over_the_coarse_assignment_passes_both_checkers(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(assignment, "COARSE_NODES", -1.0)
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, 70, 3)
    plan = plan_paths(gm.scene, S, G, seed=3, time_limit=600.0)
    assert plan.success, plan.reason
    assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, R) == []
    check_plan(gm.scene, S, G, plan)
    again = plan_paths(gm.scene, S, G, seed=3, time_limit=600.0)
    assert np.array_equal(plan.paths, again.paths)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), bound=st.floats(0.0, 2.0))
def test_fast_heuristic_reads_equal_hval(seed: int, bound: float) -> None:
    """``hval_fast`` and ``hval_in`` (settled values read in place) give ``hval``'s value
    for lattice nodes and special vertices, settled or not, after any partial expansion;
    ``read_in`` (tables passed in) reads what ``read_settled`` reads: -1 or that value."""
    _, S, G, lat, links, hs = _setup(seed % 50, 40)
    ref = GoalDistances.build(links.goal_links, G, lat, 80)
    gr, V = links.graph, lat.V
    expand_to(0, bound, gr.nbr, gr.dlen, hs)
    rng = np.random.default_rng(seed)
    for v in np.concatenate([rng.integers(0, V, 60), V + np.arange(0, 80, 7)]).tolist():
        m = int(rng.integers(0, 2))
        w = hs.win
        # in-place reads (tables passed in, or read from the tuple): -1 or the value
        got = read_in(m, v, V, hs.va, hs.vb, hs.sdone, hs.sval, hs.dist[m], hs.done[m],
                      *w[m, :4].tolist())
        assert got == read_settled(m, v, V, hs, hs.dist[m], hs.done[m], *w[m, :4].tolist())
        b = hval(m, v, gr, V, V + 40, ref)
        assert got == -1.0 or got == b or (np.isinf(got) and np.isinf(b))
        a = hval_fast(m, v, gr, V, V + 40, hs)
        assert a == b or (np.isinf(a) and np.isinf(b))
        c = hval_in(m, v, gr, V, V + 40, hs, hs.win, hs.va, hs.vb, hs.sdone, hs.sval)
        assert c == b or (np.isinf(c) and np.isinf(b))


@settings(max_examples=30, deadline=None)
@given(pts=st.lists(st.tuples(st.floats(0, 3), st.floats(0, 3)), min_size=32, max_size=90),
       radius=st.floats(0.01, 1.5), cut=st.floats(0.0, 1.0))
def test_lists_cut_to_a_smaller_radius_are_its_lists(pts, radius, cut) -> None:
    P = np.array(pts, dtype=float)
    px, py = P[:, 0].copy(), P[:, 1].copy()
    ptr, idx = neighbour_lists(px, py, radius)
    small = radius * cut
    p2, i2 = within(ptr, idx, px, py, small)
    want_p, want_i = neighbour_lists(px, py, small)
    assert np.array_equal(p2, want_p) and np.array_equal(i2, want_i)


def test_coarse_assignment_past_its_deadline_stops_without_the_exact_one() -> None:
    """Past the deadline the coarse way returns at its first check (timed out), or its
    assignment when the first bound already matches; it never falls back to the exact
    searches then."""
    gm, S, G, lat, links, hs = _setup(5, 80)

    def exact(*args):
        raise AssertionError("the exact assignment ran past the deadline")

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(assignment, "COARSE_NODES", -1.0)
        mp.setattr(assignment, "_bottleneck", exact)
        got = assignment.assign(links.graph, lat.V, hs, S, G, np.zeros(len(G), bool),
                                "bottleneck", None, 0.0, get_coarse(lat))
    assert got.timed_out or got.goal is not None
