"""Gspi at fleet scale: MAPF grid maps as scenes, the bottleneck assignment, neighbour
lists, and plans for a hundred robots re-checked by two independent checkers."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from fleet_checker import check_fleet_plan
from hypothesis import given, settings
from hypothesis import strategies as st
from mrmp_checker import check_plan

from lamp.errors import InputError
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp import plan_paths
from lamp.mrmp.assignment import assign
from lamp.mrmp.distance_field import get_lattice
from lamp.mrmp.goal_distances import GoalDistances
from lamp.mrmp.gspi_kernels import neighbour_lists
from lamp.mrmp.links import link_special_vertices
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"


def _write_map(tmp_path: Path, rows: list[str]) -> Path:
    p = tmp_path / "m.map"
    p.write_text(f"type octile\nheight {len(rows)}\nwidth {len(rows[0])}\nmap\n"
                 + "\n".join(rows) + "\n")
    return p


@settings(max_examples=30, deadline=None)
@given(grid=st.lists(st.lists(st.booleans(), min_size=5, max_size=5), min_size=4,
                     max_size=4))
def test_blocked_cells_become_exactly_their_rectangles(grid, tmp_path_factory) -> None:
    """The obstacle rectangles cover every blocked cell and no free one, and every free
    cell centre is at least half a cell from obstacles and border."""
    if all(all(r) for r in grid):
        grid[0][0] = False
    rows = ["".join("@" if b else "." for b in r) for r in grid]
    gm = load_grid_map(_write_map(tmp_path_factory.mktemp("m"), rows), cell=0.2)
    inside = np.zeros((4, 5), dtype=int)
    for o in gm.scene.obstacles:
        (w, h), (cx, cy, _) = o.shape.size, o.pose
        for r in range(4):
            for c in range(5):
                x, y = (c + 0.5) * 0.2, (3 - r + 0.5) * 0.2
                inside[r, c] += abs(x - cx) < w / 2 and abs(y - cy) < h / 2
    assert np.array_equal(inside, np.array(grid, dtype=int))  # each blocked cell once
    sp = RobotSpace.from_scene(gm.scene)
    clr = sp.clearance(gm.cell_centres(), exact=True)
    assert np.all(clr >= 0.1 - 1e-9)


def test_bad_map_files_are_refused_by_name(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="row 1, column 2: unknown cell 'x'"):
        load_grid_map(_write_map(tmp_path, ["....", "..x.", "...."]))
    (tmp_path / "h.map").write_text("type octile\nmap\n..\n")
    with pytest.raises(InputError, match="height"):
        load_grid_map(tmp_path / "h.map")
    with pytest.raises(InputError, match="cannot read"):
        load_grid_map(tmp_path / "missing.map")
    gm = load_grid_map(_write_map(tmp_path, ["..", ".@"]))
    with pytest.raises(InputError, match="do not fit"):
        random_instance(gm, 4)


@settings(max_examples=40, deadline=None)
@given(pts=st.lists(st.tuples(st.floats(0, 3), st.floats(0, 3)), min_size=0, max_size=80),
       radius=st.floats(0.01, 1.5))
def test_neighbour_lists_match_all_pairs(pts, radius) -> None:
    """The spatial hash finds exactly the other points within the radius, in index order
    (all others for teams below ALL_PAIRS_BELOW)."""
    P = np.array(pts, dtype=float).reshape(-1, 2)
    ptr, idx = neighbour_lists(P[:, 0].copy(), P[:, 1].copy(), radius)
    n = len(P)
    for i in range(n):
        got = idx[ptr[i]:ptr[i + 1]].tolist()
        if n < 32:
            want = [j for j in range(n) if j != i]
        else:
            d = np.hypot(*(P - P[i]).T)
            want = [j for j in range(n) if j != i and d[j] <= radius]
        assert got == want


def _instance(seed: int, n: int, m: int):
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, n, seed)
    return gm, S, G[:m]


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(1, 6), extra=st.integers(0, 2))
def test_bottleneck_assignment_against_brute_force(seed: int, n: int, extra: int) -> None:
    """Least longest distance, then least sum among those: checked against every
    assignment of robots to goals (exact distances from the lattice)."""
    gm, S, G = _instance(seed, n + extra, n)
    space = RobotSpace.from_scene(gm.scene)
    lat = get_lattice(space, 0.03)
    N, M = len(S), len(G)
    c_s = space.clearance(S, exact=True)
    c_g = space.clearance(G, exact=True)
    links = link_special_vertices(space, lat, S, G, c_s, c_g, 0.045, {})
    hs = GoalDistances.build(links.goal_links, G, lat, N + M)
    no_link = np.zeros(M, bool)
    got = assign(links.graph, lat.V, hs, S, G, no_link, "bottleneck", None, np.inf)
    ref = GoalDistances.build(links.goal_links, G, lat, N + M)
    from lamp.mrmp.goal_distances import hval

    C = np.array([[hval(m, lat.V + i, links.graph, lat.V, lat.V + N, ref) for m in range(M)]
                  for i in range(N)])
    best = (np.inf, np.inf)
    for robots in itertools.permutations(range(N), M):
        c = C[list(robots), range(M)]
        best = min(best, (float(c.max()), float(c.sum())))
    assert got.goal is not None
    held = got.goal >= 0
    assert sorted(got.goal[held].tolist()) == list(range(M))
    c = C[np.nonzero(held)[0], got.goal[held]]
    assert c.max() == pytest.approx(best[0], abs=1e-9)
    assert c.sum() == pytest.approx(best[1], abs=1e-9)
    assert got.bound == pytest.approx(best[0], abs=1e-9)


def test_a_hundred_robots_on_a_mapf_map_are_valid_and_deterministic() -> None:
    """100 robots on random-32-32-20 (4.8 m): solved, accepted by the fleet checker, and
    the same plan twice."""
    gm, S, G = _instance(0, 100, 100)
    plan = plan_paths(gm.scene, S, G, time_limit=600.0)
    assert plan.success, plan.reason
    assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, gm.scene.robot_radius) == []
    again = plan_paths(gm.scene, S, G, time_limit=600.0)
    assert np.array_equal(plan.paths, again.paths)
    assert np.array_equal(plan.goal_of, again.goal_of)


@pytest.mark.parametrize("assignment", ["bottleneck", "sum"])
def test_both_checkers_accept_and_reject_the_same_plans(assignment: str) -> None:
    """30 robots: the reference checker and the fleet checker accept the plan; a robot
    driven through an obstacle and two robots made to meet are rejected by both."""
    gm, S, G = _instance(3, 30, 24)
    plan = plan_paths(gm.scene, S, G, time_limit=600.0, assignment=assignment)
    assert plan.success, plan.reason
    check_plan(gm.scene, S, G, plan)
    d = gm.scene.to_dict()
    assert check_fleet_plan(d, S, G, plan, 0.05) == []
    block = gm.cell_centres(free=False)[0]
    for how in ("obstacle", "robots"):
        bad = plan.paths.copy()
        t = bad.shape[1] // 2
        if how == "obstacle":
            bad[0, t] = block
            bad[0, t - 1] = block + 0.01
            bad[0, t + 1] = block - 0.01
        else:
            bad[1, t] = bad[2, t]
        forged = type(plan)(False, bad, plan.goal_of, "forged", 0, 0.0, {},
                            plan.status.__class__("stalled"))
        assert check_fleet_plan(d, S, G, forged, 0.05, max_spacing=1e9)
        with pytest.raises(AssertionError):
            check_plan(gm.scene, S, G, forged, max_spacing=1e9)


def test_assignment_and_swap_radius_are_validated() -> None:
    gm, S, G = _instance(0, 3, 3)
    with pytest.raises(InputError, match="assignment"):
        plan_paths(gm.scene, S, G, assignment="greedy")
    with pytest.raises(InputError, match="swap_radius"):
        plan_paths(gm.scene, S, G, swap_radius=-1.0)


def test_a_robot_resting_in_a_pocket_lets_the_other_in() -> None:
    """A one-cell-wide pocket on random-64-64-20 (bottom row, columns 33-34): robot 0
    rests on its goal at the pocket's mouth, robot 1 must pass it to reach the inner cell.
    PIBT alone stalls (each blocks the other's last move); the deadlock rule trades their
    goals and keeps the trade, so robot 0 moves in and robot 1 takes its place."""
    gm = load_grid_map(MAPF / "random-64-64-20.map")
    assert gm.blocked[63, 32] and gm.blocked[63, 35] and gm.blocked[62, 34]
    G = np.array([[5.025, 0.075], [5.175, 0.075]])
    for S in (np.array([[5.025, 0.075], [5.025, 0.375]]), np.array([[5.025, 0.375],
                                                                      [5.025, 0.075]])):
        plan = plan_paths(gm.scene, S, G, time_limit=600.0, lattice_step=0.03)
        assert plan.success, plan.reason
        assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, 0.05) == []
