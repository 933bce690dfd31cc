"""Gspi's links of starts and goals (``lamp.mrmp.links``): a lattice on which some goal
has no lattice node within the link radius and no direct link from a start fails before
any link is checked, with only such goals named; otherwise the links are those of the
full check. ``Lattice.any_node_near`` against ``nodes_near``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.distance_field import clear_segments, get_lattice
from lamp.mrmp.links import Links, link_special_vertices
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
_SPACES: dict[str, tuple] = {}


def _space(name: str):
    if name not in _SPACES:
        gm = load_grid_map(MAPF / f"{name}.map", 0.15, 0.05)
        _SPACES[name] = gm, RobotSpace.from_scene(gm.scene)
    return _SPACES[name]


def _full_lone(space, lat, S, G, R) -> np.ndarray:
    """The goals with no checked link to the lattice and none from a start within R (the
    complete check, link by link)."""
    thr = space.threshold
    c_s, c_g = space.clearance(S, exact=True), space.clearance(G, exact=True)
    links = lat.links(G, R, np.minimum(thr, c_g), c_g)
    lone = np.array([len(n) == 0 for n, _ in links])
    for m in np.flatnonzero(lone):
        near = np.flatnonzero(np.hypot(*(S - G[m]).T) <= R)
        lone[m] = not clear_segments(space.geometry, space.workspace, S[near],
                                     np.repeat(G[m:m + 1], len(near), 0),
                                     np.minimum(thr, np.minimum(c_s[near], c_g[m]))).any()
    return lone


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), step=st.sampled_from([0.05, 0.03]),
       name=st.sampled_from(["random-32-32-20", "random-64-64-20"]),
       radius=st.sampled_from([0.03, 0.045, 0.075]))
def test_any_node_near_is_nodes_near_not_empty(seed, step, name, radius) -> None:
    """Random points over and beyond the map (cell centres among them): a node is near
    exactly where ``nodes_near`` finds one."""
    gm, space = _space(name)
    lat = get_lattice(space, step)
    rng = np.random.default_rng(seed)
    W, H = space.workspace
    pts = np.concatenate([rng.uniform(-0.1, 1.0, (60, 2)) * (W + 0.2, H + 0.2) - 0.1,
                          gm.cell_centres()[rng.choice(len(gm.cell_centres()), 60)]])
    want = np.array([len(lat.nodes_near(p, radius)) > 0 for p in pts])
    assert np.array_equal(lat.any_node_near(pts, radius), want)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 160),
       name=st.sampled_from(["random-32-32-20", "random-64-64-20"]),
       step=st.sampled_from([0.05, 0.03]), near_start=st.booleans())
def test_links_fail_early_only_where_the_full_check_fails(seed, n, name, step,
                                                          near_start) -> None:
    """Random cell-centre instances (some with a start beside each goal, so that a goal
    without lattice links may still be reached directly): the links fail exactly when
    the complete check leaves a goal without any link; the goals named are among those
    it leaves, and the links made are the complete check's."""
    gm, space = _space(name)
    lat = get_lattice(space, step)
    S, G = random_instance(gm, n, seed)
    if near_start:  # starts 4 cm from the goals, where free: direct links
        off = G + (0.04, 0.0)
        ok = space.clearance(off, exact=True) >= space.threshold
        S = np.where(ok[:, None], off, S)
        _, first = np.unique(S.round(6), axis=0, return_index=True)
        keep = np.sort(first)
        S, G = S[keep], G[keep]
    R = 1.5 * step
    c_s, c_g = space.clearance(S, exact=True), space.clearance(G, exact=True)
    got = link_special_vertices(space, lat, S, G, c_s, c_g, R, {})
    full = _full_lone(space, lat, S, G, R)
    if isinstance(got, Links):
        assert not full.any()
        thr = space.threshold
        want = lat.links(G, R, np.minimum(thr, c_g), c_g)
        for (a, la), (b, lb) in zip(got.goal_links, want, strict=True):
            assert np.array_equal(a, b) and np.array_equal(la, lb)
    else:
        assert got.any() and full.any()
        assert not (got & ~full).any()


def test_a_fleet_fails_on_the_5cm_lattice_before_linking() -> None:
    """400 cell-centre goals on ``random-64-64-20``: the 5 cm lattice fails on goals with
    no node within reach (a subset of the complete check's), and no link is checked (no
    goal links in the stats); the 3 cm lattice links every goal."""
    gm, space = _space("random-64-64-20")
    S, G = random_instance(gm, 400, 0)
    c_s, c_g = space.clearance(S, exact=True), space.clearance(G, exact=True)
    lat = get_lattice(space, 0.05)
    stats: dict = {}
    got = link_special_vertices(space, lat, S, G, c_s, c_g, 0.075, stats)
    assert not isinstance(got, Links) and got.any() and "goal_links" not in stats
    assert not lat.any_node_near(G[got], 0.075).any()
    assert not (got & ~_full_lone(space, lat, S, G, 0.075)).any()
    lat3 = get_lattice(space, 0.03)
    assert isinstance(link_special_vertices(space, lat3, S, G, c_s, c_g, 0.045, {}), Links)
