"""Gspi's fleet stage (teams of 32 robots or more): the last robots planned again
(``lamp.mrmp.repair``) and every robot at its own speed (``lamp.mrmp.retime``). Every
plan re-checked by both independent checkers; the stages checked on their own too."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fleet_checker import check_fleet_plan
from fleet_plans import row_makespan
from hypothesis import given, settings
from hypothesis import strategies as st
from mrmp_checker import check_plan

import lamp.mrmp.gspi as gspi
from lamp.mrmp import MRMPPlan, plan_paths
from lamp.mrmp.gspi import GspiStatus
from lamp.mrmp.gspi_kernels import ALL_PAIRS_BELOW
from lamp.mrmp.retime import densify, retime
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
R = 0.05


def _map(name: str = "random-32-32-20"):
    return load_grid_map(MAPF / f"{name}.map")


def _check_both(gm, S, G, plan) -> None:
    assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, R) == []
    check_plan(gm.scene, S, G, plan)


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(ALL_PAIRS_BELOW, 90))
def test_fleet_plans_are_valid_and_deterministic(seed: int, n: int) -> None:
    """A fleet on random-32-32-20 (4.8 m): solved, accepted by both checkers, the same plan
    twice; the fleet stage ran."""
    gm = _map()
    S, G = random_instance(gm, n, seed)
    plan = plan_paths(gm.scene, S, G, seed=seed, time_limit=600.0)
    assert plan.success, plan.reason
    assert plan.status is GspiStatus.SOLVED
    assert "repaired_paths" in plan.stats
    _check_both(gm, S, G, plan)
    again = plan_paths(gm.scene, S, G, seed=seed, time_limit=600.0)
    assert np.array_equal(plan.paths, again.paths)
    assert np.array_equal(plan.goal_of, again.goal_of)


def test_small_teams_keep_the_synchronised_plan() -> None:
    """Below ALL_PAIRS_BELOW robots (LAMP's Verify) the fleet stage does not run: every
    step is cut into equal sub-steps, all robots' moves of a step ending on one row."""
    gm = _map()
    S, G = random_instance(gm, ALL_PAIRS_BELOW - 1, 3)
    plan = plan_paths(gm.scene, S, G, seed=3, time_limit=600.0)
    assert plan.success and "repaired_paths" not in plan.stats
    _check_both(gm, S, G, plan)


def _sync_plan(seed: int, n: int):
    """A synchronised Gspi plan (the fleet stage left out) and its instance."""
    gm = _map()
    S, G = random_instance(gm, n, seed)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "ALL_PAIRS_BELOW", 10**9)  # the small-team output for any team
        plan = plan_paths(gm.scene, S, G, seed=seed, time_limit=600.0)
    assert plan.success, plan.reason
    return gm, S, G, plan


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 70), lazy=st.booleans(),
       quanta=st.sampled_from([3.0, 7.0, 20.0]))
def test_retime_keeps_each_path_and_every_clearance(seed, n, lazy, quanta) -> None:
    """Any synchronised plan retimed: each robot visits the same positions in the same
    order (so the same obstacle clearance), both checkers accept it, and its makespan is
    at most the synchronised plan's with every row rounded up to whole quanta."""
    gm, S, G, plan = _sync_plan(seed, n)
    P = np.ascontiguousarray(plan.paths.transpose(1, 0, 2))  # (rows, N, 2)
    q = 0.03 / quanta
    rows, mk = retime(P, 2 * R, q, 0.02, lazy=lazy)
    out = MRMPPlan(True, rows, plan.goal_of, "", plan.iterations, 0.0, {})
    _check_both(gm, S, G, out)
    for i in range(len(S)):
        a = P[:, i]
        a = a[np.concatenate([[True], np.any(a[1:] != a[:-1], axis=1)])]
        b = rows[i]
        b = b[np.concatenate([[True], np.any(b[1:] != b[:-1], axis=1)])]
        # the retimed rows lie on the original polyline and reach its corners in order
        k = 0
        for p in a:
            while k < len(b) and np.hypot(*(b[k] - p)) > 1e-9:
                k += 1
            assert k < len(b), f"robot {i} skips its position {p}"
    step = np.hypot(*np.diff(P, axis=0).transpose(2, 0, 1)).max(axis=1)
    bound = float((np.ceil(step / q - 1e-9) * q).sum())
    assert mk <= bound + 1e-9
    assert row_makespan(rows) <= mk + 1e-9


def test_retime_lets_a_robot_on_an_axis_go_at_full_speed() -> None:
    """Two robots far apart, one moving diagonally and one along an axis, synchronised:
    retimed, the axis robot arrives after its own length, not the diagonal one's."""
    L = 0.03
    d = L * np.sqrt(2)
    K = 20
    P = np.zeros((K + 1, 2, 2))
    P[:, 0] = np.stack([np.arange(K + 1) * L + 0.5, np.full(K + 1, 0.5)], 1)
    P[:, 1] = np.stack([np.arange(K + 1) * L + 0.5, np.arange(K + 1) * L + 2.0], 1)
    rows, mk = retime(P, 2 * R, L / 7, 0.02)
    assert mk == pytest.approx(K * 10 * L / 7)  # the diagonal: 10 quanta a step
    moving = np.any(np.diff(rows[0], axis=0) != 0, axis=1)
    arrive = np.nonzero(moving)[0].max() + 1
    t = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(rows, axis=1)
                                                  .transpose(2, 0, 1)).max(axis=0))])
    assert t[arrive] == pytest.approx(K * L, abs=1e-9)
    assert d * K == pytest.approx(mk, rel=0.011)


def test_retime_keeps_robots_in_contact_as_they_were() -> None:
    """Two robots starting closer than 2r (in contact after a push) and moving together:
    the retimed plan never brings them closer than the synchronised one did."""
    L = 0.03
    K = 10
    P = np.zeros((K + 1, 2, 2))
    P[:, 0] = np.stack([np.arange(K + 1) * L + 0.5, np.full(K + 1, 0.5)], 1)
    P[:, 1] = P[:, 0] + [0.0, 0.095]  # the same motion, 9.5 cm above
    rows, _ = retime(P, 2 * R, L / 7, 0.02)
    d = np.hypot(*(rows[0] - rows[1]).T)
    assert d.min() >= 0.095 - 1e-12


def test_repair_makes_the_last_arrival_no_later_and_keeps_the_plan_valid() -> None:
    """The repair stage, spied on inside plan_paths: its output rows, densified as
    synchronised steps, are accepted by both checkers, and the latest arrival estimate
    (moves' lengths and waits) is not larger than its input's."""
    gm = _map()
    S, G = random_instance(gm, 120, 5)
    seen = {}
    real = gspi.repair_last

    def spy(gr, V, gv0, hs, VX, goal, two_r, max_move, wait, budget, group, exch):
        out = real(gr, V, gv0, hs, VX, goal, two_r, max_move, wait, budget, group, exch)
        seen.update(before=VX.copy(), after=out[0].copy(), coords=gr[0], wait=wait,
                    goal=goal.copy())
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "repair_last", spy)
        plan = plan_paths(gm.scene, S, G, seed=5, time_limit=600.0)
    assert plan.success and seen
    coords = seen["coords"]

    def latest(VX):
        best = 0.0
        for i in range(VX.shape[1]):
            v = VX[:, i]
            a = len(v) - 1
            while a > 0 and v[a - 1] == v[-1]:
                a -= 1
            p = coords[v[: a + 1]]
            step = np.hypot(*np.diff(p, axis=0).T)
            best = max(best, float(np.where(v[1: a + 1] != v[:a], step, seen["wait"]).sum()))
        return best

    assert latest(seen["after"]) <= latest(seen["before"]) + 1e-9
    rows = densify(coords[seen["after"]], 0.02)
    out = MRMPPlan(True, rows, seen["goal"], "", 0, 0.0, {})
    _check_both(gm, S, G, out)
    ends = rows[seen["goal"] >= 0, -1]
    assert np.allclose(ends, G[seen["goal"][seen["goal"] >= 0]], atol=1e-9)


@settings(max_examples=20, deadline=None)
@given(pts=st.lists(st.tuples(st.floats(-0.3, 5.1), st.floats(-0.3, 5.1)), min_size=1,
                    max_size=30),
       radius=st.floats(0.0, 0.2), step=st.sampled_from([0.02, 0.03, 0.05]),
       window=st.booleans())
def test_nodes_near_all_matches_nodes_near(pts, radius, step, window) -> None:
    """The vectorised lookup of the links' candidate nodes: the same ids in the same
    order as one point at a time, in a whole map and in a window of it."""
    from lamp.geometry.robot_space import RobotSpace
    from lamp.mrmp.distance_field import get_lattice

    gm = _map()
    box = (1.0, 0.7, 3.9, 4.1) if window else None
    space = RobotSpace.from_scene(gm.scene, window=box)
    lat = get_lattice(space, step)
    P = np.array(pts, dtype=float)
    got = lat.nodes_near_all(P, radius)
    for p, g in zip(P, got, strict=True):
        assert g.tolist() == lat.nodes_near(p, radius).tolist()


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(65, 400), spread=st.floats(0.05, 1.0))
def test_endpoint_checks_at_fleet_size_match_the_dense_ones(seed, n, spread) -> None:
    """Starts and goals of fleets are checked by tiles and a k-d tree: the same exact
    clearances (bit for bit, points inside obstacles and far from all included) and the
    same first overlapping pair as the all-pairs, all-obstacles checks."""
    from lamp.geometry.robot_space import RobotSpace
    from lamp.mrmp import endpoints

    gm = _map()
    space = RobotSpace.from_scene(gm.scene)
    rng = np.random.default_rng(seed)
    P = rng.uniform(0, 4.8, (n, 2))
    P[: n // 4] = P[0] + rng.normal(0, spread * 0.1, (n // 4, 2))  # a cluster
    assert np.array_equal(endpoints.exact_clearance(space, P),
                          space.clearance(P, exact=True))
    limit = 2 * R * spread
    d = np.hypot(*(P[:, None, :] - P[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    close = np.argwhere(d < limit)
    want = (int(close[0, 0]), int(close[0, 1])) if len(close) else None
    assert endpoints._first_overlap(P, limit) == want
