"""The ``iros`` suite: 9 objects moved one by one to spell I R O S.

The LAMP paper's long-horizon case study.

A warehouse-like hall (5 m x 4 m): shelves along the walls, a storage yard where the
objects wait in two rows, traffic barriers and cargo at the sides, and an assembly floor
below the letter band. At their goals the objects form

* **I**: one upright bar;
* **R**: an upright stem, a disk as the bowl beside its top, a slanted bar as the leg;
* **O**: one large disk;
* **S**: a top bar, an upper-left post, a lower-right post and a bottom bar.

Pieces of one letter stand a few centimetres apart, so the last part of each placement
is a push from below: every piece has an *approach* pose ``APPROACH`` metres below its
goal; the route to the approach pose keeps robot room (``checks.ROBOT_ROOM``) and the
final straight push keeps ``checks.FREE_CLEARANCE``. The order (letters left to right,
each letter top to bottom, the front row of the yard emptied first) makes sure that no
placement blocks a later one; ``check_sequence`` verifies it with objects ``0..k-1`` at
their goals and ``k+1..`` at their starts as obstacles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lamp.scene.loader import scene_from_dict
from lamp.scene.model import Circle, Obstacle, Scene
from lamp.suites import checks as C
from lamp.suites import kernels as K
from lamp.suites.layout import circle, rect, rnd

WORKSPACE = (5.0, 4.0)
#: distance (m) below the goal from which each piece is pushed straight into place
APPROACH = 0.35
LETTER_Y = 3.05  # centre line of the letters

# (name, shape dict, goal (x, y, theta), approach direction): rectangles with sides in
# [0.15, 0.50] m and disks of radius [0.10, 0.30] m as in the families; letter origins
# (left edge, centre line) chosen so the word is centred. The approach direction points
# from the goal to the approach pose: the side the robots push from.
_I_X, _R_X, _O_X, _S_X = 1.225, 1.675, 2.475, 3.325
_UP = (0.0, -1.0)
PIECES: list[tuple[str, dict[str, Any], tuple[float, float, float], tuple[float, float]]] = [
    ("I", {"type": "rectangle", "size": [0.15, 0.50]}, (_I_X + 0.075, LETTER_Y, 0.0), _UP),
    ("R-stem", {"type": "rectangle", "size": [0.15, 0.50]}, (_R_X + 0.075, LETTER_Y, 0.0), _UP),
    ("R-bowl", {"type": "circle", "radius": 0.13}, (_R_X + 0.32, LETTER_Y + 0.12, 0.0), (1.0, 0.0)),
    (
        "R-leg",
        {"type": "rectangle", "size": [0.15, 0.22]},
        (_R_X + 0.365, LETTER_Y - 0.18, 0.7854),
        (0.6, -0.8),
    ),
    ("O", {"type": "circle", "radius": 0.27}, (_O_X + 0.27, LETTER_Y, 0.0), _UP),
    (
        "S-top",
        {"type": "rectangle", "size": [0.45, 0.15]},
        (_S_X + 0.225, LETTER_Y + 0.225, 0.0),
        _UP,
    ),
    (
        "S-upper",
        {"type": "rectangle", "size": [0.15, 0.15]},
        (_S_X + 0.075, LETTER_Y + 0.035, 0.0),
        _UP,
    ),
    (
        "S-lower",
        {"type": "rectangle", "size": [0.15, 0.15]},
        (_S_X + 0.375, LETTER_Y - 0.035, 0.0),
        _UP,
    ),
    (
        "S-bottom",
        {"type": "rectangle", "size": [0.45, 0.15]},
        (_S_X + 0.225, LETTER_Y - 0.225, 0.0),
        _UP,
    ),
]

# start poses in the yard: the front row (y = 1.65) is emptied first
STARTS: list[tuple[float, float, float]] = [
    (0.95, 1.65, 1.5708),  # I, lying across
    (1.85, 1.65, 0.3),  # R-stem
    (2.75, 1.65, 0.0),  # R-bowl
    (3.65, 1.65, -0.4),  # R-leg
    (0.95, 0.75, 0.0),  # O
    (1.85, 0.75, 0.5),  # S-top
    (2.75, 0.75, 1.2),  # S-upper
    (3.65, 0.75, -0.9),  # S-lower
    (4.35, 1.2, 1.5708),  # S-bottom
]

ROBOT_STARTS = [[0.3, 2.45], [0.3, 2.25], [0.5, 2.35]]


def _obstacles() -> list[dict[str, Any]]:
    W, H = WORKSPACE
    return [
        # shelves along the bottom and side walls
        rect(1.5, 0.15, 1.6, 0.3),
        rect(3.55, 0.15, 1.5, 0.3),
        rect(0.15, 1.1, 0.3, 1.2),
        rect(4.85, 2.0, 0.3, 1.0),
        # traffic barriers between the yard and the assembly floor, leaving wide gates
        rect(0.65, 2.1, 0.7, 0.06),
        rect(4.45, 2.2, 0.06, 0.6),
        # pallets and stationary cargo at the edges of the assembly floor
        rect(4.65, 3.6, 0.5, 0.5),
        circle(0.25, 3.75, 0.15),
        circle(4.75, 0.55, 0.16),
        rect(2.3, 3.8, 0.6, 0.3),
        # small pallets between the yard's columns
        rect(1.4, 1.2, 0.2, 0.2),
        rect(2.3, 1.2, 0.2, 0.2, 0.3),
        circle(3.2, 1.2, 0.1),
        rect(4.1, 0.45, 0.25, 0.25),
    ]


def scene_dict() -> dict[str, Any]:
    """The ``iros-01`` scene file dict."""
    objects = []
    for (_, shape, goal, _), start in zip(PIECES, STARTS, strict=True):
        objects.append(
            {
                **shape,
                "start": [rnd(start[0]), rnd(start[1]), rnd(start[2], 4)],
                "goal": [rnd(goal[0]), rnd(goal[1]), rnd(goal[2], 4)],
            }
        )
    return {
        "format": "lamp-scene/1",
        "name": "iros-01",
        "workspace": [WORKSPACE[0], WORKSPACE[1]],
        "robots": {"radius": 0.05, "starts": ROBOT_STARTS},
        "obstacles": _obstacles(),
        "objects": objects,
    }


def approach_pose(k: int) -> np.ndarray:
    """The pose ``APPROACH`` m from piece k's goal along its approach direction."""
    _, _, goal, (ux, uy) = PIECES[k]
    return np.array([goal[0] + APPROACH * ux, goal[1] + APPROACH * uy, goal[2]])


@dataclass
class StepReport:
    """Checks for placing object k (objects < k at goals, > k at starts)."""

    index: int
    piece: str
    free_route: C.Route | None
    approach_route: C.Route | None
    final_push_ok: bool
    reach: C.RobotReach
    robots_leave: bool

    @property
    def ok(self) -> bool:
        return (
            self.free_route is not None
            and self.approach_route is not None
            and self.final_push_ok
            and self.reach.all_reach
            and self.robots_leave
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "index": self.index,
            "piece": self.piece,
            "free_route": None if self.free_route is None else self.free_route.to_dict(),
            "approach_route": None
            if self.approach_route is None
            else self.approach_route.to_dict(),
            "approach_pose": [round(float(v), 4) for v in approach_pose(self.index)],
            "final_push_ok": self.final_push_ok,
            "robots": self.reach.to_dict(),
            "robots_can_leave": self.robots_leave,
        }


def state_poses(scene: Scene, k: int) -> np.ndarray:
    """Object poses while object k is moved: 0..k-1 at goals, k.. at starts."""
    poses = scene.object_starts().copy()
    poses[:k] = scene.object_goals()[:k]
    return poses


def check_sequence(scene: Scene) -> list[StepReport]:
    """Check every placement of the sequence (see the module docstring)."""
    out = []
    r = scene.robot_radius
    for k, obj in enumerate(scene.objects):
        poses = state_poses(scene, k)
        world = C.object_world(scene, k, poses)
        finder = C.RouteFinder(obj.shape, world)
        free = finder.find(obj.start, obj.goal, C.FREE_CLEARANCE)
        app = approach_pose(k)
        roomy = finder.find(obj.start, app, C.ROBOT_ROOM)
        fp = C.footprint_of(obj.shape)
        ends = np.ascontiguousarray(np.array([app, obj.goal], dtype=float))
        ca, cg = K.batch_clearance(ends, *fp.args, *world.args)
        push_ok = bool(
            K.motion_ok(
                ends[0], ends[1], ca, cg, C.FREE_CLEARANCE, C.MAX_DEPTH, *fp.args, *world.args
            )
        )
        reach = C.robot_reach(scene, k, poses)
        # after the push the robots stand on the approach side of the placed piece; they
        # must be able to get back to the depot (the robot starts) with 0..k at their goals
        after = state_poses(scene, k + 1)
        ux, uy = PIECES[k][3]
        ext = _extent_along(obj.shape, obj.goal[2], (ux, uy))
        behind = np.array(
            [obj.goal[0] + (ext + r + 0.03) * ux, obj.goal[1] + (ext + r + 0.03) * uy]
        )
        robots_leave = _same_component(scene, after, behind)
        out.append(StepReport(k, PIECES[k][0], free, roomy, push_ok, reach, robots_leave))
    return out


def _extent_along(shape: Any, theta: float, u: tuple[float, float]) -> float:
    """Support distance of the shape at heading theta in the direction u."""
    if isinstance(shape, Circle):
        return float(shape.radius)
    sx, sy = shape.size
    c, s = math.cos(theta), math.sin(theta)
    # half extents along the body axes projected on u
    return 0.5 * (sx * abs(c * u[0] + s * u[1]) + sy * abs(-s * u[0] + c * u[1]))


def _same_component(scene: Scene, poses: np.ndarray, point: np.ndarray, h: float = 0.02) -> bool:
    """Is ``point`` in the robots' free-space component of the robot starts (objects at
    ``poses``)? On the grid of ``checks.robot_free_cells``, as ``checks.robot_reach``."""
    from scipy import ndimage

    _, _, _, free = C.robot_free_cells(scene, poses, h)
    ny, nx = free.shape
    labels, _ = ndimage.label(free)

    def label_of(p: np.ndarray) -> int:
        i = int(np.clip(round(p[0] / h - 0.5), 0, nx - 1))
        j = int(np.clip(round(p[1] / h - 0.5), 0, ny - 1))
        return int(labels[j, i])

    depot = {label_of(p) for p in scene.robot_starts_array} - {0}
    return label_of(point) in depot


def build() -> tuple[dict[str, Any], Scene, list[StepReport]]:
    d = scene_dict()
    scene = scene_from_dict(d, source="iros-01")
    return d, scene, check_sequence(scene)


def goal_footprints_disjoint(scene: Scene, min_gap: float = 0.03) -> bool:
    """Every two goal footprints are at least ``min_gap`` apart (exact distances)."""
    for i, a in enumerate(scene.objects):
        others = [Obstacle(b.shape, b.goal) for j, b in enumerate(scene.objects) if j != i]
        world = C.build_world(
            (1e3, 1e3),
            [Obstacle(o.shape, (o.pose[0] + 500, o.pose[1] + 500, o.pose[2])) for o in others],
        )
        g = np.array([a.goal[0] + 500, a.goal[1] + 500, a.goal[2]])
        if C.clearance(a.shape, world, g) < min_gap:
            return False
    return True
