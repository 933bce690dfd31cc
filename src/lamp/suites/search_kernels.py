"""Compiled (Numba) lattice search and path shortcutting behind ``lamp.suites.routes``.

:func:`lattice_astar` is A* over the SE(2) lattice whose nodes are checked with the exact
clearances of :mod:`lamp.suites.kernels` (computed lazily, cached per node) and whose moves
are certified by :func:`lamp.suites.kernels.motion_ok`; :func:`shortcut` greedily drops
waypoints of a certified polyline, keeping it certified. The world and object arrays follow
the conventions of :mod:`lamp.suites.kernels`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from lamp.suites.kernels import BIG, motion_ok, pose_clearance


@numba.njit(cache=True)
def _node_clear(
    node: int,
    cache: np.ndarray,
    nx: int,
    ny: int,
    h: float,
    dth: float,
    obj_r: float,
    ov: np.ndarray,
    on: np.ndarray,
    obj_reach: float,
    circ: np.ndarray,
    pv: np.ndarray,
    pn: np.ndarray,
    pb: np.ndarray,
    width: float,
    height: float,
) -> float:
    c = cache[node]
    if math.isnan(c):
        i = node % nx
        j = (node // nx) % ny
        k = node // (nx * ny)
        c = pose_clearance(
            (i + 1) * h, (j + 1) * h, k * dth, obj_r, ov, on, obj_reach,
            circ, pv, pn, pb, width, height, -BIG,
        )  # fmt: skip
        cache[node] = c
    return c


@numba.njit(cache=True)
def _heap_push(keys: np.ndarray, vals: np.ndarray, size: int, key: float, val: int) -> int:
    """Push onto the binary min-heap stored in keys/vals[:size]; returns the new size
    (the arrays must have room)."""
    i = size
    keys[i] = key
    vals[i] = val
    while i > 0:
        p = (i - 1) // 2
        if keys[p] <= keys[i]:
            break
        keys[p], keys[i] = keys[i], keys[p]
        vals[p], vals[i] = vals[i], vals[p]
        i = p
    return size + 1


@numba.njit(cache=True)
def _heap_pop(keys: np.ndarray, vals: np.ndarray, size: int) -> tuple[float, int, int]:
    """Pop the minimum; returns (key, value, new size)."""
    key = keys[0]
    val = vals[0]
    size -= 1
    keys[0] = keys[size]
    vals[0] = vals[size]
    i = 0
    while True:
        lft = 2 * i + 1
        if lft >= size:
            break
        c = lft
        if lft + 1 < size and keys[lft + 1] < keys[lft]:
            c = lft + 1
        if keys[i] <= keys[c]:
            break
        keys[c], keys[i] = keys[i], keys[c]
        vals[c], vals[i] = vals[i], vals[c]
        i = c
    return key, val, size


@numba.njit(cache=True)
def _heap_push_grow(
    keys: np.ndarray, vals: np.ndarray, size: int, key: float, val: int
) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`_heap_push`, first doubling the arrays when they are full; returns the
    (possibly new) arrays and the new size."""
    if size == keys.shape[0]:
        keys = np.concatenate((keys, np.empty(size)))
        vals = np.concatenate((vals, np.empty(size, dtype=np.int64)))
    size = _heap_push(keys, vals, size, key, val)
    return keys, vals, size


@numba.njit(cache=True)
def _push_sources(
    src_nodes: np.ndarray,
    src_costs: np.ndarray,
    g: np.ndarray,
    parent: np.ndarray,
    nx: int,
    ny: int,
    h: float,
    goal_x: float,
    goal_y: float,
    slack: float,
) -> tuple[np.ndarray, np.ndarray, int]:
    """A new open heap holding every source at its initial cost (the cheapest when a node
    is given twice); sets their ``g`` and marks their ``parent`` -2. Returns (keys, values,
    size)."""
    hk = np.empty(1024)
    hv = np.empty(1024, dtype=np.int64)
    hn = 0
    for m in range(src_nodes.shape[0]):
        s = src_nodes[m]
        if src_costs[m] < g[s]:
            g[s] = src_costs[m]
            parent[s] = -2  # a source
            i = s % nx
            j = (s // nx) % ny
            hx = (i + 1) * h - goal_x
            hy = (j + 1) * h - goal_y
            hk, hv, hn = _heap_push_grow(hk, hv, hn, g[s] + max(0.0, math.hypot(hx, hy) - slack), s)
    return hk, hv, hn


@numba.njit(cache=True)
def _move(
    mv: int,
    i: int,
    j: int,
    k: int,
    nx: int,
    ny: int,
    nh: int,
    h: float,
    dth: float,
    rot_weight: float,
    di: np.ndarray,
    dj: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
) -> tuple[int, float]:
    """Lattice move ``mv`` from node (i, j, k) at pose ``a``: moves 0-7 are the planar
    neighbours (``di``, ``dj``), 8 and 9 the +1 and -1 heading steps. Writes the end pose
    into ``b``; returns (end node, step cost), or (-1, 0.0) when the move leaves the grid."""
    if mv < 8:
        ii = i + di[mv]
        jj = j + dj[mv]
        kk = k
        if ii < 0 or ii >= nx or jj < 0 or jj >= ny:
            return -1, 0.0
        step = h * (1.0 if mv < 4 else math.sqrt(2.0))
        b[0] = (ii + 1) * h
        b[1] = (jj + 1) * h
        b[2] = a[2]
    else:
        ii = i
        jj = j
        sgn = 1 if mv == 8 else -1
        kk = (k + sgn) % nh
        step = rot_weight * dth
        b[0] = a[0]
        b[1] = a[1]
        b[2] = a[2] + sgn * dth
    return (kk * ny + jj) * nx + ii, step


@numba.njit(cache=True)
def lattice_astar(
    nx: int, ny: int, nh: int, h: float, dth: float, tau: float, rot_weight: float,
    src_nodes: np.ndarray, src_costs: np.ndarray, dst_nodes: np.ndarray, dst_costs: np.ndarray,
    goal_x: float, goal_y: float, cache: np.ndarray, max_depth: int,
    obj_r: float, ov: np.ndarray, on: np.ndarray, obj_reach: float,
    circ: np.ndarray, pv: np.ndarray, pn: np.ndarray, pb: np.ndarray, width: float, height: float,
) -> tuple[np.ndarray, int, float]:
    """A* on the SE(2) lattice: node (i, j, k) is the pose ((i+1) h, (j+1) h, k dth) with
    heading index k cyclic modulo ``nh``; moves are the 8 planar neighbours (cost = step
    length) and +-1 heading step (cost ``rot_weight * dth``). A node is usable when its
    clearance is >= tau, a move when ``motion_ok`` certifies it. Multi-source
    (``src_nodes`` with initial costs) and multi-target (``dst_nodes`` with the cost of
    the final connector). Returns (parent array, reached target node or -1, total cost)."""
    n_nodes = nx * ny * nh
    g = np.full(n_nodes, np.inf)
    parent = np.full(n_nodes, -1, dtype=np.int64)
    closed = np.zeros(n_nodes, dtype=np.bool_)
    dst_cost = np.full(n_nodes, np.inf)
    for m in range(dst_nodes.shape[0]):
        dst_cost[dst_nodes[m]] = min(dst_cost[dst_nodes[m]], dst_costs[m])
    slack = h * 0.7072
    # lazy-deletion heap: every push improves g of its node, so pushes <= relaxations;
    # the arrays grow by doubling
    hk, hv, hn = _push_sources(src_nodes, src_costs, g, parent, nx, ny, h, goal_x, goal_y, slack)
    best_total = np.inf
    best_node = -1
    di = np.array([1, -1, 0, 0, 1, 1, -1, -1])
    dj = np.array([0, 0, 1, -1, 1, -1, 1, -1])
    a = np.empty(3)
    b = np.empty(3)
    while hn > 0:
        f, u, hn = _heap_pop(hk, hv, hn)
        if closed[u]:
            continue
        if f >= best_total:
            break
        closed[u] = True
        if dst_cost[u] < np.inf and g[u] + dst_cost[u] < best_total:
            best_total = g[u] + dst_cost[u]
            best_node = u
        i = u % nx
        j = (u // nx) % ny
        k = u // (nx * ny)
        cu = _node_clear(
            u, cache, nx, ny, h, dth, obj_r, ov, on, obj_reach, circ, pv, pn, pb, width, height
        )
        a[0] = (i + 1) * h
        a[1] = (j + 1) * h
        a[2] = k * dth
        n_moves = 8 + (2 if nh > 1 else 0)
        for mv in range(n_moves):
            v, step = _move(mv, i, j, k, nx, ny, nh, h, dth, rot_weight, di, dj, a, b)
            if v < 0:
                continue
            if closed[v]:
                continue
            ng = g[u] + step
            if ng >= g[v]:
                continue
            cv = _node_clear(
                v, cache, nx, ny, h, dth, obj_r, ov, on, obj_reach, circ, pv, pn, pb, width, height
            )
            if cv < tau:
                continue
            if not motion_ok(
                a, b, cu, cv, tau, max_depth,
                obj_r, ov, on, obj_reach, circ, pv, pn, pb, width, height,
            ):  # fmt: skip
                continue
            g[v] = ng
            parent[v] = u
            hx = b[0] - goal_x
            hy = b[1] - goal_y
            hk, hv, hn = _heap_push_grow(hk, hv, hn, ng + max(0.0, math.hypot(hx, hy) - slack), v)
    return parent, best_node, best_total


@numba.njit(cache=True)
def shortcut(
    poses: np.ndarray,
    clear: np.ndarray,
    tau: float,
    max_rot: float,
    max_depth: int,
    obj_r: float,
    ov: np.ndarray,
    on: np.ndarray,
    obj_reach: float,
    circ: np.ndarray,
    pv: np.ndarray,
    pn: np.ndarray,
    pb: np.ndarray,
    width: float,
    height: float,
) -> np.ndarray:
    """Greedy shortcutting of a certified pose polyline: from each kept waypoint jump to
    the farthest later waypoint reachable by one certified straight motion (clearance
    >= tau, rotation <= max_rot). Returns the indices of the kept waypoints."""
    n = poses.shape[0]
    keep = np.empty(n, dtype=np.int64)
    m = 0
    i = 0
    keep[m] = 0
    m += 1
    while i < n - 1:
        nxt = i + 1
        j = n - 1
        while j > i + 1:
            if abs(poses[j, 2] - poses[i, 2]) <= max_rot and motion_ok(
                poses[i], poses[j], clear[i], clear[j], tau, max_depth,
                obj_r, ov, on, obj_reach, circ, pv, pn, pb, width, height,
            ):  # fmt: skip
                nxt = j
                break
            j -= 1
        keep[m] = nxt
        m += 1
        i = nxt
    return keep[:m]
