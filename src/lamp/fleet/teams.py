"""Who pushes what: robots split into sub-teams, one per moving object.

Which ready objects go first is :func:`start_order` (:func:`least_conflict_order`):
those whose goal lies in the way of no other object still to start (:func:`in_the_way`:
placed early, it would make that object go round it or wait), then the head of the
longest chain of such objects (:func:`chain_depths`: the critical path), then those whose
way crosses the fewest ways of the objects moving. :func:`allocate` shares the free
robots equally among the ready objects, each the robots nearest to it: at most
``MAX_ROBOTS`` each (the model's budget: more would stand idle), at least
``MIN_TEAM``; a lone robot only when no other object is moving (no robot will be
freed); robots left over when the next object cannot start join the started teams
(:func:`reinforce`). A team keeps its robots until its object is placed or given up
(then they are free for the next object), but for a far robot whose place a free robot
nearer the object takes (``fleet.handover``). Robots no object needs stand still where they
are (every plan sees them as obstacles). Measured on IROS with 9 robots
(``benchmarks/fleet_iros9.py``) and the ``fleet`` family: ``docs/fleet.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence, Set

import numpy as np
import shapely
from scipy.optimize import linear_sum_assignment
from scipy.sparse import csr_array
from scipy.sparse.csgraph import connected_components, maximum_bipartite_matching

from lamp.contract.model import MAX_ROBOTS
from lamp.geometry.shapes import to_shapely
from lamp.scene.bounds import object_way
from lamp.scene.model import Scene, Shape

__all__ = ["GROW_REACH", "MIN_TEAM", "allocate", "balanced_teams", "chain_depths", "corridor",
           "goal_blocks", "in_the_way", "in_way_of", "least_conflict_order", "near_way",
           "nearest", "needed_space", "planar_distance", "reinforce", "stands_in_way",
           "start_order"]

#: The smallest sub-team an object starts with while other objects are moving.
MIN_TEAM = 2
#: Free robots this close (m) to an object's way join its team when its planner finds no
#: plan (:func:`near_way`): they may stand in its way; robots farther off do not.
GROW_REACH = 1.0


def planar_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Distance in the plane between the (x, y) of ``a`` and of ``b`` (points or poses)."""
    return float(np.hypot(*(np.asarray(a, float)[:2] - np.asarray(b, float)[:2])))


def nearest(pool: Sequence[int], robot_positions: np.ndarray, centre: np.ndarray,
            n: int) -> list[int]:
    """The ``n`` robots of ``pool`` nearest to ``centre`` (ties by index), nearest first."""
    d = [planar_distance(robot_positions[i], centre) for i in pool]
    return [pool[j] for j in sorted(range(len(pool)), key=lambda j: (d[j], pool[j]))[:n]]


def allocate(ready: Sequence[int], free: Sequence[int], robot_positions: np.ndarray,
             object_poses: np.ndarray, others_moving: bool,
             goals: np.ndarray | None = None) -> dict[int, list[int]]:
    """Sub-teams for the ``ready`` objects (priority order) from the ``free`` robots.

    The free robots are shared equally among the ready objects: each gets ``share`` =
    ``len(free) // len(ready)`` of the free robots nearest to its centre (ties by index),
    at least ``MIN_TEAM`` and at most ``MAX_ROBOTS``; an object that would get fewer than
    ``MIN_TEAM`` (1 when nothing else moves and it is the first) waits, and so do those
    after it. Robots left over when no further object can start join the teams, each the
    team of the nearest object among those below ``MAX_ROBOTS`` (ties by priority).
    With ``goals`` (each object's goal pose, by object), the started objects keep those
    team sizes but the robots are matched to them by :func:`balanced_teams` (the longest
    haul first) instead of each taking its nearest in turn. Deterministic; returns
    object -> robots (ascending)."""
    pool = list(free)
    teams: dict[int, list[int]] = {}
    if not ready:
        return teams
    share = max(MIN_TEAM, min(MAX_ROBOTS, len(pool) // len(ready)))
    moving = others_moving
    for k in ready:
        need = min(share, len(pool))
        if need < (MIN_TEAM if moving else 1):
            break
        chosen = nearest(pool, robot_positions, object_poses[k], need)
        teams[k] = sorted(chosen)
        pool = [i for i in pool if i not in chosen]
        moving = True
    if goals is not None and teams:
        hauls = {k: planar_distance(object_poses[k], goals[k]) for k in teams}
        teams = balanced_teams({k: len(t) for k, t in teams.items()}, list(free),
                               robot_positions, object_poses, hauls)
        pool = [i for i in free if all(i not in t for t in teams.values())]
    if len(teams) < len(ready):  # the next object cannot start: help the started ones
        teams = reinforce(pool, robot_positions, object_poses, teams)
    return teams


def balanced_teams(sizes: Mapping[int, int], pool: Sequence[int], robot_positions: np.ndarray,
                   object_poses: np.ndarray, hauls: Mapping[int, float]
                   ) -> dict[int, list[int]]:
    """Teams of ``sizes[k]`` robots from ``pool`` for the objects of ``sizes`` (in
    priority order), matched so that the longest of ``d(i, k) + hauls[k]`` over the
    pairs (robot ``i`` in object ``k``'s team; ``d`` the straight-line distance to the
    object's centre, ``hauls[k]`` the way it has to go, m) is the least any matching
    achieves (a bottleneck assignment: an object is placed no sooner than its farthest
    robot arrives plus its haul), and among those matchings the sum of the squares of
    those values is least (no object's team farther than it needs be). Needs
    ``sum(sizes) <= len(pool)``. Deterministic; object -> robots (ascending)."""
    objs = list(sizes)
    slots = np.repeat(np.arange(len(objs)), [sizes[k] for k in objs])
    xy = np.asarray(robot_positions, float)[list(pool), :2]
    centres = np.asarray(object_poses, float)[objs, :2]
    cost = (np.hypot(*(xy[:, None] - centres[None]).transpose(2, 0, 1))
            + np.asarray([hauls[k] for k in objs])[None])[:, slots]
    values = np.unique(cost)
    lo, hi = int(np.searchsorted(values, cost.min(axis=0).max())), len(values) - 1
    while lo < hi:  # the least threshold under which every slot still gets a robot
        mid = (lo + hi) // 2
        under = csr_array(cost <= values[mid])
        if (maximum_bipartite_matching(under, perm_type="row") >= 0).sum() == len(slots):
            hi = mid
        else:
            lo = mid + 1
    rows, cols = linear_sum_assignment(np.where(cost <= values[lo], cost ** 2, np.inf))
    teams: dict[int, list[int]] = {k: [] for k in objs}
    for i, j in zip(rows.tolist(), cols.tolist(), strict=True):
        teams[objs[slots[j]]].append(pool[i])
    return {k: sorted(t) for k, t in teams.items()}


def reinforce(pool: Sequence[int], robot_positions: np.ndarray, object_poses: np.ndarray,
              teams: Mapping[int, list[int]], reach: float = math.inf) -> dict[int, list[int]]:
    """``teams`` (object -> robots, in priority order) with the robots of ``pool`` (in
    order) joined: each the team of the nearest object among those below ``MAX_ROBOTS``
    and within ``reach`` of it (ties by priority), until none has room. Deterministic;
    robots ascending."""
    out = {k: sorted(t) for k, t in teams.items()}
    order = list(out)
    for i in pool:
        dist = {k: planar_distance(robot_positions[i], object_poses[k])
                for k in order if len(out[k]) < MAX_ROBOTS}
        if not dist:
            break
        k = min(dist, key=lambda k: (dist[k], order.index(k)))
        if dist[k] <= reach:
            out[k] = sorted(out[k] + [i])
    return out


def least_conflict_order(candidates: Sequence[int], corridors: Mapping[int, shapely.Geometry],
                         busy: Sequence[shapely.Geometry],
                         blocks: Mapping[int, Set[int]] | None = None) -> list[int]:
    """``candidates`` in the order they should start: greedily, next the one whose goal
    lies in the way of the fewest candidates not yet put (``blocks[k]``: the objects whose
    way ``k``'s goal lies in, :func:`in_the_way`; none when ``blocks`` is None), then
    that heads the longest chain of objects that must start after it (:func:`chain_depths`:
    the critical path first), then whose corridor (``corridors[k]``: the way it has to go)
    meets the fewest of ``busy`` (the moving objects' corridors) and of the corridors of
    those put before it; ties by index. Objects whose ways do not cross start together,
    crossing ones wait, and an object whose goal would bar another's way starts after
    it."""
    rest, taken, out = sorted(candidates), list(busy), []
    blocks = blocks or {}
    depth = chain_depths(rest, blocks)
    while rest:
        k = min(rest, key=lambda k: (len(blocks.get(k, set()) & (set(rest) - {k})), -depth[k],
                                     sum(corridors[k].intersects(b) for b in taken), k))
        rest.remove(k)
        out.append(k)
        taken.append(corridors[k])
    return out


def chain_depths(candidates: Sequence[int], blocks: Mapping[int, Set[int]]) -> dict[int, int]:
    """For each of ``candidates``: how many candidates the longest chain starting at it
    holds, where ``j`` follows ``k`` when ``j``'s goal lies in ``k``'s way (``k`` in
    ``blocks[j]``: ``j`` should start after ``k``). Objects on a cycle of that relation
    count as one link of the size of their strongly connected component (SciPy), so
    those on one cycle get the same depth. An object nothing follows has depth 1."""
    cands = sorted(candidates)
    index = {k: i for i, k in enumerate(cands)}
    edges = [(index[k], index[j]) for j in cands for k in blocks.get(j, ()) if k in index
             and k != j]
    n = len(cands)
    if not edges:
        return dict.fromkeys(cands, 1)
    rows, cols = zip(*edges, strict=True)
    graph = csr_array((np.ones(len(edges)), (rows, cols)), shape=(n, n))
    _, label = connected_components(graph, directed=True, connection="strong")
    size = np.bincount(label)
    after: dict[int, set[int]] = {c: set() for c in range(len(size))}
    for a, b in edges:
        if label[a] != label[b]:
            after[int(label[a])].add(int(label[b]))
    depth: dict[int, int] = {}

    def visit(c: int) -> int:  # the condensation is acyclic: plain memoised recursion
        if c not in depth:
            depth[c] = int(size[c]) + max((visit(d) for d in after[c]), default=0)
        return depth[c]

    return {k: visit(int(label[index[k]])) for k in cands}


def in_the_way(corridors: Mapping[int, shapely.Geometry],
               goals: Mapping[int, shapely.Geometry], poses: Mapping[int, np.ndarray],
               goal_poses: Mapping[int, np.ndarray]) -> dict[int, set[int]]:
    """For each object ``k``: the objects ``j`` whose way its goal lies in, that is,
    ``k``'s footprint at its goal (``goals[k]``) meets ``j``'s corridor and its goal lies
    nearer ``j``'s pose than ``j``'s own goal does (before ``j``'s goal on its way, not
    beside or beyond it). Placed before ``j`` moves, ``k`` would stand in its way."""
    return {k: {j for j in corridors if j != k and goals[k].intersects(corridors[j])
                and planar_distance(poses[j], goal_poses[k])
                < planar_distance(poses[j], goal_poses[j])}
            for k in goals}


def stands_in_way(scene: Scene, poses: np.ndarray, candidates: Sequence[int]
                  ) -> dict[int, set[int]]:
    """For each of ``candidates`` (objects of ``scene`` at ``poses``) ``j``: the others
    that stand in its way (:func:`in_way_of`). Until they move, ``j`` goes round them or
    waits: a line of loads leaving an aisle is led by the one nearest the exit."""
    return {j: in_way_of(scene, poses, j, [k for k in candidates if k != j])
            for j in candidates}


def in_way_of(scene: Scene, poses: np.ndarray, j: int, others: Sequence[int],
              way: shapely.LineString | None = None) -> set[int]:
    """Those of ``others`` (objects of ``scene`` at ``poses``) whose footprint comes within
    ``j``'s circumscribed radius plus a robot diameter of ``way`` (a line from its pose
    on; default its shortest way to its goal round the obstacles,
    ``scene.bounds.object_way``): where ``j`` and its robots pass, and push it from."""
    if way is None:
        pts = object_way(scene, j, poses[j])
        way = None if pts is None else shapely.LineString(pts)
    if way is None or not others or way.length == 0.0:
        return set()
    objs = scene.objects
    reach = objs[j].shape.bounding_radius + 2 * float(scene.robot_radius)
    return {k for k in others
            if shapely.dwithin(way, to_shapely(objs[k].shape, np.asarray(poses[k], float)), reach)}


def corridor(shape: Shape, pose: np.ndarray, goal: np.ndarray, robot_radius: float
             ) -> shapely.Geometry:
    """An object's way from ``pose`` to ``goal``: the convex hull of its footprints at
    both, grown by a robot diameter."""
    ends = shapely.union_all([to_shapely(shape, np.asarray(pose, float)),
                              to_shapely(shape, np.asarray(goal, float))])
    return ends.convex_hull.buffer(2 * float(robot_radius))


def goal_blocks(scene: Scene, poses: np.ndarray, candidates: Sequence[int]
                ) -> tuple[dict[int, shapely.Geometry], dict[int, set[int]]]:
    """The :func:`corridor` of each of ``candidates`` (objects of ``scene`` at ``poses``)
    and :func:`in_the_way` taken among them."""
    objs, r = scene.objects, scene.robot_radius
    ways = {k: corridor(objs[k].shape, poses[k], objs[k].goal, r) for k in candidates}
    blocks = in_the_way(ways, {k: to_shapely(objs[k].shape, np.asarray(objs[k].goal, float))
                               for k in candidates},
                        {k: poses[k] for k in candidates}, {k: objs[k].goal for k in candidates})
    return ways, blocks


def start_order(scene: Scene, poses: np.ndarray, candidates: Sequence[int],
                moving: Sequence[int], in_way: bool = False) -> list[int]:
    """``candidates`` (objects of ``scene`` at ``poses``) in :func:`least_conflict_order`,
    the corridors of the ``moving`` objects busy and :func:`in_the_way` taken among the
    candidates (:func:`goal_blocks`), and with ``in_way`` :func:`stands_in_way` too."""
    objs, r = scene.objects, scene.robot_radius
    ways, blocks = goal_blocks(scene, poses, candidates)
    standing = (stands_in_way(scene, poses, candidates) if in_way
                else {k: set() for k in candidates})
    # one standing in k's way whose goal lies in it is placed after k whatever happens:
    # k goes first (round it, or it makes way), as the goal says
    after = {k: blocks.get(k, set()) | {j for j in standing[k] if k not in blocks.get(j, ())}
             for k in candidates}
    busy = [corridor(objs[k].shape, poses[k], objs[k].goal, r) for k in moving]
    return least_conflict_order(candidates, ways, busy, after)


def near_way(scene: Scene, k: int, pose: np.ndarray, pool: Sequence[int],
             robot_positions: np.ndarray, reach: float = GROW_REACH) -> list[int]:
    """The robots of ``pool`` (in order) whose centre lies within ``reach`` of object
    ``k``'s way from ``pose`` to its goal (:func:`corridor`)."""
    obj = scene.objects[k]
    way = corridor(obj.shape, pose, obj.goal, scene.robot_radius)
    pts = shapely.points(np.asarray(robot_positions, float)[list(pool)].reshape(-1, 2))
    return [i for i, d in zip(pool, shapely.distance(way, pts), strict=True) if d <= reach]


def needed_space(shape: Shape, pose: np.ndarray, goal: np.ndarray, team: np.ndarray,
                 robot_radius: float, claim: shapely.Geometry | None = None
                 ) -> shapely.Geometry:
    """The space an object of ``shape`` at ``pose`` needs to be reached by its sub-team
    (``team``, (N, 2) robot centres) and moved to ``goal``: its :func:`corridor`, the
    convex hull of its footprint and the robots grown by a robot diameter (their
    approach), and ``claim`` (its last plan's, ``regions.claims``) when given. A body
    standing in it may be what a planner that finds no plan finds no way past
    (``Fleet.plan_failed``)."""
    pose = np.asarray(pose, float)
    body = to_shapely(shape, pose)
    approach = shapely.union(body, shapely.multipoints(np.asarray(team, float).reshape(-1, 2)))
    parts = [corridor(shape, pose, goal, robot_radius),
             approach.convex_hull.buffer(2 * float(robot_radius))]
    return shapely.union_all(parts + ([claim] if claim is not None else []))
