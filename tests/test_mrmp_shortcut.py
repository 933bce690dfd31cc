"""Any-angle shortcuts of fleet plans (``lamp.mrmp.shortcut``): against a brute-force
reference of the rule every synchronised row keeps, on random small plans; inside
``plan_paths``, with both independent checkers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fleet_checker import check_fleet_plan
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from mrmp_checker import check_plan

import lamp.mrmp.gspi as gspi
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp import MRMPPlan, plan_paths
from lamp.mrmp.retime import densify
from lamp.mrmp.shortcut import shortcut_rows
from lamp.scene.mapf import load_grid_map, random_instance
from lamp.scene.model import Circle, Obstacle, Scene

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
R = 0.05
L = 0.03
MOVES = [(dx, dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1)]


def _pair_ok(a, b, c, d, two_r=2 * R) -> bool:
    """Reference rule for two robots moving a->b and c->d over one row: their closest
    approach (origin to the segment of relative offsets, closed form) is at least
    ``min(2r, distance at the row's start)``."""
    p, q = np.subtract(a, c), np.subtract(b, d)
    u = q - p
    den = float(u @ u)
    s = 0.0 if den == 0.0 else min(1.0, max(0.0, -float(p @ u) / den))
    closest = float(np.hypot(*(p + s * u)))
    return closest >= min(two_r, float(np.hypot(*p))) - 1e-9


def _rows_ok(P: np.ndarray, space: RobotSpace) -> bool:
    """Every row of ``P`` ((K+1, N, 2)): every pair keeps the reference rule, every move
    keeps the space's threshold from the obstacles (exact)."""
    K1, N, _ = P.shape
    for t in range(K1 - 1):
        for i in range(N):
            for j in range(i + 1, N):
                if not _pair_ok(P[t, i], P[t + 1, i], P[t, j], P[t + 1, j]):
                    return False
    a = P[:-1].reshape(-1, 2)
    b = P[1:].reshape(-1, 2)
    return bool(space.segment_free(a, b).all())


def _lengths(P: np.ndarray) -> np.ndarray:
    return np.hypot(*np.diff(P, axis=0).transpose(2, 0, 1))  # (K, N)


def _random_plan(rng: np.random.Generator, space: RobotSpace, n: int, k: int) -> np.ndarray:
    """A synchronised plan of n lattice walks of k rows keeping the reference rules: each
    robot in turn picks a random move among those clear of the robots already moved in
    the row (waiting last); None when even waiting is not."""
    W, H = space.workspace
    P = np.empty((k + 1, n, 2))
    cells = rng.choice(int(W / L - 4) * int(H / L - 4), size=n, replace=False)
    P[0, :, 0] = (cells % int(W / L - 4) + 2) * L
    P[0, :, 1] = (cells // int(W / L - 4) + 2) * L
    if not space.is_free(P[0], exact=True).all():
        return None
    drift = rng.integers(-1, 2, size=(n, 2))
    for t in range(k):
        for i in range(n):
            order = [MOVES[m] for m in rng.permutation(9)]
            order = sorted(order, key=lambda m: (m == (0, 0), -int(np.dot(m, drift[i]))))
            for dx, dy in order:
                b = P[t, i] + (dx * L, dy * L)
                if not space.segment_free(P[t, i][None], b[None])[0]:
                    continue
                if all(_pair_ok(P[t, i], b, P[t, j], P[t + 1, j]) for j in range(i)):
                    P[t + 1, i] = b
                    break
            else:
                return None
    return P


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(1, 5), k=st.integers(2, 24),
       obstacles=st.lists(st.tuples(st.floats(0.1, 1.1), st.floats(0.1, 1.1),
                                    st.floats(0.02, 0.15)), max_size=3),
       window=st.integers(2, 20))
def test_shortcuts_keep_every_row_valid_against_a_brute_force_reference(
        seed, n, k, obstacles, window) -> None:
    """Random valid synchronised plans: the shortcut rows keep the reference rules (every
    pair in every row, exact obstacle clearance), every robot's first and last positions,
    and no move is longer than before, so no path is either."""
    sc = Scene("shortcut", (1.2, 1.2), ((0.1, 0.1),), (),
               tuple(Obstacle(Circle(r), (x, y, 0.0)) for x, y, r in obstacles))
    space = RobotSpace.from_scene(sc)
    P = _random_plan(np.random.default_rng(seed), space, n, k)
    assume(P is not None and _rows_ok(P, space))
    cost = _lengths(P).sum(axis=0)
    out, done = shortcut_rows(P, np.zeros(P.shape[:2], bool), cost, 2 * R,
                              L * np.sqrt(2), space.geometry, space.workspace,
                              space.threshold, 0.0, window)
    assert _rows_ok(out, space)
    assert np.array_equal(out[0], P[0]) and np.array_equal(out[-1], P[-1])
    if out.shape[0] == P.shape[0]:
        assert np.all(_lengths(out) <= _lengths(P) + 1e-12)
    assert np.all(_lengths(out).sum(axis=0) <= _lengths(P).sum(axis=0) + 1e-9)
    if done == 0:
        assert np.array_equal(out, P)


@settings(max_examples=30, deadline=None)
@given(steps=st.lists(st.sampled_from(MOVES[:4] + MOVES[5:]), min_size=2, max_size=15))
def test_a_lone_robot_in_the_open_goes_straight(steps) -> None:
    """With nothing in the way and a window as long as the path, the path becomes the
    straight line from its start to its end (the reference: their distance)."""
    sc = Scene("open", (3.0, 3.0), ((1.5, 1.5),), (), ())
    space = RobotSpace.from_scene(sc)
    P = np.empty((len(steps) + 1, 1, 2))
    P[0, 0] = (1.5, 1.5)
    for t, (dx, dy) in enumerate(steps):
        P[t + 1, 0] = P[t, 0] + (dx * L, dy * L)
    out, _ = shortcut_rows(P, np.zeros((len(P), 1), bool), np.ones(1), 2 * R,
                           L * np.sqrt(2), space.geometry, space.workspace, space.threshold,
                           0.0, len(steps))
    line = float(np.hypot(*(P[-1, 0] - P[0, 0])))
    assert _lengths(out).sum() == pytest.approx(line, abs=1e-9)


def test_shortcuts_inside_plan_paths_pass_both_checkers() -> None:
    """The shortcut stage, spied on inside plan_paths (120 robots): its rows, densified
    as synchronised steps, pass both independent checkers; no move got longer, the
    latest robots' paths got shorter, and the plan passes too."""
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, 120, 5)
    seen = {}
    real = gspi.shortcut_rows

    def spy(P, isgoal, cost, *rest):
        out = real(P, isgoal, cost, *rest)
        seen.update(before=np.array(P), after=out[0].copy(), done=out[1])
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "shortcut_rows", spy)
        plan = plan_paths(gm.scene, S, G, seed=5, time_limit=600.0)
    assert plan.success and seen["done"] > 0
    before, after = seen["before"], seen["after"]
    assert before.shape == after.shape
    assert np.all(_lengths(after) <= _lengths(before) + 1e-12)
    assert _lengths(after).sum() < _lengths(before).sum()
    rows = densify(after, 0.02)
    out = MRMPPlan(True, rows, plan.goal_of, "", 0, 0.0, {})
    for p in (out, plan):
        assert check_fleet_plan(gm.scene.to_dict(), S, G, p, R) == []
        check_plan(gm.scene, S, G, p)


@settings(max_examples=30, deadline=None)
@given(n=st.integers(4, 15), m=st.integers(4, 15), t=st.floats(0.09, 0.3))
def test_a_corner_around_an_obstacle_is_cut_only_where_clear(n, m, t) -> None:
    """A robot goes right, then up round a disk inside the corner that the straight line
    from its start to its end crosses: every move of the result keeps the threshold from
    the disk (exact), and the path is still shortened where it can be."""
    x0, y0 = 0.3, 0.3
    corner = np.array([x0 + n * L, y0])
    c = corner + t * np.array([-1.0, 1.0]) / np.sqrt(2)
    rc = t / np.sqrt(2) - R - 0.005
    assume(rc > 0.01)
    sc = Scene("corner", (1.5, 1.5), ((x0, y0),), (), (Obstacle(Circle(rc), (*c, 0.0)),))
    space = RobotSpace.from_scene(sc)
    P = np.array([[x0 + min(k, n) * L, y0 + max(0, k - n) * L] for k in range(n + m + 1)])
    P = P[:, None, :]
    assume(_rows_ok(P, space))
    assume(not space.segment_free(P[0], P[-1])[0])
    out, done = shortcut_rows(P, np.zeros((len(P), 1), bool), np.ones(1), 2 * R,
                              L * np.sqrt(2), space.geometry, space.workspace,
                              space.threshold, 0.0, n + m)
    assert _rows_ok(out, space)
    assert _lengths(out).sum() > float(np.hypot(*(P[-1, 0] - P[0, 0]))) + 1e-6
    assert done > 0 and _lengths(out).sum() < _lengths(P).sum()
