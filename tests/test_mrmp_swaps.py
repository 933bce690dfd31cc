"""Gspi's goal swaps (``gspi_swaps.swap_goals``) against a plain reference of the
rule, with and without the values kept from the step before (Hypothesis)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.distance_field import get_lattice
from lamp.mrmp.goal_distances import GoalDistances, hval
from lamp.mrmp.gspi_swaps import swap_goals
from lamp.mrmp.links import link_special_vertices
from lamp.mrmp.neighbours import neighbour_lists
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"


def _reference(gr, V, gv0, hs, cur, goal, prio, sptr, sidx, cool, fleet) -> None:
    """The swap rule of ``swap_goals``'s docstring, every value read afresh."""
    coords = gr[0]

    def h(g: int, v: int) -> float:
        return hval(g, v, gr, V, gv0, hs) if g >= 0 else 0.0

    for i in range(len(cur)):
        for j in sidx[sptr[i]:sptr[i + 1]].tolist():
            if j <= i or cool[i] > 0 or cool[j] > 0:
                continue
            gi, gj = int(goal[i]), int(goal[j])
            if gi < 0 and gj < 0:
                continue
            if fleet and gi >= 0 and gj >= 0 and cur[i] != gv0 + gi and cur[j] != gv0 + gj:
                continue
            hi, hj = h(gi, cur[i]), h(gj, cur[j])
            la = math.hypot(*(coords[cur[j]] - coords[gv0 + gi])) if gi >= 0 else 0.0
            lb = math.hypot(*(coords[cur[i]] - coords[gv0 + gj])) if gj >= 0 else 0.0
            if la + lb >= hi + hj - 1e-9 and (not fleet or max(la, lb) >= max(hi, hj) - 1e-9):
                continue
            if fleet and max(la, lb) > max(hi, hj) + 1e-9:
                continue
            sa, sb = h(gi, cur[j]), h(gj, cur[i])
            if fleet:
                better = max(sa, sb) < max(hi, hj) - 1e-9 or (
                    max(sa, sb) <= max(hi, hj) + 1e-9 and sa + sb < hi + hj - 1e-9)
            else:
                better = sa + sb < hi + hj - 1e-9
            if better:
                goal[i], goal[j] = gj, gi
                prio[i], prio[j] = prio[j], prio[i]


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 40), fleet=st.booleans(),
       kept=st.floats(0.0, 1.0))
def test_swaps_match_the_rule_with_or_without_kept_values(seed, n, fleet, kept) -> None:
    """Robots at their starts, on their goals or on a lattice node by their start, some
    without a goal, some sitting out: the same swaps as the reference, whether the
    robots' values come kept (a random share of them) or are read afresh."""
    rng = np.random.default_rng(seed)
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, n, seed)
    M = int(rng.integers(1, n + 1))
    G = G[:M]
    space = RobotSpace.from_scene(gm.scene)
    lat = get_lattice(space, 0.03)
    N, V = n, lat.V
    gv0 = V + N
    links = link_special_vertices(space, lat, S, G, space.clearance(S, exact=True),
                                  space.clearance(G, exact=True), 0.045, {})
    gr = links.graph
    goal = np.full(N, -1, np.int64)
    goal[rng.permutation(N)[:M]] = np.arange(M)
    cur = np.arange(V, V + N, dtype=np.int64)
    for i in range(N):
        r = rng.random()
        if r < 0.4 and goal[i] >= 0:
            cur[i] = gv0 + goal[i]
        elif r < 0.7 and gr[3][V + i + 1] > gr[3][V + i]:
            cur[i] = gr[4][gr[3][V + i]]
    prio = rng.random(N)
    cool = (rng.random(N) < 0.1).astype(np.int64)
    xy = gr[0][cur]
    sptr, sidx = neighbour_lists(xy[:, 0].copy(), xy[:, 1].copy(), 1.5)
    results = []
    for mode in ("reference", "fresh", "kept"):
        hs = GoalDistances.build(links.goal_links, G, lat, N + M)
        g, p = goal.copy(), prio.copy()
        if mode == "reference":
            _reference(gr, V, gv0, hs, cur, g, p, sptr, sidx, cool, fleet)
        else:
            hcur, hgoal = np.zeros(N), np.full(N, -1, np.int64)
            if mode == "kept":
                for i in np.flatnonzero((rng.random(N) < kept) & (goal >= 0)).tolist():
                    hcur[i] = hval(int(goal[i]), int(cur[i]), gr, V, gv0, hs)
                    hgoal[i] = goal[i]
            swap_goals(gr, V, gv0, hs, cur, g, p, sptr, sidx, cool, fleet, hcur, hgoal)
        results.append((g, p))
    for g, p in results[1:]:
        assert np.array_equal(g, results[0][0])
        assert np.array_equal(p, results[0][1])


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 60), swap=st.booleans())
def test_steps_sum_the_values_read_afresh(seed, n, swap) -> None:
    """The summed heuristic after each step (the values kept from the candidates) is the
    sum of every robot's value to its goal read afresh; with goal swaps, at the last
    step (the goals it ends with)."""
    from lamp.mrmp.assignment import assign
    from lamp.mrmp.gspi_kernels import run_steps

    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, n, seed)
    space = RobotSpace.from_scene(gm.scene)
    lat = get_lattice(space, 0.03)
    V, gv0 = lat.V, lat.V + n
    links = link_special_vertices(space, lat, S, G, space.clearance(S, exact=True),
                                  space.clearance(G, exact=True), 0.045, {})
    gr = links.graph
    hs = GoalDistances.build(links.goal_links, G, lat, 2 * n)
    goal = assign(gr, V, hs, S, G, np.zeros(n, bool), "bottleneck", None, np.inf).goal
    assert goal is not None
    K = 12
    cur = np.arange(V, V + n, dtype=np.int64)
    hist = np.empty((K + 1, n), np.int64)
    hist[0] = cur
    hsum = np.zeros(K + 1)
    near = 0.1 + 2 * links.max_move + 1e-9
    t, _ = run_steps(gr, V, gv0, hs, cur, goal, np.random.default_rng(seed).random(n), 0.1,
                     seed, swap, hist, hsum, 0, K, links.max_candidates, near, 2 * near,
                     np.zeros((2, n), np.int64), np.full(n, np.inf), n >= 32)
    ref = GoalDistances.build(links.goal_links, G, lat, 2 * n)
    for s in ([t] if swap else range(1, t + 1)):
        want = sum(min(hval(int(goal[i]), int(hist[s, i]), gr, V, gv0, ref), 1e6)
                   for i in range(n) if hist[s, i] != gv0 + goal[i])
        assert hsum[s] == want
