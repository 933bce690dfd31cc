"""Seeded generators of the benchmark families (LAMP paper, Experiments, Fig. 3).

Four families of single-object scenes, 25 each, in a 4 m x 4 m workspace with 3 robots of
radius 0.05 m and one object (a circle of radius 0.10-0.30 m or a rectangle with sides
0.15-0.50 m; even indices rectangles, odd indices circles):

* ``random``: relatively sparse scattered circles and boxes;
* ``maze``: a corridor maze of thin walls on a grid of cells sized to the object;
* ``tilt``: a lattice of blocks rotated by an oblique angle, forming diagonal channels;
* ``warehouse``: shelf rows with aisles and cross-aisles, pallets and stationary cargo in
  the aisles, traffic barriers closing some of them, and a free dock area.

Maze, tilt and warehouse are built as a network of *roomy* passages (room for the object
plus a robot on each side) in which some passages are *tight* (only 7-10 cm wider than the
object: no room for a 0.1 m robot beside it) and some are closed. Start and goal are
picked on a small passage graph so that, in most scenes (``TIGHT_SHARE``), the tight
passages make a markedly shorter route than the roomy one: the paper's Fig. 1 situation.
Every generated scene is validated by ``lamp.scene.scene_from_dict`` and checked with
``lamp.suites.checks`` (free route, robot-room route, robots reach the object); an attempt
that fails is discarded and the next one drawn from the same random stream, so a scene is
a pure function of ``(family, index)``.

Maps are generated per scene (the paper uses one map per family with varied objects):
sizing the passages to each scene's object is what makes "slightly wider than the
object" and "room for robots" exact statements.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import shortest_path

from lamp.geometry.shapes import obstacle_geometry
from lamp.scene.loader import SceneError, scene_from_dict
from lamp.scene.model import Obstacle, Scene, shape_from_dict
from lamp.suites import checks as C

FAMILIES = ("random", "maze", "tilt", "warehouse")
SCENES_PER_FAMILY = 25
#: base seed; scene k of family f uses ``np.random.default_rng([SUITE_SEED, f, k])``
SUITE_SEED = 20260
WORKSPACE = (4.0, 4.0)
N_ROBOTS = 3
ROBOT_RADIUS = 0.05
#: share of maze/tilt/warehouse scenes whose start and goal are chosen for a too-tight
#: shortest route (the others pick any far-apart pair; decoy tight passages remain)
TIGHT_SHARE = 0.8
#: clearance (m) of the object at its start and goal: robots fit all around it
END_CLEARANCE = 0.16
#: tight passages are wider than the object by this much (total, both sides)
TIGHT_SLACK = (0.07, 0.10)
MAX_ATTEMPTS = 60


# --------------------------------------------------------------------------- helpers
def _r(v: float, nd: int = 3) -> float:
    """Round for the scene file (mm positions/sizes, 1e-4 rad angles); no negative zero."""
    out = round(float(v), nd)
    return 0.0 if out == 0.0 else out


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def rect(cx: float, cy: float, sx: float, sy: float, angle: float = 0.0) -> dict[str, Any]:
    """Rectangle obstacle dict (rounded). Axis-aligned ones are rounded through their
    bounds (to mm), so that a rectangle meant to touch the border stays inside it."""
    if angle == 0.0:
        x0, x1 = _r(cx - 0.5 * sx), _r(cx + 0.5 * sx)
        y0, y1 = _r(cy - 0.5 * sy), _r(cy + 0.5 * sy)
        return {
            "type": "rectangle",
            "center": [_r(0.5 * (x0 + x1), 4), _r(0.5 * (y0 + y1), 4)],
            "size": [_r(x1 - x0), _r(y1 - y0)],
            "angle": 0.0,
        }
    return {
        "type": "rectangle",
        "center": [_r(cx), _r(cy)],
        "size": [_r(sx), _r(sy)],
        "angle": _r(_wrap(angle) if angle else 0.0, 4),
    }


def circle(cx: float, cy: float, r: float) -> dict[str, Any]:
    return {"type": "circle", "center": [_r(cx), _r(cy)], "radius": _r(r)}


def polygon(points: np.ndarray) -> dict[str, Any]:
    return {"type": "polygon", "points": [[_r(x), _r(y)] for x, y in points]}


def _obstacles_of(dicts: list[dict[str, Any]]) -> list[Obstacle]:
    out = []
    for d in dicts:
        if d["type"] == "polygon":
            out.append(Obstacle(shape_from_dict(d)))
        else:
            ang = d.get("angle", 0.0)
            out.append(Obstacle(shape_from_dict(d), (d["center"][0], d["center"][1], ang)))
    return out


@dataclass(frozen=True)
class ObjectSpec:
    """The scene's object: its file dict and a few derived extents."""

    shape: dict[str, Any]
    width: float  # narrowest extent (what a tight passage is sized to)
    length: float  # largest side (circle: diameter)
    reach: float  # bounding radius

    @property
    def is_circle(self) -> bool:
        return self.shape["type"] == "circle"


def sample_object(rng: np.random.Generator, index: int) -> ObjectSpec:
    """Even index: rectangle with sides in [0.15, 0.50]; odd: circle of radius [0.10, 0.30]."""
    if index % 2 == 1:
        r = _r(rng.uniform(0.10, 0.30))
        return ObjectSpec({"type": "circle", "radius": r}, 2 * r, 2 * r, r)
    a, b = (_r(v) for v in rng.uniform(0.15, 0.50, size=2))
    return ObjectSpec(
        {"type": "rectangle", "size": [a, b]}, min(a, b), max(a, b), 0.5 * math.hypot(a, b)
    )


def street_width(
    rng: np.random.Generator, obj: ObjectSpec, lo: float = 0.30, hi: float = 0.42
) -> float:
    """A roomy passage for this object: the object plus a robot-room margin on each side,
    and wide enough for a rectangle to get round a right-angle corner with that margin
    (ladder-around-a-corner bound 2 (a sqrt 2 - w) >= l, with l, w inflated by 0.125 m)."""
    s = obj.width + rng.uniform(lo, hi)
    if not obj.is_circle:
        turn = (0.5 * obj.length + obj.width + 0.375) / math.sqrt(2.0)
        s = max(s, min(obj.length + 0.28, turn + 0.03))
    return s


def tight_gap(rng: np.random.Generator, obj: ObjectSpec) -> float:
    return obj.width + rng.uniform(*TIGHT_SLACK)


@dataclass
class Layout:
    """A generated map plus candidate object sites and a passage graph for guidance."""

    obstacles: list[dict[str, Any]]
    #: candidate object positions with preferred headings (x, y, theta)
    sites: np.ndarray
    #: (n_sites, n_sites) shortest passage-graph distances using roomy passages only
    d_roomy: np.ndarray
    #: the same, also using tight passages
    d_all: np.ndarray
    #: summary of the layout for the manifest (grid size, tight/closed passages, ...)
    info: dict[str, Any] = field(default_factory=dict)


def _graph_distances(n: int, edges: list[tuple[int, int, float]]) -> np.ndarray:
    if not edges:
        d = np.full((n, n), np.inf)
        np.fill_diagonal(d, 0.0)
        return d
    i, j, w = (np.array(v) for v in zip(*edges, strict=True))
    m = coo_matrix((w, (i, j)), shape=(n, n)).tocsr()
    return shortest_path(m, directed=False)


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
        geom = obstacle_geometry(_obstacles_of([d])[0])
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
    world = C.build_world(WORKSPACE, _obstacles_of(obstacles))
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
    d_open = _graph_distances(nx * ny, edges(("open",), True))
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
    d_roomy = _graph_distances(nx * ny, edges(("open",), True))
    d_all = _graph_distances(nx * ny, edges(("open",), False))

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


# --------------------------------------------------------------------------- block lattice
def _street_offsets(streets: np.ndarray, blocks: np.ndarray) -> tuple[list[float], list[float]]:
    """Along one lattice axis, alternating streets and blocks from 0: the start of every
    street (``len(blocks) + 1`` of them) and of every block."""
    pos = 0.0
    street0, block0 = [], []
    for i in range(len(blocks)):
        street0.append(pos)
        pos += streets[i]
        block0.append(pos)
        pos += blocks[i]
    street0.append(pos)
    return street0, block0


@dataclass
class _Lattice:
    """Blocks on a (possibly rotated) lattice: columns of widths ``bu`` separated by
    streets ``su`` (one before the first column and one after the last), rows likewise;
    frame origin ``origin`` (world), rotation ``angle``."""

    bu: np.ndarray
    su: np.ndarray
    bv: np.ndarray
    sv: np.ndarray
    origin: np.ndarray
    angle: float

    def __post_init__(self) -> None:
        # street i spans [us0[i], us0[i] + su[i]] in u; column i follows street i (v alike)
        self.us0, self.uc0 = _street_offsets(self.su, self.bu)
        self.vs0, self.vr0 = _street_offsets(self.sv, self.bv)

    def world(self, u: float, v: float) -> np.ndarray:
        c, s = math.cos(self.angle), math.sin(self.angle)
        return self.origin + np.array([c * u - s * v, s * u + c * v])

    def box(self, u0: float, u1: float, v0: float, v1: float) -> tuple[float, float, float, float]:
        """World centre and size of the frame-aligned box [u0, u1] x [v0, v1]."""
        cx, cy = self.world(0.5 * (u0 + u1), 0.5 * (v0 + v1))
        return float(cx), float(cy), u1 - u0, v1 - v0


def _clip_box(
    lat: _Lattice, u0: float, u1: float, v0: float, v1: float, min_area: float = 0.02
) -> dict[str, Any] | None:
    """Obstacle dict of a lattice box clipped to the workspace (rectangle when entirely
    inside, else the convex polygon of the intersection; None when too small)."""
    W, H = WORKSPACE
    cx, cy, sx, sy = lat.box(u0, u1, v0, v1)
    d = rect(cx, cy, sx, sy, lat.angle)
    geom = obstacle_geometry(_obstacles_of([d])[0])
    x0, y0, x1, y1 = geom.bounds
    if x0 >= -1e-9 and y0 >= -1e-9 and x1 <= W + 1e-9 and y1 <= H + 1e-9:
        return d
    clipped = geom.intersection(shapely.box(0.0, 0.0, W, H))
    if clipped.is_empty or clipped.geom_type != "Polygon" or clipped.area < min_area:
        return None
    # thin slivers along the border make meaningless obstacles
    if clipped.area / max(clipped.length, 1e-9) < 0.03:
        return None
    pts = np.asarray(shapely.simplify(clipped, 1e-6).exterior.coords)[:-1]
    pts = np.clip(pts, 0.0, [W, H])
    return polygon(pts)


def _lattice_graph(
    lat: _Lattice, states: dict[tuple[str, int, int], str], margin: float
) -> tuple[np.ndarray, list[tuple[int, int, float, str]]]:
    """Intersections X(i, j) of column-street i and row-street j that lie inside the
    workspace (shrunk by ``margin``) and the street segments between them with states."""
    W, H = WORKSPACE
    nu, nv = len(lat.su), len(lat.sv)
    node_id = -np.ones((nu, nv), dtype=int)
    pts = []
    for i in range(nu):
        for j in range(nv):
            if lat.su[i] <= 0 or lat.sv[j] <= 0:
                continue
            x, y = lat.world(lat.us0[i] + 0.5 * lat.su[i], lat.vs0[j] + 0.5 * lat.sv[j])
            if margin <= x <= W - margin and margin <= y <= H - margin:
                node_id[i, j] = len(pts)
                pts.append((x, y))
    edges = []
    for i in range(nu):
        for j in range(nv):
            a = node_id[i, j]
            if a < 0:
                continue
            if j + 1 < nv and node_id[i, j + 1] >= 0:  # along column-street i past row j
                b = node_id[i, j + 1]
                edges.append(
                    (a, b, float(math.dist(pts[a], pts[b])), states.get(("c", i, j), "roomy"))
                )
            if i + 1 < nu and node_id[i + 1, j] >= 0:  # along row-street j past column i
                b = node_id[i + 1, j]
                edges.append(
                    (a, b, float(math.dist(pts[a], pts[b])), states.get(("r", i, j), "roomy"))
                )
    return np.array(pts).reshape(-1, 2), edges


def _segment_box(lat: _Lattice, kind: str, i: int, j: int) -> tuple[float, float, float, float]:
    """Frame box of street segment: ('c', i, j) = column-street i beside row j;
    ('r', i, j) = row-street j beside column i."""
    if kind == "c":
        return lat.us0[i], lat.us0[i] + lat.su[i], lat.vr0[j], lat.vr0[j] + lat.bv[j]
    return lat.uc0[i], lat.uc0[i] + lat.bu[i], lat.vs0[j], lat.vs0[j] + lat.sv[j]


def _lattice_layout(
    rng: np.random.Generator,
    lat: _Lattice,
    obj: ObjectSpec,
    p_plug: float,
    p_tight: float,
    render_plug: Callable[[tuple[float, float, float, float], str], list[dict[str, Any]]],
    render_tight: Callable[[tuple[float, float, float, float], str, float], list[dict[str, Any]]],
    extra: list[dict[str, Any]],
    info: dict[str, Any],
) -> Layout:
    """Blocks + segment states -> Layout (obstacles, sites at intersections and segment
    midpoints, passage-graph distances)."""
    nu, nv = len(lat.su), len(lat.sv)
    states: dict[tuple[str, int, int], str] = {}
    seg_keys = [("c", i, j) for i in range(1, nu - 1) for j in range(len(lat.bv))]
    seg_keys += [("r", i, j) for i in range(len(lat.bu)) for j in range(1, nv - 1)]
    for key in seg_keys:
        x = rng.random()
        states[key] = "plug" if x < p_plug else ("tight" if x < p_plug + p_tight else "roomy")
    obstacles: list[dict[str, Any]] = []
    for i in range(len(lat.bu)):
        for j in range(len(lat.bv)):
            d = _clip_box(
                lat, lat.uc0[i], lat.uc0[i] + lat.bu[i], lat.vr0[j], lat.vr0[j] + lat.bv[j]
            )
            if d is not None:
                obstacles.append(d)
    pts, edges = _lattice_graph(lat, states, margin=0.25)
    used = {("c", i, j) for i in range(nu) for j in range(len(lat.bv))} | {
        ("r", i, j) for i in range(len(lat.bu)) for j in range(nv)
    }
    for key in sorted(used):
        st = states.get(key, "roomy")
        if st == "roomy":
            continue
        box = _segment_box(lat, *key)
        if st == "plug":
            obstacles.extend(render_plug(box, key[0]))
        else:
            obstacles.extend(render_tight(box, key[0], tight_gap(rng, obj)))
    obstacles.extend(extra)
    n = len(pts)
    d_roomy = _graph_distances(n, [(a, b, w) for a, b, w, st in edges if st == "roomy"])
    d_all = _graph_distances(n, [(a, b, w) for a, b, w, st in edges if st in ("roomy", "tight")])
    # sites: intersections plus midpoints of roomy segments (distance via the end nodes)
    site_xy = [tuple(p) for p in pts]
    rows_r = [d_roomy[k] for k in range(n)]
    rows_a = [d_all[k] for k in range(n)]
    for a, b, w, st in edges:
        if st != "roomy":
            continue
        site_xy.append(tuple(0.5 * (pts[a] + pts[b])))
        rows_r.append(np.minimum(d_roomy[a], d_roomy[b]) + 0.5 * w)
        rows_a.append(np.minimum(d_all[a], d_all[b]) + 0.5 * w)
    m = len(site_xy)
    dr = np.full((m, m), np.inf)
    da = np.full((m, m), np.inf)
    rr = np.array(rows_r).reshape(m, n)
    ra = np.array(rows_a).reshape(m, n)
    # distance between two sites through graph nodes (exact for nodes, near for midpoints)
    for s in range(m):
        dr[s] = np.min(rr[s][None, :] + rr[:, :], axis=1) if n else dr[s]
        da[s] = np.min(ra[s][None, :] + ra[:, :], axis=1) if n else da[s]
    np.fill_diagonal(dr, 0.0)
    np.fill_diagonal(da, 0.0)
    heading = np.full((m, 1), lat.angle)
    sites = np.concatenate([np.array(site_xy).reshape(-1, 2), heading], axis=1)
    info = dict(info)
    info["tight_passages"] = sum(1 for v in states.values() if v == "tight")
    info["closed_passages"] = sum(1 for v in states.values() if v == "plug")
    return Layout(obstacles, sites, dr, da, info)


def _fill_widths(
    rng: np.random.Generator, total: float, block: tuple[float, float], street: Callable[[], float]
) -> tuple[np.ndarray, np.ndarray]:
    """Alternate streets and blocks until ``total`` is covered (street first and last)."""
    bs, ss = [], [street()]
    pos = ss[0]
    while pos < total:
        b = rng.uniform(*block)
        bs.append(b)
        s = street()
        ss.append(s)
        pos += b + s
    return np.array(bs), np.array(ss)


def layout_tilt(rng: np.random.Generator, obj: ObjectSpec, want_tight: bool) -> Layout:
    """Blocks on a lattice rotated by an oblique angle (a multiple of 11.25 degrees, so a
    rectangle can line up with the channels on the checks' heading lattice), clipped to
    the workspace; some channel segments closed, some narrowed to a tight channel as long
    as the block beside it."""
    W, H = WORKSPACE
    angle = math.radians(float(rng.choice([22.5, 33.75, 45.0, 56.25, 67.5]))) * float(
        rng.choice([-1.0, 1.0])
    )
    span = math.hypot(W, H) + 1.5

    def street() -> float:
        return street_width(rng, obj, 0.32, 0.42)

    bu, su = _fill_widths(rng, span, (0.35, 0.75), street)
    bv, sv = _fill_widths(rng, span, (0.35, 0.75), street)
    total_u = float(np.sum(bu) + np.sum(su))
    total_v = float(np.sum(bv) + np.sum(sv))
    shift = rng.uniform(-0.4, 0.4, size=2)
    c, s = math.cos(angle), math.sin(angle)
    off = np.array(
        [
            c * (-0.5 * total_u + shift[0]) - s * (-0.5 * total_v + shift[1]),
            s * (-0.5 * total_u + shift[0]) + c * (-0.5 * total_v + shift[1]),
        ]
    )
    lat = _Lattice(bu, su, bv, sv, np.array([W / 2, H / 2]) + off, angle)

    def plug(box: tuple[float, float, float, float], kind: str) -> list[dict[str, Any]]:
        u0, u1, v0, v1 = box
        d = _clip_box(lat, u0, u1, v0, v1, min_area=0.005)
        return [] if d is None else [d]

    def tight(
        box: tuple[float, float, float, float], kind: str, gap: float
    ) -> list[dict[str, Any]]:
        u0, u1, v0, v1 = box
        side = rng.random() < 0.5
        if kind == "c":  # narrow the column street across u
            u0, u1 = (u0, u1 - gap) if side else (u0 + gap, u1)
        else:
            v0, v1 = (v0, v1 - gap) if side else (v0 + gap, v1)
        if u1 - u0 <= 0.01 or v1 - v0 <= 0.01:
            return []
        d = _clip_box(lat, u0, u1, v0, v1, min_area=0.005)
        return [] if d is None else [d]

    p_plug, p_tight = (0.25, 0.25) if want_tight else (0.2, 0.15)
    return _lattice_layout(
        rng,
        lat,
        obj,
        p_plug,
        p_tight,
        plug,
        tight,
        [],
        {"angle_deg": round(math.degrees(angle), 2)},
    )


def layout_warehouse(rng: np.random.Generator, obj: ObjectSpec, want_tight: bool) -> Layout:
    """Shelf rows (long, shallow blocks) with aisles and cross-aisles sized for the
    object, a dock area along one wall, pallets and cargo (boxes, barrels) narrowing some
    aisles to tight passages, traffic barriers closing others, and cargo stacked against
    the walls. The whole layout is randomly mirrored/transposed."""
    W, H = WORKSPACE

    def aisle() -> float:
        return street_width(rng, obj, 0.30, 0.40)

    dock = max(aisle(), rng.uniform(0.7, 1.0))
    # rows of shelves above the dock (in the frame before transposing); a last row may
    # stand against the far wall
    bv_list, sv_list = [], [dock]
    pos = dock
    while True:
        depth = rng.uniform(0.35, 0.6)
        a = aisle()
        if pos + depth + a > H + 1e-9:
            break
        bv_list.append(depth)
        pos += depth
        sv_list.append(a)
        pos += a
    rest = H - pos
    if rest >= 0.3:
        depth = min(rest, rng.uniform(0.3, 0.5))
        bv_list.append(depth)
        sv_list[-1] += rest - depth
        sv_list.append(0.0)
    else:
        sv_list[-1] += rest
    # columns of shelf segments with cross-aisles; the first may leave an aisle along the
    # side wall, the last shelf reaches the other wall unless an aisle fits there
    bu_list, su_list = [], []
    first = aisle() if rng.random() < 0.6 else 0.0
    su_list.append(first)
    pos = first
    while True:
        pos += rng.uniform(0.8, 1.5)
        bu_list.append(pos - sum(bu_list) - sum(su_list))
        a = aisle()
        if W - pos < a + 0.4:  # no room for another shelf: this one reaches the wall
            bu_list[-1] += W - pos
            su_list.append(0.0)
            break
        if W - pos < a + 0.8:  # room for an aisle along the wall only
            su_list.append(W - pos)
            break
        su_list.append(a)
        pos += a
    lat = _Lattice(
        np.array(bu_list), np.array(su_list), np.array(bv_list), np.array(sv_list), np.zeros(2), 0.0
    )
    transpose = rng.random() < 0.5
    flip_x = rng.random() < 0.5
    flip_y = rng.random() < 0.5

    def plug(box: tuple[float, float, float, float], kind: str) -> list[dict[str, Any]]:
        u0, u1, v0, v1 = box
        if rng.random() < 0.5:  # traffic barrier across the aisle
            t = rng.uniform(0.05, 0.08)
            if kind == "c":
                vm = rng.uniform(v0 + t, v1 - t)
                return [rect(*lat.box(u0, u1, vm - t / 2, vm + t / 2))]
            um = rng.uniform(u0 + t, u1 - t)
            return [rect(*lat.box(um - t / 2, um + t / 2, v0, v1))]
        # a pallet stack filling the aisle
        if kind == "c":
            ln = min(v1 - v0, rng.uniform(0.35, 0.55))
            vm = rng.uniform(v0 + ln / 2, v1 - ln / 2)
            return [rect(*lat.box(u0, u1, vm - ln / 2, vm + ln / 2))]
        ln = min(u1 - u0, rng.uniform(0.35, 0.55))
        um = rng.uniform(u0 + ln / 2, u1 - ln / 2)
        return [rect(*lat.box(um - ln / 2, um + ln / 2, v0, v1))]

    def tight(
        box: tuple[float, float, float, float], kind: str, gap: float
    ) -> list[dict[str, Any]]:
        u0, u1, v0, v1 = box
        side = rng.random() < 0.5
        across = (u1 - u0) if kind == "c" else (v1 - v0)
        fill = across - gap
        if fill <= 0.02:
            return []
        along0, along1 = (v0, v1) if kind == "c" else (u0, u1)
        if rng.random() < 0.3 and 0.2 <= fill <= 0.6 and along1 - along0 >= fill:
            # a barrel (disk) against one side, its widest point leaving the gap
            r = fill / 2
            am = rng.uniform(along0 + r, along1 - r)
            if kind == "c":
                cu = u0 + r if side else u1 - r
                x, y = lat.world(cu, am)
            else:
                cv = v0 + r if side else v1 - r
                x, y = lat.world(am, cv)
            return [circle(x, y, r)]
        ln = min(along1 - along0, rng.uniform(0.3, 0.55))
        am = rng.uniform(along0 + ln / 2, along1 - ln / 2)
        if kind == "c":
            a0, a1 = (u0, u0 + fill) if side else (u1 - fill, u1)
            return [rect(*lat.box(a0, a1, am - ln / 2, am + ln / 2))]
        a0, a1 = (v0, v0 + fill) if side else (v1 - fill, v1)
        return [rect(*lat.box(am - ln / 2, am + ln / 2, a0, a1))]

    # cargo stacked against the dock wall (v = 0), away from the dock's middle
    extra: list[dict[str, Any]] = []
    n_cargo = int(rng.integers(2, 6))
    room = dock - (obj.width + 2 * END_CLEARANCE)
    for _ in range(n_cargo):
        if room < 0.2:
            break
        depth = rng.uniform(0.2, min(0.45, room))
        ln = rng.uniform(0.25, 0.5)
        um = rng.uniform(ln / 2, W - ln / 2)
        if rng.random() < 0.35:
            r = depth / 2
            x, y = lat.world(um, r)
            extra.append(circle(x, y, r))
        else:
            extra.append(rect(*lat.box(um - ln / 2, um + ln / 2, 0.0, depth)))
    p_plug, p_tight = (0.2, 0.3) if want_tight else (0.15, 0.15)
    layout = _lattice_layout(rng, lat, obj, p_plug, p_tight, plug, tight, extra, {})
    layout.obstacles = [_transform(d, transpose, flip_x, flip_y) for d in layout.obstacles]
    layout.sites = np.array(
        [_transform_pose(p, transpose, flip_x, flip_y) for p in layout.sites]
    ).reshape(-1, 3)
    layout.info.update({"shelf_rows": len(bv_list), "transposed": transpose})
    return layout


def _transform_pose(p: np.ndarray, transpose: bool, fx: bool, fy: bool) -> np.ndarray:
    W, H = WORKSPACE
    x, y, th = float(p[0]), float(p[1]), float(p[2])
    if transpose:
        x, y, th = y, x, 0.5 * math.pi - th
    if fx:
        x, th = W - x, math.pi - th
    if fy:
        y, th = H - y, -th
    return np.array([x, y, _wrap(th)])


def _transform(d: dict[str, Any], transpose: bool, fx: bool, fy: bool) -> dict[str, Any]:
    """Mirror/transpose an axis-aligned layout's obstacle (rectangles stay axis-aligned)."""
    if d["type"] == "polygon":
        pts = [
            _transform_pose(np.array([x, y, 0.0]), transpose, fx, fy)[:2] for x, y in d["points"]
        ]
        return polygon(np.array(pts))
    x, y, _ = _transform_pose(np.array([*d["center"], 0.0]), transpose, fx, fy)
    if d["type"] == "circle":
        return circle(x, y, d["radius"])
    sx, sy = d["size"]
    if transpose:
        sx, sy = sy, sx
    return rect(x, y, sx, sy, 0.0)


# --------------------------------------------------------------------------- scenes
@dataclass
class Generated:
    """A generated scene with its file dict, loaded Scene and check report."""

    family: str
    index: int
    scene_dict: dict[str, Any]
    scene: Scene
    report: C.ObjectReport
    attempts: int
    want_tight: bool
    layout_info: dict[str, Any]


def scene_name(family: str, index: int) -> str:
    return f"{family}-{index + 1:02d}"


def wants_tight(family: str, index: int) -> bool:
    """Scenes 0..24: in maze/tilt/warehouse, all but every fifth aim at a too-tight
    shortest route (TIGHT_SHARE = 0.8)."""
    return family != "random" and index % 5 != 4


def _sample_heading(rng: np.random.Generator, obj: ObjectSpec, preferred: float) -> float:
    if obj.is_circle:
        return 0.0
    if rng.random() < 0.5:
        return _wrap(preferred + 0.5 * math.pi * int(rng.integers(4)) + rng.uniform(-0.2, 0.2))
    return rng.uniform(-math.pi, math.pi)


def _place(
    rng: np.random.Generator,
    obj: ObjectSpec,
    world: C.World,
    site: np.ndarray,
    jitter: float,
    tries: int = 30,
) -> np.ndarray | None:
    """A pose near ``site`` with clearance >= END_CLEARANCE (None when none found)."""
    shape = shape_from_dict(obj.shape)
    for t in range(tries):
        j = jitter if t < tries - 5 else 0.0
        x = site[0] + rng.uniform(-j, j)
        y = site[1] + rng.uniform(-j, j)
        th = (
            _sample_heading(rng, obj, site[2])
            if t < tries - 3
            else _wrap(site[2] + 0.5 * math.pi * (t % 2))
        )
        pose = np.array([_r(x), _r(y), _r(th, 4)])
        if C.clearance(shape, world, pose) >= END_CLEARANCE:
            return pose
    return None


def _place_robots(
    rng: np.random.Generator, world: C.World, obj_shape: Any, start: np.ndarray, reach: float
) -> list[list[float]] | None:
    """Three robot positions 0.12-0.7 m outside the object's bounding circle, clear of
    everything by >= 3 cm and of each other by >= 5 cm."""
    obj_world = C.build_world(WORKSPACE, [Obstacle(obj_shape, tuple(float(v) for v in start))])
    out: list[np.ndarray] = []
    for _ in range(300):
        rad = reach + ROBOT_RADIUS + rng.uniform(0.12, 0.7)
        a = rng.uniform(-math.pi, math.pi)
        p = np.array([_r(start[0] + rad * math.cos(a)), _r(start[1] + rad * math.sin(a))])
        c = min(C.point_clearance(world, p), C.point_clearance(obj_world, p))
        if c < ROBOT_RADIUS + 0.03:
            continue
        if any(math.dist(p, q) < 2 * ROBOT_RADIUS + 0.05 for q in out):
            continue
        out.append(p)
        if len(out) == N_ROBOTS:
            return [[float(v) for v in q] for q in out]
    return None


def _pick_pair(
    rng: np.random.Generator, layout: Layout, want_tight: bool
) -> tuple[int, int] | None:
    sites = layout.sites
    eu = np.hypot(sites[:, None, 0] - sites[None, :, 0], sites[:, None, 1] - sites[None, :, 1])
    dr, da = layout.d_roomy, layout.d_all
    finite = np.isfinite(dr)
    if want_tight:
        ok = finite & (eu >= 1.0) & (dr >= da + 0.8) & (dr >= 1.35 * da)
    else:
        ok = finite & (eu >= 1.8)
    cand = np.argwhere(ok)
    if len(cand) == 0:
        return None
    # prefer far-apart pairs (probability grows with the squared distance)
    w = eu[cand[:, 0], cand[:, 1]] ** 2
    a, b = cand[int(rng.choice(len(cand), p=w / w.sum()))]
    return int(a), int(b)


LAYOUTS: dict[str, Callable[..., Layout]] = {
    "maze": layout_maze,
    "tilt": layout_tilt,
    "warehouse": layout_warehouse,
}


def generate_scene(family: str, index: int, *, full_checks: bool = True) -> Generated:
    """Generate scene ``index`` (0-based) of ``family``; deterministic in (family, index).

    ``full_checks=False`` skips the clearance-ladder routes and robot reachability of the
    accepted attempt (used by tests that only compare the scene dict).
    """
    if family not in FAMILIES:
        raise ValueError(f"family must be one of {', '.join(FAMILIES)}; got {family!r}")
    if not (isinstance(index, int) and 0 <= index < SCENES_PER_FAMILY):
        raise ValueError(f"index must be an int in [0, {SCENES_PER_FAMILY}), got {index!r}")
    rng = np.random.default_rng([SUITE_SEED, FAMILIES.index(family), index])
    want_tight = wants_tight(family, index)
    obj = sample_object(rng, index)
    shape = shape_from_dict(obj.shape)
    name = scene_name(family, index)
    rejected: dict[str, int] = {}

    def reject(why: str) -> None:
        rejected[why] = rejected.get(why, 0) + 1

    for attempt in range(1, MAX_ATTEMPTS + 1):
        layout = (
            layout_random(rng, obj) if family == "random" else LAYOUTS[family](rng, obj, want_tight)
        )
        pair = _pick_pair(rng, layout, want_tight)
        if pair is None:
            reject("no site pair")
            continue
        world = C.build_world(WORKSPACE, _obstacles_of(layout.obstacles))
        start = _place(rng, obj, world, layout.sites[pair[0]], jitter=0.12)
        goal = _place(rng, obj, world, layout.sites[pair[1]], jitter=0.12)
        if start is None or goal is None:
            reject("no start/goal pose")
            continue
        if obj.is_circle:
            start[2] = goal[2] = 0.0
        robots = _place_robots(rng, world, shape, start, obj.reach)
        if robots is None:
            reject("no robot starts")
            continue
        d = {
            "format": "lamp-scene/1",
            "name": name,
            "workspace": [WORKSPACE[0], WORKSPACE[1]],
            "robots": {"radius": ROBOT_RADIUS, "starts": robots},
            "obstacles": layout.obstacles,
            "objects": [
                {**obj.shape, "start": [float(v) for v in start], "goal": [float(v) for v in goal]}
            ],
        }
        try:
            scene = scene_from_dict(d, source=name)
        except SceneError:
            reject("invalid scene")
            continue
        finder = C.RouteFinder(shape, C.object_world(scene, 0))
        free = finder.find(start, goal, C.FREE_CLEARANCE)
        if free is None:
            reject("no free route")
            continue
        roomy = finder.find(start, goal, C.ROBOT_ROOM)
        if roomy is None:
            reject("no robot-room route")
            continue
        if want_tight and not C.is_tight(free, roomy):
            reject("shortest route not too tight")
            continue
        reach = C.robot_reach(scene, 0)
        if not reach.all_reach or reach.ring_fraction < 0.5:
            reject("robots cannot reach the object")
            continue
        known = {C.FREE_CLEARANCE: free, C.ROBOT_ROOM: roomy}
        if full_checks:
            report = C.check_object(scene, 0, finder=finder, known=known)
        else:
            report = C.ObjectReport(0, 0.0, 0.0, free, roomy, {}, reach)
        return Generated(family, index, d, scene, report, attempt, want_tight, layout.info)
    raise RuntimeError(
        f"{name}: no valid scene after {MAX_ATTEMPTS} attempts (rejected: {rejected})"
    )
