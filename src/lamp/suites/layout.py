"""Shared pieces of the benchmark map generators: suite constants, obstacle dicts, the
object sampler, passage widths and the ``Layout`` a family generator returns."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import shortest_path

from lamp.geometry.team import DEFAULT_TEAM
from lamp.scene.model import Obstacle, shape_from_dict

FAMILIES = ("random", "maze", "tilt", "warehouse")
SCENES_PER_FAMILY = 25
#: base seed; scene k of family f uses ``np.random.default_rng([SUITE_SEED, f, k])``
SUITE_SEED = 20260
WORKSPACE = (4.0, 4.0)
N_ROBOTS = 3
ROBOT_RADIUS = DEFAULT_TEAM.radius
#: share of maze/tilt/warehouse scenes whose start and goal are chosen for a too-tight
#: shortest route (the others pick any far-apart pair; decoy tight passages remain)
TIGHT_SHARE = 0.8
#: clearance (m) of the object at its start and goal: robots fit all around it
END_CLEARANCE = 0.16
#: tight passages are wider than the object by this much (total, both sides)
TIGHT_SLACK = (0.07, 0.10)
MAX_ATTEMPTS = 60


def rnd(v: float, nd: int = 3) -> float:
    """Round for the scene file (mm positions/sizes, 1e-4 rad angles); no negative zero."""
    out = round(float(v), nd)
    return 0.0 if out == 0.0 else out


def wrap_angle(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def rect(cx: float, cy: float, sx: float, sy: float, angle: float = 0.0) -> dict[str, Any]:
    """Rectangle obstacle dict (rounded). Axis-aligned ones are rounded through their
    bounds (to mm), so that a rectangle meant to touch the border stays inside it."""
    if angle == 0.0:
        x0, x1 = rnd(cx - 0.5 * sx), rnd(cx + 0.5 * sx)
        y0, y1 = rnd(cy - 0.5 * sy), rnd(cy + 0.5 * sy)
        return {
            "type": "rectangle",
            "center": [rnd(0.5 * (x0 + x1), 4), rnd(0.5 * (y0 + y1), 4)],
            "size": [rnd(x1 - x0), rnd(y1 - y0)],
            "angle": 0.0,
        }
    return {
        "type": "rectangle",
        "center": [rnd(cx), rnd(cy)],
        "size": [rnd(sx), rnd(sy)],
        "angle": rnd(wrap_angle(angle) if angle else 0.0, 4),
    }


def circle(cx: float, cy: float, r: float) -> dict[str, Any]:
    return {"type": "circle", "center": [rnd(cx), rnd(cy)], "radius": rnd(r)}


def polygon(points: np.ndarray) -> dict[str, Any]:
    return {"type": "polygon", "points": [[rnd(x), rnd(y)] for x, y in points]}


def obstacles_of(dicts: list[dict[str, Any]]) -> list[Obstacle]:
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
        r = rnd(rng.uniform(0.10, 0.30))
        return ObjectSpec({"type": "circle", "radius": r}, 2 * r, 2 * r, r)
    a, b = (rnd(v) for v in rng.uniform(0.15, 0.50, size=2))
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


def graph_distances(n: int, edges: list[tuple[int, int, float]]) -> np.ndarray:
    if not edges:
        d = np.full((n, n), np.inf)
        np.fill_diagonal(d, 0.0)
        return d
    i, j, w = (np.array(v) for v in zip(*edges, strict=True))
    m = coo_matrix((w, (i, j)), shape=(n, n)).tocsr()
    return shortest_path(m, directed=False)
