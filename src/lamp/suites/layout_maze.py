"""The ``random`` and ``maze`` map families (see :mod:`lamp.suites.generators`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
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


@dataclass(frozen=True)
class _MazeGrid:
    """The maze's cells: column widths and tightness (``cw``, ``ct``), row heights and
    tightness (``rh``, ``rt``), cell edges ``xs``/``ys`` (``xs[i]`` = left edge of column
    ``i``), cell centres ``xc``/``yc`` and the wall thickness ``t``. A wall key
    ``(i, j, "v")`` separates cells (i, j) and (i+1, j); ``(i, j, "h")`` (i, j) and (i, j+1)."""

    cw: np.ndarray
    ct: np.ndarray
    rh: np.ndarray
    rt: np.ndarray
    xs: np.ndarray
    ys: np.ndarray
    xc: np.ndarray
    yc: np.ndarray
    t: float

    @property
    def nx(self) -> int:
        return len(self.cw)

    @property
    def ny(self) -> int:
        return len(self.rh)

    def cid(self, i: int, j: int) -> int:
        return j * self.nx + i

    def roomy_move(self, i: int, j: int, o: str) -> bool:
        return not self.rt[j] if o == "v" else not self.ct[i]


def _maze_grid(rng: np.random.Generator, obj: ObjectSpec) -> _MazeGrid:
    """Draw the columns and rows (see :func:`_maze_widths`) and place them."""
    W, H = WORKSPACE
    t = 0.07
    cw, ct = _maze_widths(rng, obj, W, t)
    rh, rt = _maze_widths(rng, obj, H, t)
    xs = np.concatenate([[0.0], np.cumsum(cw + t)])  # xs[i] = left edge of column i
    xs[-1] = W + t  # so that the last column's right edge is the border
    ys = np.concatenate([[0.0], np.cumsum(rh + t)])
    ys[-1] = H + t
    # wall line between column i and i+1 is centred at xs[i+1] - t/2
    xc = 0.5 * (xs[:-1] + xs[1:] - t)
    yc = 0.5 * (ys[:-1] + ys[1:] - t)
    return _MazeGrid(cw, ct, rh, rt, xs, ys, xc, yc, t)


def _carve_spanning_tree(rng: np.random.Generator, g: _MazeGrid) -> dict[tuple[int, int, str], str]:
    """Every wall of the grid, "wall" or "open": randomised depth-first search over the
    roomy moves opens a spanning tree of each roomy component (every cell not tight in
    both directions is reached)."""
    nx, ny, cid = g.nx, g.ny, g.cid
    walls: dict[tuple[int, int, str], str] = {}
    for j in range(ny):
        for i in range(nx):
            if i + 1 < nx:
                walls[(i, j, "v")] = "wall"
            if j + 1 < ny:
                walls[(i, j, "h")] = "wall"
    seen = np.zeros(nx * ny, dtype=bool)
    roots = [(i, j) for j in range(ny) for i in range(nx) if not (g.ct[i] and g.rt[j])]
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
                if 0 <= a < nx and 0 <= b < ny and not seen[cid(a, b)] and g.roomy_move(*key):
                    nbrs.append((a, b, key))
            if not nbrs:
                stack.pop()
                continue
            a, b, key = nbrs[int(rng.integers(len(nbrs)))]
            walls[key] = "open"
            seen[cid(a, b)] = True
            stack.append((a, b))
    return walls


def _maze_edges(g: _MazeGrid, walls: dict[tuple[int, int, str], str], states: tuple[str, ...],
                roomy_only: bool) -> list[tuple[int, int, float]]:
    """Cell-graph edges (cell, cell, centre distance) through the walls in ``states``."""
    out = []
    for (i, j, o), st in walls.items():
        if st in states and (g.roomy_move(i, j, o) or not roomy_only):
            a = g.cid(i, j)
            b = g.cid(i + 1, j) if o == "v" else g.cid(i, j + 1)
            pa = (g.xc[i], g.yc[j])
            pb = (g.xc[i + 1], g.yc[j]) if o == "v" else (g.xc[i], g.yc[j + 1])
            out.append((a, b, float(math.dist(pa, pb))))
    return out


def _open_extra_walls(rng: np.random.Generator, g: _MazeGrid,
                      walls: dict[tuple[int, int, str], str], want_tight: bool) -> None:
    """Open, in place: shortcuts along tight corridors (preferring walls between cells far
    apart), one wall of each cell tight in both directions that is still closed in, and
    with probability 0.3 one roomy wall (a loop)."""
    nx, ny, cid = g.nx, g.ny, g.cid
    keys = sorted(walls)
    # shortcuts along tight corridors, preferring walls between cells far apart
    d_open = graph_distances(nx * ny, _maze_edges(g, walls, ("open",), True))
    tight_walls = [k for k in keys if walls[k] == "wall" and not g.roomy_move(*k)]
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
            if not (g.ct[i] and g.rt[j]):
                continue
            around = [(i - 1, j, "v"), (i, j, "v"), (i, j - 1, "h"), (i, j, "h")]
            around = [k for k in around if k in walls]
            if all(walls[k] == "wall" for k in around):
                walls[around[int(rng.integers(len(around)))]] = "open"
    roomy_walls = [k for k in keys if walls[k] == "wall" and g.roomy_move(*k)]
    if roomy_walls and rng.random() < 0.3:
        walls[roomy_walls[int(rng.integers(len(roomy_walls)))]] = "open"


def _wall_rectangles(g: _MazeGrid, walls: dict[tuple[int, int, str], str]) -> list[dict[str, Any]]:
    """The closed walls as rectangles, each run of closed segments along a grid line merged
    into one."""
    W, H = WORKSPACE
    xs, ys, t = g.xs, g.ys, g.t
    obstacles: list[dict[str, Any]] = []
    for o, n_lines, n_pos in (("v", g.nx - 1, g.ny), ("h", g.ny - 1, g.nx)):
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
    return obstacles


def layout_maze(rng: np.random.Generator, obj: ObjectSpec, want_tight: bool) -> Layout:
    """A corridor maze of thin walls on a grid whose columns and rows are either roomy
    (the object plus a robot on each side) or tight (the object plus 7-10 cm: corridors
    too narrow for a robot beside the object). A spanning tree is carved by randomised
    depth-first search over the roomy moves (horizontal moves are roomy in roomy rows,
    vertical moves in roomy columns), so every cell with a roomy dimension is connected
    with robot room; then some walls are opened along tight corridors (shortcuts only
    the object fits through) and one roomy loop may be added. Sites are cell centres
    where the object fits with room all around; the passage graph is the cell graph."""
    g = _maze_grid(rng, obj)
    nx, ny = g.nx, g.ny
    walls = _carve_spanning_tree(rng, g)
    _open_extra_walls(rng, g, walls, want_tight)
    d_roomy = graph_distances(nx * ny, _maze_edges(g, walls, ("open",), True))
    d_all = graph_distances(nx * ny, _maze_edges(g, walls, ("open",), False))
    obstacles = _wall_rectangles(g, walls)
    sites = np.array([(g.xc[i], g.yc[j], 0.0) for j in range(ny) for i in range(nx)])
    n_tight_open = sum(1 for k, v in walls.items() if v == "open" and not g.roomy_move(*k))
    info = {
        "grid": [nx, ny],
        "tight_columns": int(g.ct.sum()),
        "tight_rows": int(g.rt.sum()),
        "tight_openings": n_tight_open,
    }
    return Layout(obstacles, sites, d_roomy, d_all, info)
