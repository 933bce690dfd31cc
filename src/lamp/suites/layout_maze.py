"""The ``random`` and ``maze`` map families (see :mod:`lamp.suites.generators`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely

from lamp.geometry.shapes import obstacle_geometry
from lamp.scene.model import shape_from_dict
from lamp.suites import checks as C
from lamp.suites.layout import (
    END_CLEARANCE,
    WORKSPACE,
    Layout,
    ObjectSpec,
    circle,
    graph_distances,
    obstacles_of,
    rect,
    street_width,
    tight_gap,
)


# --------------------------------------------------------------------------- random
def layout_random(rng: np.random.Generator, obj: ObjectSpec) -> Layout:
    """Sparse scattered obstacles: 8-12 circles and boxes, pairwise gaps >= a roomy street."""
    W, H = WORKSPACE
    n = int(rng.integers(10, 15))
    placed: list[shapely.Geometry] = []
    obstacles: list[dict[str, Any]] = []
    for _ in range(400):
        if len(obstacles) >= n:
            break
        if rng.random() < 0.45:
            r = rng.uniform(0.10, 0.30)
            x, y = rng.uniform(r, W - r), rng.uniform(r, H - r)
            d = circle(x, y, r)
        else:
            sx, sy = rng.uniform(0.2, 0.6, size=2)
            ang = rng.uniform(0.0, math.pi)
            x, y = rng.uniform(0.3, W - 0.3), rng.uniform(0.3, H - 0.3)
            d = rect(x, y, sx, sy, ang)
        geom = obstacle_geometry(obstacles_of([d])[0])
        x0, y0, x1, y1 = geom.bounds
        if x0 < 0 or y0 < 0 or x1 > W or y1 > H:
            continue
        # pairwise gaps between 0.25 m and a roomy street: mostly open, a few narrows
        gap = rng.uniform(0.25, obj.width + 0.35)
        if min(x0, y0, W - x1, H - y1) < 0.2:
            continue
        if any(geom.distance(g) < gap for g in placed):
            continue
        placed.append(geom)
        obstacles.append(d)
    # sites: random poses where the object fits with room all around
    world = C.build_world(WORKSPACE, obstacles_of(obstacles))
    cand = np.stack(
        [
            rng.uniform(0.3, W - 0.3, 300),
            rng.uniform(0.3, H - 0.3, 300),
            rng.uniform(-math.pi, math.pi, 300),
        ],
        axis=1,
    )
    if obj.is_circle:
        cand[:, 2] = 0.0
    ok = C.clearance(shape_from_dict(obj.shape), world, cand) >= END_CLEARANCE + 0.02
    sites = cand[ok][:40]
    d = np.hypot(sites[:, None, 0] - sites[None, :, 0], sites[:, None, 1] - sites[None, :, 1])
    return Layout(obstacles, sites, d, d, {"n_obstacles": len(obstacles)})


# --------------------------------------------------------------------------- maze
def _maze_widths(
    rng: np.random.Generator, obj: ObjectSpec, total: float, t: float
) -> tuple[np.ndarray, np.ndarray]:
    """Free widths of the maze's columns (or rows) and whether each is tight: roomy ones
    hold the object plus robot room, tight ones (about 30%) only the object plus 7-10 cm.
    Wall thickness ``t`` sits on each internal grid line; the roomy widths are stretched
    so that the cells fill ``total`` exactly."""
    free: list[float] = []
    tight: list[bool] = []

    def span(n: int, widths: list[float]) -> float:
        return float(sum(widths)) + t * (n - 1)

    while True:
        is_t = len(free) > 0 and not tight[-1] and rng.random() < 0.35
        w = tight_gap(rng, obj) if is_t else street_width(rng, obj, 0.28, 0.40)
        if span(len(free) + 1, [*free, w]) > total:
            break
        free.append(w)
        tight.append(is_t)
    if not any(not x for x in tight):
        raise RuntimeError("maze: no roomy corridor fits")  # cannot happen for 4 m
    rest = total - span(len(free), free)
    roomy = np.array([not x for x in tight])
    widths = np.array(free)
    widths[roomy] += rest / roomy.sum()
    return widths, np.array(tight)


def layout_maze(rng: np.random.Generator, obj: ObjectSpec, want_tight: bool) -> Layout:
    """A corridor maze of thin walls on a grid whose columns and rows are either roomy
    (the object plus a robot on each side) or tight (the object plus 7-10 cm: corridors
    too narrow for a robot beside the object). A spanning tree is carved by randomised
    depth-first search over the roomy moves (horizontal moves are roomy in roomy rows,
    vertical moves in roomy columns), so every cell with a roomy dimension is connected
    with robot room; then some walls are opened along tight corridors (shortcuts only
    the object fits through) and one roomy loop may be added. Sites are cell centres
    where the object fits with room all around; the passage graph is the cell graph."""
    W, H = WORKSPACE
    t = 0.07
    cw, ct = _maze_widths(rng, obj, W, t)
    rh, rt = _maze_widths(rng, obj, H, t)
    nx, ny = len(cw), len(rh)
    xs = np.concatenate([[0.0], np.cumsum(cw + t)])  # xs[i] = left edge of column i
    xs[-1] = W + t  # so that the last column's right edge is the border
    ys = np.concatenate([[0.0], np.cumsum(rh + t)])
    ys[-1] = H + t
    # wall line between column i and i+1 is centred at xs[i+1] - t/2
    xc = 0.5 * (xs[:-1] + xs[1:] - t)
    yc = 0.5 * (ys[:-1] + ys[1:] - t)

    def cid(i: int, j: int) -> int:
        return j * nx + i

    def roomy_move(i: int, j: int, o: str) -> bool:
        return not rt[j] if o == "v" else not ct[i]

    walls: dict[tuple[int, int, str], str] = {}
    for j in range(ny):
        for i in range(nx):
            if i + 1 < nx:
                walls[(i, j, "v")] = "wall"
            if j + 1 < ny:
                walls[(i, j, "h")] = "wall"
    keys = sorted(walls)
    seen = np.zeros(nx * ny, dtype=bool)
    roots = [(i, j) for j in range(ny) for i in range(nx) if not (ct[i] and rt[j])]
    for root in [roots[int(rng.integers(len(roots)))]] + roots:
        if seen[cid(*root)]:
            continue
        seen[cid(*root)] = True
        stack = [root]
        while stack:
            i, j = stack[-1]
            nbrs = []
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                a, b = i + di, j + dj
                key = (min(i, a), min(j, b), "v" if di else "h")
                if 0 <= a < nx and 0 <= b < ny and not seen[cid(a, b)] and roomy_move(*key):
                    nbrs.append((a, b, key))
            if not nbrs:
                stack.pop()
                continue
            a, b, key = nbrs[int(rng.integers(len(nbrs)))]
            walls[key] = "open"
            seen[cid(a, b)] = True
            stack.append((a, b))

    def edges(states: tuple[str, ...], roomy_only: bool) -> list[tuple[int, int, float]]:
        out = []
        for (i, j, o), st in walls.items():
            if st in states and (roomy_move(i, j, o) or not roomy_only):
                a = cid(i, j)
                b = cid(i + 1, j) if o == "v" else cid(i, j + 1)
                pa = (xc[i], yc[j])
                pb = (xc[i + 1], yc[j]) if o == "v" else (xc[i], yc[j + 1])
                out.append((a, b, float(math.dist(pa, pb))))
        return out

    # shortcuts along tight corridors, preferring walls between cells far apart
    d_open = graph_distances(nx * ny, edges(("open",), True))
    tight_walls = [k for k in keys if walls[k] == "wall" and not roomy_move(*k)]
    far = [
        k
        for k in tight_walls
        if d_open[cid(k[0], k[1]), cid(k[0] + (k[2] == "v"), k[1] + (k[2] == "h"))] > 2.5
    ]
    pool = far if far else tight_walls
    cells = nx * ny
    if want_tight:
        n_short = int(rng.integers(max(1, cells // 10), max(2, cells // 6) + 1))
    else:
        n_short = int(rng.integers(1, max(2, cells // 10) + 1))
    for k in rng.permutation(len(pool))[:n_short]:
        walls[pool[k]] = "open"
    # cells tight in both directions: open one of their walls (no closed boxes)
    for j in range(ny):
        for i in range(nx):
            if not (ct[i] and rt[j]):
                continue
            around = [(i - 1, j, "v"), (i, j, "v"), (i, j - 1, "h"), (i, j, "h")]
            around = [k for k in around if k in walls]
            if all(walls[k] == "wall" for k in around):
                walls[around[int(rng.integers(len(around)))]] = "open"
    roomy_walls = [k for k in keys if walls[k] == "wall" and roomy_move(*k)]
    if roomy_walls and rng.random() < 0.3:
        walls[roomy_walls[int(rng.integers(len(roomy_walls)))]] = "open"
    d_roomy = graph_distances(nx * ny, edges(("open",), True))
    d_all = graph_distances(nx * ny, edges(("open",), False))

    obstacles: list[dict[str, Any]] = []
    # merge runs of closed wall segments along each grid line into one rectangle
    for o, n_lines, n_pos in (("v", nx - 1, ny), ("h", ny - 1, nx)):
        for line in range(n_lines):
            run: list[int] = []
            for pos in range(n_pos + 1):
                key = (line, pos, o) if o == "v" else (pos, line, o)
                if pos < n_pos and walls.get(key) == "wall":
                    run.append(pos)
                    continue
                if run:
                    edges_ = ys if o == "v" else xs
                    lo = max(0.0, edges_[run[0]] - t)
                    hi = min(H if o == "v" else W, edges_[run[-1] + 1])
                    c = (xs if o == "v" else ys)[line + 1] - t / 2
                    if o == "v":
                        obstacles.append(rect(c, 0.5 * (lo + hi), t, hi - lo))
                    else:
                        obstacles.append(rect(0.5 * (lo + hi), c, hi - lo, t))
                    run = []
    sites = np.array([(xc[i], yc[j], 0.0) for j in range(ny) for i in range(nx)])
    n_tight_open = sum(1 for k, v in walls.items() if v == "open" and not roomy_move(*k))
    info = {
        "grid": [nx, ny],
        "tight_columns": int(ct.sum()),
        "tight_rows": int(rt.sum()),
        "tight_openings": n_tight_open,
    }
    return Layout(obstacles, sites, d_roomy, d_all, info)
