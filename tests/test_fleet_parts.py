"""The fleet schedule's parts, each against a simple reference: coroutine turns, the
re-timing of rows on the shared grid, robot allocation, and the space-time test of two
segments (``spacetime.compatible``: when it holds, a row-by-row brute force finds every
robot and object clear)."""

from __future__ import annotations

import math
import subprocess
import sys
import threading

import numpy as np
import pytest
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st

from lamp.contract.model import MAX_ROBOTS
from lamp.fleet.admission import CROSSING, crosses, meets_moving, meets_standing
from lamp.fleet.config import CLAIM_NEAR
from lamp.fleet.regions import (
    CLAIM_BLOCK,
    OBJECT_MARGIN,
    ROBOT_MARGIN,
    STATIC_SLACK,
    ClaimBlocks,
    claim,
    claims,
    footprints,
    swept,
)
from lamp.fleet.segments import Segment, on_grid
from lamp.fleet.spacetime import PUSH_LEAD, PUSH_SPEEDUP, compatible, halted, halted_by
from lamp.fleet.teams import (
    GROW_REACH,
    MIN_TEAM,
    allocate,
    chain_depths,
    least_conflict_order,
    near_way,
    reinforce,
    stands_in_way,
    start_order,
)
from lamp.fleet.turns import Turns
from lamp.geometry.primitives import Circle, Polygon
from lamp.geometry.shapes import to_shapely, to_shapely_many
from lamp.scene import scene_from_dict
from lamp.scene.model import Obstacle, Rectangle, Scene, SceneObject

R = 0.05
STEP = 0.02

# ------------------------------------------------------------------ turns


def test_turns_run_one_thread_at_a_time_in_the_schedulers_order() -> None:
    turns = Turns()
    log: list[str] = []
    running = threading.Semaphore(1)

    def body(k: int) -> None:
        for i in range(3):
            assert running.acquire(blocking=False), "two threads ran at once"
            log.append(f"{k}.{i}")
            running.release()
            turns.pause(k)

    for k in range(3):
        turns.start(k, lambda k=k: body(k))
    order = [2, 0, 1, 1, 0, 2, 0, 1, 2, 0, 1, 2]
    for k in order:
        if not turns.finished(k):
            turns.resume(k)
    assert log == ["2.0", "0.0", "1.0", "1.1", "0.1", "2.1", "0.2", "1.2", "2.2"]
    assert all(turns.finished(k) for k in range(3))
    turns.close()


def test_an_exception_in_a_thread_is_raised_by_resume() -> None:
    turns = Turns()

    def body() -> None:
        turns.pause(0)
        raise KeyError("inside")

    turns.start(0, body)
    turns.resume(0)
    with pytest.raises(KeyError, match="inside"):
        turns.resume(0)
    turns.close()


def test_close_ends_paused_threads() -> None:
    turns = Turns()
    reached = []

    def body() -> None:
        turns.pause(0)
        reached.append("after")  # never: closed while paused

    turns.start(0, body)
    turns.resume(0)
    turns.close()
    assert turns.finished(0) and reached == []


_ARENAS_PROBE = r"""
import ctypes, ctypes.util, os, sys, tempfile
from lamp.fleet.turns import MALLOC_ARENAS, Turns
turns = Turns()
keep = []
def body(k):
    keep.append([bytearray(1000) for _ in range(2000)])  # malloc in this thread
    turns.pause(k)  # alive, as a loop waiting on its executor
for k in range(8):
    turns.start(k, lambda k=k: body(k))
    turns.resume(k)
libc = ctypes.CDLL(ctypes.util.find_library("c"))
libc.fopen.restype = ctypes.c_void_p
libc.fopen.argtypes = [ctypes.c_char_p, ctypes.c_char_p]
libc.malloc_info.argtypes = [ctypes.c_int, ctypes.c_void_p]
libc.fclose.argtypes = [ctypes.c_void_p]
path = os.path.join(tempfile.mkdtemp(), "malloc.xml")
fp = libc.fopen(path.encode(), b"w")
libc.malloc_info(0, fp)
libc.fclose(fp)
print(open(path).read().count("<heap nr="), MALLOC_ARENAS)
turns.close()
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc arenas")
def test_fleet_threads_share_malloc_arenas() -> None:
    """Eight live loop threads, each having allocated, leave the process with at most
    ``MALLOC_ARENAS`` malloc heaps (glibc otherwise gives each thread its own)."""
    out = subprocess.run([sys.executable, "-c", _ARENAS_PROBE], capture_output=True,
                         text=True, check=True).stdout.split()
    heaps, cap = int(out[0]), int(out[1])
    assert 1 <= heaps <= cap


_MMAP_PROBE = r"""
import ctypes, numpy as np
from lamp.fleet.turns import Turns
class MI(ctypes.Structure):
    _fields_ = [(n, ctypes.c_size_t) for n in ("arena", "ordblks", "smblks", "hblks",
                "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]
libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = MI
Turns()
big = np.ones(8 << 20, np.uint8)
del big  # freed: glibc would now raise its threshold to 8 MB
before = libc.mallinfo2().hblkhd
mid = np.ones(400 << 10, np.uint8)  # 400 kB
print(libc.mallinfo2().hblkhd - before)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc")
def test_fleet_pins_the_mmap_threshold() -> None:
    """Once a fleet starts, an array of a few hundred kB allocated after a larger one was
    freed is still mapped on its own (handed back when freed), not cut from the heap."""
    out = subprocess.run([sys.executable, "-c", _MMAP_PROBE], capture_output=True,
                         text=True, check=True).stdout.split()
    assert int(out[0]) >= 400 << 10


# ------------------------------------------------------------------ the grid

#: steps of up to 5 cm; no subnormal coordinates (GEOS, the reference, projects a point
#: onto a segment 5e-324 m off the axis without the precision the check needs)
_step = st.floats(-0.05, 0.05, allow_subnormal=False)
paths_st = st.integers(1, 3).flatmap(lambda n: st.lists(
    st.lists(st.tuples(_step, _step), min_size=n, max_size=n), min_size=1, max_size=25))


@settings(max_examples=80)
@given(paths_st)
@example([[(0.0, 6.102307671045676e-249)]])  # a leg GEOS cannot locate a point on
@example([[(0.0, 0.0)], [(0.3, 0.0)]])
def test_on_grid_keeps_the_route_and_steps_at_most_a_row(steps) -> None:
    """Reference: each robot's polyline; re-timed rows lie on it, in order, no step longer
    than the row step, and the last row is the paths' last."""
    deltas = np.array(steps, float).transpose(1, 0, 2)  # (N, T, 2)
    start = np.zeros((deltas.shape[0], 2))
    paths = start[:, None] + np.cumsum(deltas, axis=1)
    rows = on_grid(start, paths, STEP)
    assert rows.shape[0] == paths.shape[0] and rows.shape[1] >= 1
    np.testing.assert_allclose(rows[:, -1], paths[:, -1], atol=1e-12)
    way = np.concatenate([start[:, None], rows], axis=1)
    assert np.hypot(*np.moveaxis(np.diff(way, axis=1), 2, 0)).max() <= STEP + 1e-9
    for i in range(paths.shape[0]):
        pts = np.concatenate([start[i:i + 1], paths[i]])
        # legs under 1e-9 m left out: GEOS cannot locate a point on them
        pts = pts[np.r_[True, np.hypot(*np.diff(pts, axis=0).T) > 1e-9]]
        if len(pts) < 2:
            np.testing.assert_allclose(rows[i], start[i][None].repeat(rows.shape[1], 0),
                                       atol=1e-8)
            continue
        line = shapely.LineString(pts)
        where = [line.project(shapely.Point(p)) for p in rows[i]]
        assert all(line.distance(shapely.Point(p)) < 1e-7 for p in rows[i])
        # distance along a self-crossing polyline can jump back; monotone where simple
        if line.is_simple:
            assert all(b >= a - 1e-7 for a, b in zip(where[:-1], where[1:], strict=True))


# ------------------------------------------------------------------ allocation


@settings(max_examples=80)
@given(st.integers(0, 2**31 - 1), st.integers(1, 5), st.integers(0, 12), st.booleans())
def test_allocate_shares_the_nearest_free_robots_in_priority_order(seed, n_obj, n_free,
                                                                   moving):
    rng = np.random.default_rng(seed)
    robots = rng.uniform(0, 10, (14, 2))
    objects = np.c_[rng.uniform(0, 10, (n_obj, 2)), np.zeros(n_obj)]
    free = sorted(rng.choice(14, n_free, replace=False).tolist())
    teams = allocate(list(range(n_obj)), free, robots, objects, moving)
    # reference: the same greedy rule written plainly
    pool, expect, busy = list(free), {}, moving
    split = n_obj
    share = min(MAX_ROBOTS, max(MIN_TEAM, n_free // split))
    for k in range(n_obj):
        want = min(share, len(pool))
        if want < (MIN_TEAM if busy else 1):
            break
        order = sorted(pool, key=lambda i: (math.dist(robots[i], objects[k][:2]), i))
        expect[k] = sorted(order[:want])
        pool = [i for i in pool if i not in expect[k]]
        busy = True
    if len(expect) < n_obj:
        for i in pool:  # leftovers join the nearest team with room
            room = [k for k in expect if len(expect[k]) < MAX_ROBOTS]
            if room:
                k = min(room, key=lambda k: (math.dist(robots[i], objects[k][:2]), k))
                expect[k] = sorted(expect[k] + [i])
    assert teams == expect
    sizes = [len(t) for t in teams.values()]
    assert all(s <= MAX_ROBOTS for s in sizes)
    if len(teams) == n_obj:  # everyone started: the split is as equal as the order allows
        assert max(sizes, default=0) <= max(MIN_TEAM, min(MAX_ROBOTS, n_free // split))
    used = [i for t in teams.values() for i in t]
    assert len(used) == len(set(used)) and set(used) <= set(free)


@settings(max_examples=80)
@given(st.integers(0, 2**31 - 1), st.integers(0, 8), st.integers(0, 4),
       st.sampled_from([math.inf, 2.0]))
def test_reinforce_joins_each_robot_to_the_nearest_team_with_room(seed, n_pool, n_teams, reach):
    rng = np.random.default_rng(seed)
    n = n_pool + 3 * n_teams
    pos = rng.uniform(0, 6, (n, 2))
    poses = np.column_stack([rng.uniform(0, 6, (n_teams, 2)), np.zeros(n_teams)])
    ids = rng.permutation(n).tolist()
    pool, rest = ids[:n_pool], ids[n_pool:]
    teams = {k: sorted(rest[3 * k:3 * k + int(rng.integers(1, MAX_ROBOTS + 1))])
             for k in range(n_teams)}
    out = reinforce(pool, pos, poses, teams, reach)
    assert set(out) == set(teams)
    sizes = dict((k, len(t)) for k, t in teams.items())
    for i in pool:  # replay the rule robot by robot
        d = {k: float(np.hypot(*(poses[k, :2] - pos[i]))) for k in teams
             if sizes[k] < MAX_ROBOTS}
        k = min(d, key=lambda k: (d[k], k)) if d else None
        joined = [j for j in out if i in out[j]]
        if k is None or d[k] > reach:
            assert joined == []
        else:
            assert joined == [k]
            sizes[k] += 1
    for k in teams:
        assert set(teams[k]) <= set(out[k]) and len(out[k]) == sizes[k] <= MAX_ROBOTS
        assert out[k] == sorted(out[k])


@settings(max_examples=60)
@given(st.integers(0, 2**31 - 1), st.integers(0, 6), st.integers(0, 3))
def test_least_conflict_order_starts_the_least_crossed_ways_first(seed, n, n_busy):
    rng = np.random.default_rng(seed)

    def box():
        x, y = rng.uniform(0, 10, 2)
        return shapely.box(x, y, x + rng.uniform(0.5, 3), y + rng.uniform(0.5, 3))

    cands = sorted(rng.choice(20, n, replace=False).tolist())
    corridors = {k: box() for k in cands}
    busy = [box() for _ in range(n_busy)]
    order = least_conflict_order(cands, corridors, busy)
    assert sorted(order) == cands
    # each pick meets no more corridors (moving ones and those picked before) than any
    # object still left, and the lowest index among the equals
    taken = list(busy)
    for i, k in enumerate(order):
        count = {j: sum(corridors[j].intersects(b) for b in taken) for j in order[i:]}
        assert count[k] == min(count.values())
        assert k == min(j for j in count if count[j] == count[k])
        taken.append(corridors[k])


def test_least_conflict_order_keeps_file_order_when_no_ways_cross():
    corridors = {k: shapely.box(3 * k, 0, 3 * k + 1, 1) for k in (4, 1, 7)}
    assert least_conflict_order([4, 1, 7], corridors, []) == [1, 4, 7]
    # the one crossing a moving object's way goes last
    assert least_conflict_order([4, 1, 7], corridors, [shapely.box(2.5, 0, 4.5, 1)]) == [4, 7, 1]


@settings(max_examples=60)
@given(st.integers(0, 2**31 - 1), st.integers(1, 7))
def test_an_object_whose_goal_bars_a_way_starts_after_that_object(seed, n):
    """With ``blocks`` acyclic, every object starts after each one whose way its goal
    lies in, whatever the corridors."""
    rng = np.random.default_rng(seed)
    cands = sorted(rng.choice(20, n, replace=False).tolist())
    rank = {k: r for r, k in enumerate(rng.permutation(cands).tolist())}
    blocks = {k: {j for j in cands if rank[j] < rank[k] and rng.random() < 0.4} for k in cands}
    corridors = {k: shapely.box(*(xy := rng.uniform(0, 5, 2)), *(xy + 2)) for k in cands}
    order = least_conflict_order(cands, corridors, [], blocks)
    assert sorted(order) == cands
    for k in cands:
        assert all(order.index(j) < order.index(k) for j in blocks[k])


@settings(max_examples=80)
@given(st.integers(0, 2**31 - 1), st.integers(1, 7), st.booleans())
def test_chain_depths_are_the_longest_chains(seed, n, acyclic):
    """Against a plain search of every chain: on an acyclic relation the depth is the
    most objects on a chain from the object; on any relation, objects on one cycle share
    a depth at least the cycle's length, and an object is deeper than what follows it
    off its cycle."""
    rng = np.random.default_rng(seed)
    cands = sorted(rng.choice(30, n, replace=False).tolist())
    rank = {k: r for r, k in enumerate(rng.permutation(cands).tolist())}
    blocks = {j: {k for k in cands if k != j and rng.random() < 0.35
                  and (not acyclic or rank[k] < rank[j])} for j in cands}
    depth = chain_depths(cands, blocks)
    follows = {k: {j for j in cands if k in blocks[j]} for k in cands}

    def longest(k, seen):
        return 1 + max((longest(j, seen | {j}) for j in follows[k] if j not in seen), default=0)

    def reaches(a, b):
        todo, seen = [a], {a}
        while todo:
            for j in follows[todo.pop()] - seen:
                seen.add(j)
                todo.append(j)
        return b in seen

    for k in cands:
        if acyclic:
            assert depth[k] == longest(k, {k})
        for j in follows[k]:
            if reaches(j, k):  # on one cycle
                assert depth[j] == depth[k] >= 2
            else:
                assert depth[k] > depth[j]


def test_the_head_of_the_longest_chain_starts_first():
    """Three objects whose ways do not cross; object 2's goal lies in object 1's way, so
    object 1 heads a chain of two and starts before object 0 (file order otherwise)."""
    corridors = {k: shapely.box(3 * k, 0, 3 * k + 1, 1) for k in (0, 1, 2)}
    assert least_conflict_order([0, 1, 2], corridors, []) == [0, 1, 2]
    assert least_conflict_order([0, 1, 2], corridors, [], {2: {1}}) == [1, 0, 2]


def test_loads_into_a_dead_end_aisle_start_deepest_first():
    """Three boxes go into an aisle closed at x = 0, their goals at x = 1, 2, 3, from
    starts side by side beyond its mouth (x = 8); in whatever file order, the deepest goal
    starts first."""
    walls = (Obstacle(Rectangle((8.0, 0.1)), (4.0, 0.45, 0.0)),
             Obstacle(Rectangle((8.0, 0.1)), (4.0, 1.55, 0.0)))
    for goals_x in ((3.0, 1.0, 2.0), (1.0, 2.0, 3.0), (2.0, 3.0, 1.0)):
        objects = tuple(SceneObject(BOX, (9.3, 0.3 + 0.7 * k, 0.0), (gx, 1.0, 0.0))
                        for k, gx in enumerate(goals_x))
        scene = Scene("aisle", (10.0, 2.0), ((9.8, 0.3), (9.8, 1.7)), objects, walls, 0.05)
        poses = np.array([o.start for o in objects])
        for in_way in (False, True):  # (``fleet_order_in_way`` either way)
            order = start_order(scene, poses, [0, 1, 2], [], in_way)
            assert [goals_x[k] for k in order] == [1.0, 2.0, 3.0]


def test_a_line_of_loads_leaving_an_aisle_starts_nearest_the_exit_first():
    """Three boxes stand in a line in an aisle open only at its east end (x = 8) and go to
    drop spots beyond it, north and south of the aisle's mouth, in whatever file order:
    the one nearest the exit starts first, then the next; each stands in the way of those
    behind it, none in the way of those ahead."""
    walls = (Obstacle(Rectangle((8.0, 0.1)), (4.0, 1.45, 0.0)),
             Obstacle(Rectangle((8.0, 0.1)), (4.0, 2.55, 0.0)),
             Obstacle(Rectangle((0.1, 1.0)), (0.05, 2.0, 0.0)))
    drops = ((9.5, 0.5, 0.0), (9.5, 3.5, 0.0), (9.5, 2.0, 0.0))
    for xs in ((1.5, 3.0, 4.5), (4.5, 1.5, 3.0), (3.0, 4.5, 1.5)):
        objects = tuple(SceneObject(BOX, (x, 2.0, 0.0), goal) for x, goal in zip(xs, drops,
                                                                                  strict=True))
        scene = Scene("exit", (10.0, 4.0), ((9.5, 2.0), (9.0, 2.0)), objects, walls, R)
        poses = np.array([o.start for o in objects])
        ahead = stands_in_way(scene, poses, [0, 1, 2])
        assert ahead == {k: {j for j in range(3) if xs[j] > xs[k]} for k in range(3)}
        order = start_order(scene, poses, [0, 1, 2], [], in_way=True)
        assert [xs[k] for k in order] == [4.5, 3.0, 1.5]


def test_a_load_in_the_way_whose_goal_is_in_the_way_too_goes_after():
    """Object 0 stands in object 1's way and its goal lies further along that way: it must
    be placed after object 1 whatever happens, so object 1 starts first (round it), in
    either file order."""
    walls = ()
    for swap in (False, True):
        a = SceneObject(BOX, (3.0, 1.0, 0.0), (4.2, 1.0, 0.0))  # in the way, goal too
        b = SceneObject(BOX, (1.0, 1.0, 0.0), (6.0, 1.0, 0.0))
        objects = (b, a) if swap else (a, b)
        scene = Scene("line", (7.0, 2.0), ((0.3, 0.3),), objects, walls, R)
        poses = np.array([o.start for o in objects])
        first = 0 if swap else 1  # object b's index
        assert stands_in_way(scene, poses, [0, 1])[first] == {1 - first}
        assert start_order(scene, poses, [0, 1], [], in_way=True)[0] == first


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_stands_in_way_in_the_open_is_the_band_along_the_straight_way(seed):
    """With no obstacles an object's way is the straight segment to its goal: another
    object stands in it exactly when a point of its outline lies within (circumradius +
    robot diameter) of that segment, brute force over outline points 1 mm apart; near the
    band's edge either answer is taken."""
    rng = np.random.default_rng(seed)
    objects = tuple(SceneObject(Rectangle(tuple(rng.uniform(0.2, 0.6, 2))),
                                (*rng.uniform(0.5, 9.5, 2), rng.uniform(-3, 3)),
                                (*rng.uniform(0.5, 9.5, 2), 0.0)) for _ in range(4))
    scene = Scene("open", (10.0, 10.0), ((0.2, 0.2),), objects, (), R)
    poses = np.array([o.start for o in objects])
    got = stands_in_way(scene, poses, [0, 1, 2, 3])
    for j, o in enumerate(objects):
        a, b = np.asarray(o.start[:2]), np.asarray(o.goal[:2])
        length = float(np.linalg.norm(b - a))
        u = (b - a) / length
        reach = max(np.hypot(*np.asarray(shapely.get_coordinates(to_shapely(o.shape, (0, 0, 0)))).T)
                    ) + 2 * R
        for k in range(4):
            if k == j:
                continue
            ring = to_shapely(objects[k].shape, poses[k]).exterior
            pts = shapely.get_coordinates(shapely.segmentize(ring, 0.001)) - a
            along = np.clip(pts @ u, 0.0, length)
            margin = reach - np.hypot(*(pts - along[:, None] * u).T)
            if np.all(np.abs(margin) > 2e-3):  # clear of the edge
                assert (k in got[j]) == bool(np.any(margin > 0)), (j, k)


@settings(max_examples=60)
@given(st.integers(0, 2**31 - 1), st.integers(0, 12))
def test_near_way_takes_the_robots_within_reach_of_the_objects_way(seed, n):
    """The robots ``Fleet.plan_failed`` takes into a team whose planner failed: those
    within ``GROW_REACH`` of the hull of the object's footprints now and at its goal grown
    by a robot diameter (brute force: distance to each footprint's hull), in pool order;
    none farther."""
    rng = np.random.default_rng(seed)
    box = Rectangle((0.4, 0.3))
    start, goal = rng.uniform(1, 9, 3), rng.uniform(1, 9, 3)
    scene = Scene("open", (10.0, 10.0), ((0.5, 0.5),), (SceneObject(box, tuple(start),
                                                                     tuple(goal)),), (), R)
    robots = rng.uniform(0, 10, (n, 2))
    pool = [int(i) for i in rng.permutation(n)]
    hull = shapely.union_all([to_shapely(box, start), to_shapely(box, goal)]).convex_hull
    want = [i for i in pool if hull.distance(shapely.Point(robots[i])) <= GROW_REACH + 2 * R]
    got = near_way(scene, 0, start, pool, robots)
    assert got == want or all(  # a robot on the reach's edge may fall either way (the
        # buffer is a polygon)
        abs(hull.distance(shapely.Point(robots[i])) - GROW_REACH - 2 * R) < 1e-3
        for i in set(got) ^ set(want))


# ------------------------------------------------------------------ space-time

BOX = Rectangle((0.3, 0.2))


def _segment(index: int, start_xy, rows: np.ndarray, poses: np.ndarray, cursor: int = 0):
    return Segment(index, list(range(len(rows))), rows, poses, None, BOX, R, cursor=cursor)


def _brute_force_clear(a: Segment, b: Segment, seen: np.ndarray | None = None) -> bool:
    """Row by row: robots (holding their last row) at least 2R + 2*ROBOT_MARGIN apart, and
    each robot ROBOT_MARGIN clear of the other's object wherever it may be (its first
    pose until a robot may touch it, the planned poses while its segment runs, cut to
    where it can get from ``seen`` when given, the last one after), and the two objects
    apart."""
    n = max(a.remaining, b.remaining)
    def at(seg, t):
        return seg.rows[:, min(seg.cursor + t, seg.rows.shape[1] - 1)]
    def reach(seg, t):  # PUSH_SPEEDUP x its farthest robot's way from the last row run
        way = [np.max(np.linalg.norm(at(seg, u) - at(seg, u - 1), axis=1))
               for u in range(1 - min(seg.cursor, 1), t + 1)]
        return PUSH_SPEEDUP * sum(way) + PUSH_LEAD
    def obj(seg, t):  # at its first pose until touched, along its motion, at its last
        poses = (seg.poses[:1] if seg.cursor + t < seg.touch else
                 seg.poses if t < seg.remaining else seg.poses[-1:])
        region = footprints(seg.shape, poses, OBJECT_MARGIN)
        if seen is None or not seg.cursor + t >= seg.touch or not t < seg.remaining:
            return region
        return region.intersection(to_shapely(seg.shape, seen[seg.index]).buffer(
            reach(seg, t), quad_segs=64))
    for t in range(n + 1):
        if obj(a, t).intersects(obj(b, t)):
            return False
    for t in range(n):
        pa, pb = at(a, t), at(b, t)
        if min(math.dist(p, q) for p in pa for q in pb) < 2 * R + 2 * ROBOT_MARGIN - 1e-9:
            return False
        for robots, seg in ((pb, a), (pa, b)):
            region = obj(seg, t)
            if min(region.distance(shapely.Point(p)) for p in robots) < R + ROBOT_MARGIN - 1e-9:
                return False
    return True


def _random_segment(rng, index: int, centre) -> Segment:
    n = int(rng.integers(1, 4))
    start = np.asarray(centre) + rng.uniform(-0.6, 0.6, (n, 2))
    end = start + rng.uniform(-0.8, 0.8, (n, 2))
    t = int(rng.integers(2, 30))
    rows = start[:, None] + (end - start)[:, None] * np.linspace(0, 1, t)[None, :, None]
    q0 = np.r_[np.asarray(centre) + rng.uniform(-0.3, 0.3, 2), rng.uniform(-3, 3)]
    q1 = q0 + np.r_[rng.uniform(-0.4, 0.4, 2), rng.uniform(-0.5, 0.5)]
    cursor = int(rng.integers(0, t)) if index == 0 else 0
    return _segment(index, start, rows, np.array([q0, q1]), cursor)


@settings(max_examples=150)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 2.5))
def test_compatible_segments_stay_clear_row_by_row(seed, apart) -> None:
    rng = np.random.default_rng(seed)
    a = _random_segment(rng, 0, (0.0, 0.0))
    b = _random_segment(rng, 1, (apart, 0.3))
    if compatible(a, b):
        assert _brute_force_clear(a, b)
    if not _brute_force_clear(a, b):
        assert not compatible(a, b)
    # later on the clock, with each segment's object spaces kept from the first test
    for seg in (a, b):
        seg.cursor = int(rng.integers(seg.cursor, seg.rows.shape[1]))
    warm = compatible(a, b)
    if warm:
        assert _brute_force_clear(a, b)
    a.spaces.clear()
    b.spaces.clear()
    assert compatible(a, b) == warm  # the kept spaces are the ones it would compute now


@settings(max_examples=150)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 2.5), st.floats(0.0, 0.6))
def test_segments_compatible_with_objects_seen_stay_clear_row_by_row(seed, apart, off) -> None:
    """With the objects' poses read now (``seen``), a pushed object is cut to where it can
    get from there: ``compatible`` then still keeps everything clear row by row (the
    brute force cuts each motion phase to the reach), and it never refuses what it
    allows without them."""
    rng = np.random.default_rng(seed)
    if seed % 2:  # a robot that approaches its box first, then pushes it
        a = _approach_then_push(0, 0.0, int(rng.integers(2, 40)))
        a.cursor = int(rng.integers(0, a.rows.shape[1]))
    else:
        a = _random_segment(rng, 0, (0.0, 0.0))
    b = _random_segment(rng, 1, (apart, 0.3))
    seen = np.array([seg.poses[0] + np.r_[rng.uniform(-off, off, 2), rng.uniform(-0.5, 0.5)]
                     for seg in (a, b)])
    cut = compatible(a, b, seen)
    if cut:
        assert _brute_force_clear(a, b, seen)
    if compatible(a, b):
        assert cut


def test_a_crossing_of_a_pushs_far_end_waits_only_without_the_pose_seen() -> None:
    """A's robot drives 0.8 m to its box in 40 rows, then pushes it 2 m along y = 1 in 100
    more. B's robot crosses A's way at x = 3.1 in rows 40-60, while A's box is still near
    x = 1: without where the box was seen, its whole way is taken and B must wait; with
    it, B goes. Crossing at x = 2.2 then, or lingering on the far end until the box
    comes, B must wait either way (the box may be 1.45 m on by row 40)."""
    box = np.array([[1.0, 1.0, 0.0], [3.0, 1.0, 0.0]])
    contact = 1.0 - BOX.size[0] / 2 - R
    rows = np.concatenate([np.linspace([contact - 0.8, 1.0], [contact, 1.0], 41),
                           np.linspace([contact, 1.0], [contact + 2.0, 1.0], 101)[1:]])[None]
    a = _segment(0, None, rows, box)
    seen = np.array([box[0], [5.0, 5.0, 0.0]])
    def crossing(x, linger=0):
        way = np.linspace([x, 0.2], [x, 1.8], 20)
        way = np.concatenate([np.repeat(way[:1], 40, axis=0), way[:10],
                              np.repeat(way[10:11], linger, axis=0), way[10:]])[None]
        return _segment(1, None, way, np.array([[5.0, 5.0, 0.0]]))
    assert 30 < a.touch <= 40
    far = crossing(3.1)
    assert not compatible(a, far)
    assert compatible(a, far, seen) and _brute_force_clear(a, far, seen)
    for b in (crossing(2.2), crossing(3.1, linger=100)):
        assert not compatible(a, b, seen) and not _brute_force_clear(a, b, seen)


def test_boxes_whose_ways_cross_go_together_only_if_one_cannot_come_in_time() -> None:
    """A pushes its box 2 m along y = 1 in 100 rows, through (2, 1); B pushes its box up
    along x = 2 from ``d`` m below that crossing. Without the poses seen both ways are
    taken whole: B waits. With them, B's box, 4 m off, cannot come within A's way before
    A's segment ends (3.1 m of reach by then): both go. From 3 m off it could (though its
    robot keeps clear of A's robot, and A's of B's box): B waits."""
    def pusher(index, start, goal, rows):
        start, goal = np.asarray(start, float), np.asarray(goal, float)
        way = (goal - start) / np.linalg.norm(goal - start)
        back = start[:2] - way[:2] * (BOX.size[0] / 2 + R + 0.005)
        robot = np.linspace(back, back + goal[:2] - start[:2], rows)[None]
        return _segment(index, None, robot, np.array([start, goal]))
    a = pusher(0, [1.0, 1.0, 0.0], [3.0, 1.0, 0.0], 101)
    for d, together in ((4.0, True), (3.0, False)):
        b = pusher(1, [2.0, 1.0 - d, np.pi / 2], [2.0, 6.0 - d, np.pi / 2], 251)
        seen = np.array([a.poses[0], b.poses[0]])
        assert a.touch == 0 and b.touch == 0 and not compatible(a, b)
        assert compatible(a, b, seen) == together
        assert _brute_force_clear(a, b, seen) == together


def _ended_push(index: int, y: float, pose: np.ndarray) -> Segment:
    """A segment that pushed a box from (1, y) to (2, y) and has ended, its box read at
    ``pose``."""
    rows = np.linspace([1.0 - BOX.size[0] / 2 - R, y], [2.0 - BOX.size[0] / 2 - R, y], 50)[None]
    seg = _segment(index, None, rows, np.array([[1.0, y, 0.0], [2.0, y, 0.0]]))
    seg.cursor = seg.rows.shape[1]
    return seg


def test_segments_in_the_way_of_an_object_left_off_its_plan_stop() -> None:
    """A's push ended with its box 0.5 m short of its last planned pose; B's robot will
    cross x = 1.5 where the box stands: B stops. With the box where it was planned to
    end, or B crossing farther on, nothing stops. C, whose robot crosses where B's box
    now stands off its plan, stops too once B has (``halted``)."""
    cross = np.linspace([1.5, 0.2], [1.5, 1.8], 40)[None]
    b = _segment(1, None, cross, np.array([[4.0, 4.0, 0.0], [4.0, 4.0, 0.0]]))
    short = np.array([1.5, 1.0, 0.0])
    a = _ended_push(0, 1.0, short)
    assert halted_by(a, [a, b], short) == [b]
    assert halted_by(a, [a, b], np.array([2.0, 1.0, 0.0])) == []
    assert halted_by(a, [a, _segment(1, None, cross + [2.5, 0.0], b.poses)], short) == []
    # a robot passing 5.5 cm from the box's side (its centre) comes too near; 7 cm does not
    for gap, stops in ((0.055, True), (0.07, False)):
        by = _segment(1, None, cross + [BOX.size[0] / 2 + gap, 0.0], b.poses)
        assert halted_by(a, [a, by], short) == ([by] if stops else [])
    # B pushes its own box from (4, 4) to (4, 3); read 0.6 m short, it is in C's way
    b = _segment(1, None, np.concatenate([cross, np.linspace([4.0, 4.3], [4.0, 3.3], 40)[None]],
                                         axis=1), np.array([[4.0, 4.0, 0.0], [4.0, 3.0, 0.0]]))
    c = _segment(2, None, np.linspace([3.5, 3.6], [4.5, 3.6], 40)[None],
                 np.array([[6.0, 6.0, 0.0], [6.0, 6.0, 0.0]]))
    poses = np.array([short, [4.0, 3.6, 0.0], [6.0, 6.0, 0.0]])
    assert halted([a, b, c], poses) == [b, c]
    assert halted([a, b, c], np.array([[2.0, 1.0, 0.0], *poses[1:]])) == []


@settings(max_examples=100)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 2.5), st.floats(0.0, 0.8))
def test_a_segment_not_halted_keeps_clear_of_the_object_left_off_its_plan(seed, apart, off):
    """Brute force: a running segment ``halted_by`` leaves running has no robot row left
    within ``ROBOT_MARGIN`` of the ended segment's box where it stands, and no object
    space meeting it; and none is halted while the box stands inside its last planned
    pose grown by ``OBJECT_MARGIN``."""
    rng = np.random.default_rng(seed)
    pose = np.r_[rng.uniform(1.0, 2.0) + rng.uniform(-off, off), 1.0 + rng.uniform(-off, off),
                 rng.uniform(-0.6, 0.6) * off]
    a = _ended_push(0, 1.0, pose)
    b = _random_segment(rng, 1, (1.5 + apart - 1.2, 1.2))
    b.cursor = int(rng.integers(0, b.rows.shape[1]))
    stop = halted_by(a, [a, b], pose)
    body = to_shapely(BOX, pose)
    if footprints(BOX, a.poses[-1:], OBJECT_MARGIN).contains(body):
        assert stop == []
    elif b not in stop:
        rows = b.rows[:, b.cursor:].reshape(-1, 2)
        assert all(body.distance(shapely.Point(p)) >= R + ROBOT_MARGIN for p in rows)
        assert not any(footprints(BOX, q, OBJECT_MARGIN).intersects(body)
                       for q in (b.poses[:1], b.poses, b.poses[-1:]))


def test_far_apart_segments_are_compatible_and_crossing_robots_are_not() -> None:
    rows = np.linspace([0.0, 0.0], [1.0, 0.0], 50)[None]
    a = _segment(0, None, rows, np.array([[0.0, 1.0, 0.0], [0.5, 1.0, 0.0]]))
    far = _segment(1, None, rows + [0.0, 5.0], np.array([[0.0, 6.0, 0.0], [0.5, 6.0, 0.0]]))
    assert compatible(a, far) and compatible(far, a)
    crossing = _segment(1, None, np.linspace([0.5, -0.5], [0.5, 0.5], 50)[None],
                        np.array([[3.0, 3.0, 0.0], [3.2, 3.0, 0.0]]))
    assert not compatible(a, crossing)
    # the same crossing, but only after ``a``'s robot has passed: fine
    later = _segment(1, None, np.linspace([0.5, -0.5], [0.5, 0.5], 50)[None],
                     np.array([[3.0, 3.0, 0.0], [3.2, 3.0, 0.0]]))
    ahead = _segment(0, None, np.linspace([0.9, 0.0], [3.0, 0.0], 50)[None],
                     np.array([[5.0, 1.0, 0.0], [5.5, 1.0, 0.0]]))
    assert compatible(ahead, later)


def _approach_then_push(index: int, y: float, approach: int) -> Segment:
    """A robot that drives ``approach`` rows towards a box at (1, y) from the left, then
    pushes it 0.4 m to the right."""
    box_x = 1.0
    contact = box_x - BOX.size[0] / 2 - R
    rows = np.concatenate([np.linspace([contact - 0.02 * approach, y], [contact, y], approach),
                           np.linspace([contact, y], [contact + 0.4, y], 20)[1:]])[None]
    return _segment(index, None, rows, np.array([[box_x, y, 0.0], [box_x + 0.4, y, 0.0]]))


def test_first_touch_is_where_a_robot_comes_near_the_object() -> None:
    seg = _approach_then_push(0, 1.0, 40)
    d = [to_shapely(BOX, seg.poses[0]).distance(shapely.Point(p)) - R for p in seg.rows[0]]
    g = seg.touch
    assert 0 < g < 40 and d[g + 1] < OBJECT_MARGIN <= d[g - 1]  # the move from row g comes near
    # robots left in contact that move away (or along) push nothing; coming nearer does
    away = seg.rows[:, ::-1].copy()
    back = _segment(0, None, away, seg.poses[::-1])
    assert back.touch == 0  # starts pushing at once: the push is at the front, reversed
    leave = _segment(0, None, np.linspace([0.75, 1.0], [0.2, 1.0], 30)[None],
                     np.array([[1.0, 1.0, 0.0]]))
    assert leave.touch == 0  # nobody comes near: nothing known, moving from the start
    stay = np.concatenate([np.linspace([0.8 - R, 1.0], [0.8 - R, 0.6], 20),
                           np.linspace([0.8 - R, 0.6], [0.8 - R + 0.05, 0.6], 5)[1:]])[None]
    slide = _segment(0, None, stay, np.array([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0]]))
    assert slide.touch == 0 or slide.touch >= 19


def test_an_object_not_yet_touched_leaves_its_future_way_free() -> None:
    """B's robot crosses where A's box will be pushed, but leaves it before A's robot
    reaches the box: compatible now; a B that stays on A's way is not."""
    a = _approach_then_push(0, 1.0, 60)
    cross = np.linspace([1.3, 0.2], [1.3, 1.8], 30)[None]  # across x = 1.3 in 30 rows
    b = _segment(1, None, cross, np.array([[3.0, 3.0, 0.0], [3.2, 3.0, 0.0]]))
    assert a.touch > 30 and compatible(a, b) and compatible(b, a)
    lingering = _segment(1, None, np.concatenate([cross, np.repeat(cross[:, 15:16], 60, axis=1)],
                                                 axis=1),
                         np.array([[3.0, 3.0, 0.0], [3.2, 3.0, 0.0]]))
    assert not compatible(a, lingering)


@settings(max_examples=120)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 2.0))
def test_disjoint_swept_regions_keep_the_bodies_apart_whatever_their_timing(seed, apart):
    """``regions.swept``'s guarantee: when two segments' swept regions do not meet, every
    robot of one (anywhere on its path) stays 2 * ROBOT_MARGIN beyond a robot diameter from
    every robot of the other, robots ROBOT_MARGIN + OBJECT_MARGIN beyond the radius from
    the other's object at any planned pose, and the objects 2 * OBJECT_MARGIN apart; up
    to the polygon approximation of the disks and of a turn between sampled poses
    (TOL)."""
    tol = 3e-3
    rng = np.random.default_rng(seed)
    a = _random_segment(rng, 0, (0.0, 0.0))
    b = _random_segment(rng, 1, (apart, 0.3))
    if swept(BOX, a.poses, a.rows, R).intersects(swept(BOX, b.poses, b.rows, R)):
        return

    def path_points(seg):  # rows and the midpoints between them
        rows = seg.rows
        return np.concatenate([rows, (rows[:, 1:] + rows[:, :-1]) / 2], axis=1).reshape(-1, 2)

    def bodies(seg):
        return [to_shapely(BOX, q) for q in np.linspace(seg.poses[0], seg.poses[-1], 9)]

    pa, pb = path_points(a), path_points(b)
    gap = np.hypot(*(pa[:, None] - pb[None]).T)
    assert gap.min() >= 2 * R + 2 * ROBOT_MARGIN - tol
    for robots, objects in ((pa, bodies(b)), (pb, bodies(a))):
        pts = shapely.points(robots)
        for body in objects:
            assert shapely.distance(body, pts).min() >= R + ROBOT_MARGIN + OBJECT_MARGIN - tol
    for x in bodies(a):
        for y in bodies(b):
            assert x.distance(y) >= 2 * OBJECT_MARGIN - tol


def test_claim_covers_the_planned_footprints_and_room_for_pushers() -> None:
    poses = np.array([[1.0, 1.0, 0.0], [2.0, 1.0, 0.0], [2.0, 2.0, math.pi / 2]])
    c = claim(BOX, poses, R)
    for q in poses:
        assert c.contains(to_shapely(BOX, q).buffer(2 * R))
    assert claim(BOX, np.zeros((0, 3)), R) is None


def test_claims_near_part_is_the_claim_of_the_first_metres_of_travel() -> None:
    """``claims``: the claim of the whole plan, the claim of the poses within
    ``CLAIM_NEAR`` m of travel (the whole claim for a shorter plan), and the way through
    the poses on to the goal."""
    poses = np.array([[x, 1.0, 0.0] for x in np.arange(0.0, 8.01, 0.25)])
    full, near, way = claims(BOX, poses, [9.0, 1.0, 0.0], R)
    assert full.equals(claim(BOX, poses, R))
    assert near.equals(claim(BOX, poses[poses[:, 0] <= CLAIM_NEAR + 1e-9], R))
    assert shapely.area(shapely.difference(near, full)) < 1e-9 < shapely.area(full) - shapely.area(near)
    assert shapely.get_coordinates(way)[-1].tolist() == [9.0, 1.0]
    short = claims(BOX, poses[:4], [1.0, 1.0, 0.0], R)
    assert short[0] is short[1]
    off = claims(BOX, poses, [9.0, 1.0, 0.0], R, near_reach=0.0)  # the fleet's default
    assert off[0] is off[1] and off[0].equals(full)
    assert claims(BOX, np.zeros((0, 3)), [0.0, 0.0, 0.0], R) == (None, None, None)


def test_a_plan_that_crosses_a_higher_claim_heeds_only_its_near_part() -> None:
    """``meets_moving``: a segment that ends deeper in a higher-ranked object's claim
    waits, unless its own way crosses the claim (``crosses``: its goal outside, at most
    ``CROSSING`` m inside) and it ends beyond the claim's near part; a way that runs
    along the claim, or ends in it, heeds all of it."""
    corridor = np.array([[x, 1.0, 0.0] for x in np.arange(0.0, 10.01, 0.25)])
    full, near, _ = claims(BOX, corridor, [10.0, 1.0, 0.0], R)
    higher = [(0, full, near)]

    def into(x: float, way: list[list[float]]) -> tuple[Segment, shapely.Geometry]:
        q0, q1 = np.array([x, 0.0, 0.0]), np.array([x, 0.9, 0.0])  # up into the claim
        rows = np.linspace(q0[:2] - [0.0, 0.2], q1[:2] - [0.0, 0.2], 20)[None]
        return (Segment(1, [0], rows, np.array([q0, q1]), None, BOX, R),
                shapely.LineString(way))

    across = [[0.0, 0.0], [0.0, 2.2]]  # up through the corridor, goal beyond it
    for x, want in ((7.0, None), (1.0, "claim 0")):  # far ahead / within CLAIM_NEAR
        seg, way = into(x, [[x + a, b] for a, b in across])
        assert crosses(way, full)
        assert meets_moving(seg, [], higher, way) == want
        assert meets_moving(seg, [], higher) == "claim 0"  # no way known: the whole claim
    seg, _ = into(7.0, [])
    along = shapely.LineString([[7.0, 0.0], [7.0, 1.0], [2.0, 1.0], [2.0, 2.2]])
    stops = shapely.LineString([[7.0, 0.0], [7.0, 1.0]])
    assert shapely.length(shapely.intersection(along, full)) > CROSSING
    for way in (along, stops):
        assert not crosses(way, full)
        assert meets_moving(seg, [], higher, way) == "claim 0"


def test_limit_reached_names_the_limit_that_ends_an_object() -> None:
    """An object whose last loop ended only for the world or the team (so another would
    follow) fails by the limit it ran out of, planning time first."""
    from lamp.planners.series import limit_reached

    assert limit_reached(50, 10, 3, 12.0, 300.0) == ""
    assert limit_reached(50, 50, 3, 12.0, 300.0) == "segment limit reached (50)"
    assert limit_reached(50, 10, 51, 12.0, 300.0) == "plan-anew limit reached (50 loops)"
    assert limit_reached(50, 60, 60, 300.0, 300.0) == "planning time limit"


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 12))
def test_meets_standing_finds_the_standing_robots_the_planned_bodies_overlap(seed, n) -> None:
    """Against exact disks: a robot not in the team nor moving, whose disk (shrunk by
    ``STATIC_SLACK``) the segment's planned bodies overlap, is found; one they keep clear
    of is not (up to the 16-gon the disk is drawn as: within 0.5% of its radius)."""
    rng = np.random.default_rng(seed)
    seg = _random_segment(rng, 0, (0.0, 0.0))
    robots = rng.uniform(-1.2, 1.2, (n, 2))
    moving = {int(i) for i in rng.choice(n, size=int(rng.integers(0, n + 1)), replace=False)}
    scene = scene_from_dict({
        "format": "lamp-scene/1", "name": "standing", "workspace": [20.0, 20.0],
        "robots": {"radius": R, "starts": [[1.0 + 0.2 * i, 15.0] for i in range(n)]},
        "obstacles": [],
        "objects": [{"type": "circle", "radius": 0.1, "start": [15.0, 1.0, 0.0],
                     "goal": [15.0, 3.0, 0.0]}]})
    core = seg.core()
    outer = R - STATIC_SLACK
    inner = outer * math.cos(math.pi / 32)
    d = [float(core.distance(shapely.Point(p))) if i not in seg.team and i not in moving
         else math.inf for i, p in enumerate(robots)]
    found = meets_standing(seg, scene, np.zeros((1, 3)), robots, [], moving)
    if min(d, default=math.inf) < inner:
        assert found
    if found:
        assert min(d) < outer


_SHAPES = st.one_of(
    st.builds(lambda w, h: Rectangle((w, h)), st.floats(0.05, 1.0), st.floats(0.05, 1.0)),
    st.builds(Circle, st.floats(0.05, 0.5)),
    st.just(Polygon(((-0.2, -0.15), (0.2, -0.15), (0.0, 0.25)))),
    st.just(Polygon(((0.0, 0.3), (0.2, -0.1), (-0.25, -0.2), (-0.1, 0.1)))))


def _footprints_pair_by_pair(shape, poses, grow):
    """The reference: each densified pose's body, each step's hull, all unioned."""
    from lamp.fleet.regions import _densified

    parts = [to_shapely(shape, q) for q in _densified(poses)]
    hulls = [shapely.convex_hull(shapely.union(a, b))
             for a, b in zip(parts[:-1], parts[1:], strict=True)]
    geom = shapely.union_all(parts + hulls) if hulls else parts[0]
    return geom.buffer(grow) if grow > 0 else geom


def _same_set(a, b, tol=1e-9) -> bool:
    """Whether two geometries differ by less than ``tol`` of area (and tol m of reach)."""
    return (shapely.area(shapely.symmetric_difference(a, b)) <= tol * max(1.0, a.area)
            and shapely.hausdorff_distance(a, b) <= 1e-6)


@settings(max_examples=60, deadline=None)
@given(_SHAPES, st.integers(0, 2**31 - 1), st.integers(1, 6), st.sampled_from([0.0, 0.05]))
def test_footprints_are_the_bodies_and_step_hulls_pose_by_pose(shape, seed, n, grow) -> None:
    """``to_shapely_many`` builds each pose's ``to_shapely`` to the last bit, and the
    footprints (each step's hull, unioned) are the same set as every densified pose's body
    and every step's hull unioned pair by pair; grown, the same up to GEOS' growing (its
    arcs are chords of a sixteenth of a turn, ``grow * (1 - cos(pi / 16))``, placed by
    each representation's vertices)."""
    rng = np.random.default_rng(seed)
    poses = np.cumsum(rng.uniform([-0.5, -0.5, -1.0], [0.5, 0.5, 1.0], (n, 3)), axis=0)
    for g, q in zip(to_shapely_many(shape, poses), poses, strict=True):
        assert np.array_equal(shapely.get_coordinates(g),
                              shapely.get_coordinates(to_shapely(shape, q)))
    assert _same_set(footprints(shape, poses), _footprints_pair_by_pair(shape, poses, 0.0))
    if grow > 0:
        new, old = footprints(shape, poses, grow), _footprints_pair_by_pair(shape, poses, grow)
        chord = grow * (1.0 - math.cos(math.pi / 16)) + 1e-9
        assert shapely.hausdorff_distance(new, old) <= chord
        assert shapely.area(shapely.symmetric_difference(new, old)) <= chord * old.length


@settings(max_examples=40, deadline=None)
@given(_SHAPES, st.integers(0, 2**31 - 1), st.integers(1, 70), st.data())
def test_claim_blocks_give_the_claim_of_every_suffix(shape, seed, n, data) -> None:
    """``ClaimBlocks.claim`` of the suffixes of one plan, in the order a plan is executed
    (and of another plan's between them): like ``claim``, it holds the footprints along
    the plan and its border lies ``grow`` from them, up to the accuracy of GEOS' growing
    (arcs as chords, ``grow * (1 - cos(pi / 64))``; shallow dents within 1% of ``grow``
    filled), and each block is built once."""
    rng = np.random.default_rng(seed)
    plan = np.cumsum(rng.uniform([-0.2, -0.2, -0.4], [0.2, 0.2, 0.4], (n, 3)), axis=0)
    other = plan[::-1] + 1.0
    blocks = ClaimBlocks()
    grow = 2.0 * R + OBJECT_MARGIN
    tol = grow * (1.0 - math.cos(math.pi / 64)) + 0.01 * grow + 1e-9
    cuts = sorted(set(data.draw(st.lists(st.integers(0, n - 1), max_size=6))) | {0})
    for i in cuts:
        for poses in (plan[i:], other):
            bodies = footprints(shape, poses)
            want = claim(shape, poses, R)
            got = blocks.claim(shape, poses, R)
            assert got.buffer(1e-9).contains(bodies)
            gap = shapely.distance(bodies, shapely.points(shapely.get_coordinates(got)))
            assert np.all(np.abs(gap - grow) <= tol)
            assert abs(got.area - want.area) <= tol * want.length
    steps = len(plan) - 1
    assert len(blocks._blocks) <= 2 * (steps // CLAIM_BLOCK) + 2
