"""The ``corridor`` family: one load through a corridor barely wider than the load.

Each scene is a map of ``SIDE_RANGE`` metres a side holding a single corridor from a
start room to a goal room (``lamp.suites.corridor_layout``). The corridor has 1-4 turns
of 30-120 degrees; its legs (1.5-4 m of narrow corridor each) run at arbitrary absolute
angles, every one at least ``MIN_BIN_OFFSET`` away from the axes and from every multiple
of 22.5 degrees (the heading bins of a 16-heading lattice), and every centreline vertex
is at least ``MIN_GRID_OFFSET`` off the 0.1 m grid in x and y. The corridor is as wide
as the object's extent across it plus a clearance drawn in ``CLEARANCE_RANGE`` (both
sides together), and at least a robot wide (``checks.ROBOT_ROOM``). The object keeps its
long axis along the corridor, so it has to rotate at every turn: each turn has a bay of
diameter at least the object's diagonal + 4 robot radii + ``BAY_MARGIN`` (larger at
sharp turns, to leave ``WALL_NEAR`` of wall between the legs). The walls fill the rest
of the workspace as simple polygons on the scene files' millimetre grid; snapping them
there leaves each wall 0.1-1.5 mm farther out than drawn, never nearer.

Objects, by index ``k``: ``k % 4 == 0`` a bar 1.0-1.5 m long and 0.15-0.30 m wide
(a polygon for even ``k // 4``, a rectangle otherwise; 7 of the 25 scenes), ``k % 4 ==
2`` a circle of radius 0.10-0.25 m, otherwise a rectangle with sides 0.15-0.50 m. The
object starts in the start room and ends in the goal room, each time turned 25-90
degrees from the leg's direction (rectangles and bars); 3 robots of radius 0.05 m start
in the start room behind it (within ``ROBOT_SECTOR`` of the direction away from the
corridor's mouth), where they can push it in: inside the corridor no robot can pass it.

Checks (the guarantee that every scene is feasible for the object): the generator knows
a *witness* route: rotate in place to the first leg's heading, slide onto the leg's
centreline, follow it to the first bay's centre, rotate to the next leg's heading, ...,
slide to the goal and rotate to its heading. The witness is sampled every
``WITNESS_STEP`` m and ``WITNESS_ROT_STEP`` rad; every sample has exact clearance (the
suite kernels, zero inflation) >= ``WITNESS_MIN_CLEARANCE``, and every motion between two
samples is certified to keep it (``kernels.motion_ok``, bisection on the Lipschitz
bound). Every robot reaches the object's contact ring (``checks.robot_reach`` on a
``REACH_RESOLUTION`` grid). An attempt that fails any check is redrawn.

Every scene is a pure function of its index: ``np.random.default_rng([SUITE_SEED,
STREAM, index])``, with rejected attempts drawn from the same stream.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lamp.scene.model import Scene, shape_from_dict
from lamp.suites import checks as C
from lamp.suites import corridor_layout as CL
from lamp.suites import kernels as K
from lamp.suites.generators import parse_scene, place_robots, scene_dict
from lamp.suites.layout import (
    ROBOT_RADIUS,
    SUITE_SEED,
    obstacles_of,
    polygon,
    rnd,
    wrap_angle,
)

NAME = "corridor"
N_SCENES = 25
#: the family's random stream (the paper's families use 0-3, warehouse-xl 10)
STREAM = 11
#: each side of the map (m)
SIDE_RANGE = (6.0, 14.0)
#: number of turns, and the range of each turn's magnitude (rad)
TURNS_RANGE = (1, 4)
TURN_RANGE = (math.radians(30.0), math.radians(120.0))
#: narrow length of each leg (m)
LEG_RANGE = (1.5, 4.0)
#: corridor width minus the object's extent across it (m, both sides together)
CLEARANCE_RANGE = (0.02, 0.06)
#: a bay's diameter is at least the object's diagonal + 4 robot radii + this (m)
BAY_MARGIN = 0.15
#: legs stay this far (rad) from every multiple of HEADING_BIN (22.5 degrees)
HEADING_BIN = math.pi / 8
MIN_BIN_OFFSET = math.radians(3.0)
#: centreline vertices stay this far (m) from the GRID lines in x and y
GRID = 0.1
MIN_GRID_OFFSET = 0.005
#: wall (m) between the legs on either side of a bay, and between farther pieces
WALL_NEAR = 0.1
WALL_FAR = 0.3
#: wall (m) between the free region and the workspace border, at least
BORDER_MIN = 0.3
#: heading of the object at start / goal, relative to its leg (rad)
END_TURN_RANGE = (math.radians(25.0), math.radians(90.0))
#: robots start within this angle (rad) of the direction away from the corridor
ROBOT_SECTOR = math.radians(60.0)
#: witness sampling (m of translation, rad of rotation) and the clearance it keeps (m)
WITNESS_STEP = 0.01
WITNESS_ROT_STEP = 0.01
WITNESS_MIN_CLEARANCE = 0.005
#: robot reachability grid (m) and width of the contact ring (m) the robots must reach
REACH_RESOLUTION = 0.025
REACH_RING_WIDTH = 0.06
MAX_ATTEMPTS = 20
#: layout draws per attempt (geometry only: fitting the map, not running into itself)
MAX_DRAWS = 400


def scene_name(index: int) -> str:
    return f"{NAME}-{index + 1:02d}"


# --------------------------------------------------------------------------- objects
@dataclass(frozen=True)
class CorridorObject:
    """The scene's object: file dict, extent across the corridor and along it, bounding
    radius, the angle (object frame) of the axis kept along the corridor, and the
    rotation period of its footprint (0: a disk)."""

    shape: dict[str, Any]
    kind: str
    across: float
    along: float
    reach: float
    axis: float
    period: float

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        if not 0.0 < self.across <= self.along <= 2.0 * self.reach + 1e-9:
            raise ValueError(
                f"need 0 < across <= along <= 2 reach, got across={self.across!r}, "
                f"along={self.along!r}, reach={self.reach!r}"
            )
        if self.period not in (0.0, math.pi):
            raise ValueError(f"period must be 0 or pi, got {self.period!r}")

    @property
    def rotate_radius(self) -> float:
        """Radius of the disk the object rotates in with robots around it."""
        return self.reach + 2.0 * ROBOT_RADIUS + 0.5 * BAY_MARGIN


#: the object kinds, and the kind of scene ``k``: ``KIND_CYCLE[k % 4]``
KINDS = ("bar", "rectangle", "circle")
KIND_CYCLE = ("bar", "rectangle", "circle", "rectangle")


def object_kind(index: int) -> str:
    return KIND_CYCLE[index % len(KIND_CYCLE)]


def sample_object(rng: np.random.Generator, index: int) -> CorridorObject:
    """The object of scene ``index`` (see the module docstring)."""
    kind = object_kind(index)
    if kind == "circle":
        r = rnd(rng.uniform(0.10, 0.25))
        return CorridorObject({"type": "circle", "radius": r}, kind, 2 * r, 2 * r, r, 0.0, 0.0)
    if kind == "bar":
        ln, w = rnd(rng.uniform(1.0, 1.5)), rnd(rng.uniform(0.15, 0.30))
        if (index // 4) % 2 == 0:
            hx, hy = 0.5 * ln, 0.5 * w
            shape = {"type": "polygon",
                     "points": [[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]]}
        else:
            shape = {"type": "rectangle", "size": [ln, w]}
        return CorridorObject(shape, kind, w, ln, 0.5 * math.hypot(ln, w), 0.0, math.pi)
    a, b = (rnd(v) for v in rng.uniform(0.15, 0.50, size=2))
    axis = 0.0 if a >= b else 0.5 * math.pi
    return CorridorObject({"type": "rectangle", "size": [a, b]}, kind, min(a, b), max(a, b),
                          0.5 * math.hypot(a, b), axis, math.pi)


# --------------------------------------------------------------------------- layout
@dataclass(frozen=True)
class CorridorLayout:
    """A generated map: workspace, centreline, corridor width and clearance, rooms, the
    wall obstacle dicts, and the object's start / goal positions (x, y)."""

    workspace: tuple[float, float]
    chain: CL.Chain
    width: float
    clearance: float
    rooms: CL.Rooms
    obstacles: list[dict[str, Any]]
    start_xy: np.ndarray
    goal_xy: np.ndarray
    #: distance of the start / goal behind / past the mouth (along the leg)
    start_depth: float
    goal_depth: float
    draws: int

    def info(self, obj: CorridorObject) -> dict[str, Any]:
        return {
            "workspace": list(self.workspace),
            "turns": len(self.chain.radii),
            "clearance": round(self.clearance, 4),
            "object_across": obj.across,
            "object_along": obj.along,
            "object_kind": obj.kind,
            "draws": self.draws,
            **CL.layout_summary(self.chain, self.width, self.rooms),
        }


def _off_bin_angle(rng: np.random.Generator, base: float | None) -> float | None:
    """A leg angle at least MIN_BIN_OFFSET from every heading bin: uniform when ``base``
    is None, else ``base`` turned by a TURN_RANGE angle either way (None: no luck)."""
    for _ in range(100):
        if base is None:
            a = rng.uniform(-math.pi, math.pi)
        else:
            a = base + (1.0 if rng.random() < 0.5 else -1.0) * rng.uniform(*TURN_RANGE)
        if CL.angle_bin_offset(a, HEADING_BIN) >= MIN_BIN_OFFSET:
            return a
    return None


def _up(v: float) -> float:
    """``v`` rounded up to the centimetre (a map side)."""
    return round(math.ceil(v * 100.0) / 100.0, 2)


def _draw(rng: np.random.Generator, obj: CorridorObject, n: int, width: float,
          clearance: float, draws: int) -> CorridorLayout | None:
    angles: list[float] = []
    for _ in range(n + 1):
        a = _off_bin_angle(rng, angles[-1] if angles else None)
        if a is None:
            return None
        angles.append(a)
    lengths = [float(v) for v in rng.uniform(*LEG_RANGE, size=n + 1)]
    rr = obj.rotate_radius
    radii = [CL.bay_radius(rr, width, b - a, WALL_NEAR)
             for a, b in zip(angles[:-1], angles[1:], strict=True)]
    chain = CL.chain_from(angles, lengths, radii)
    s, o = rr + rng.uniform(0.05, 0.3), rng.uniform(-0.25, 0.25)
    g, og = rr + rng.uniform(0.05, 0.3), rng.uniform(-0.25, 0.25)
    behind = s + rr + 2.0 * ROBOT_RADIUS + rng.uniform(0.3, 0.6)
    side = rng.uniform(0.1, 0.5, size=4)
    rooms = CL.Rooms(
        (-behind, 0.0), (min(o, 0.0) - rr - side[0], max(o, 0.0) + rr + side[1]),
        (0.0, g + rr + rng.uniform(0.1, 0.5)), (min(og, 0.0) - rr - side[2],
                                                max(og, 0.0) + rr + side[3]),
    )
    free = CL.free_region(chain, width, rooms)
    x0, y0, x1, y1 = free.bounds
    wx = _up(max(x1 - x0 + 2 * BORDER_MIN, rng.uniform(SIDE_RANGE[0], SIDE_RANGE[0] + 1.5)))
    wy = _up(max(y1 - y0 + 2 * BORDER_MIN, rng.uniform(SIDE_RANGE[0], SIDE_RANGE[0] + 1.5)))
    if wx > SIDE_RANGE[1] or wy > SIDE_RANGE[1]:
        return None
    if not CL.separated(CL.free_pieces(chain, width, rooms), WALL_NEAR - 1e-3, WALL_FAR):
        return None
    for _ in range(50):
        shift = np.array([
            BORDER_MIN - x0 + rng.uniform(0.0, wx - (x1 - x0) - 2 * BORDER_MIN),
            BORDER_MIN - y0 + rng.uniform(0.0, wy - (y1 - y0) - 2 * BORDER_MIN),
        ])
        v = chain.vertices + shift
        if all(CL.grid_offset(float(c), GRID) >= MIN_GRID_OFFSET for c in v.ravel()):
            break
    else:
        return None
    chain = chain.shifted(shift)
    free = CL.free_region(chain, width, rooms)
    walls = CL.wall_polygons((wx, wy), free)
    v = chain.vertices
    e0, e1 = CL.unit(angles[0]), CL.unit(angles[-1])
    n0, n1 = CL.unit(angles[0] + 0.5 * math.pi), CL.unit(angles[-1] + 0.5 * math.pi)
    start_xy = np.array([rnd(c) for c in v[0] - s * e0 + o * n0])
    goal_xy = np.array([rnd(c) for c in v[-1] + g * e1 + og * n1])
    return CorridorLayout((wx, wy), chain, width, clearance, rooms,
                          [polygon(p) for p in walls], start_xy, goal_xy, s, g, draws)


def layout_corridor(rng: np.random.Generator, obj: CorridorObject) -> CorridorLayout | None:
    """Draw a corridor map for ``obj`` (None when ``MAX_DRAWS`` draws do not fit). The
    number of turns and the clearance are drawn once, then the geometry until it fits."""
    n = int(rng.integers(TURNS_RANGE[0], TURNS_RANGE[1] + 1))
    clearance = float(rng.uniform(*CLEARANCE_RANGE))
    width = max(obj.across + clearance, C.ROBOT_ROOM)
    for k in range(1, MAX_DRAWS + 1):
        lay = _draw(rng, obj, n, width, clearance, k)
        if lay is not None:
            return lay
    return None


# --------------------------------------------------------------------------- witness
def _unwrap(theta: float, ref: float, period: float) -> float:
    return theta if period == 0.0 else theta + period * round((ref - theta) / period)


def witness_poses(lay: CorridorLayout, obj: CorridorObject, start: np.ndarray,
                  goal: np.ndarray) -> np.ndarray:
    """The witness route's poses (straight SE(2) motions between them, theta unwrapped):
    start, turned to leg 0, on the centreline, each bay's centre before and after
    turning, on the last leg's centreline in the goal room, beside the goal, the goal
    (the goal's heading up to the footprint's period). The poses between the start and
    the goal are rounded to 0.1 mm / 1e-4 rad."""
    ch = lay.chain
    v = ch.vertices
    heads = [a - obj.axis for a in ch.angles]

    def turned(theta: float, ref: float) -> float:
        return 0.0 if obj.period == 0.0 else _unwrap(theta, ref, obj.period)

    th = turned(heads[0], float(start[2]))
    out = [start, [start[0], start[1], th]]
    out.append([*(v[0] - lay.start_depth * CL.unit(ch.angles[0])), th])
    for k in range(1, len(ch.angles)):
        out.append([*v[k], th])
        th = turned(heads[k], th)
        out.append([*v[k], th])
    out.append([*(v[-1] + lay.goal_depth * CL.unit(ch.angles[-1])), th])
    out.append([goal[0], goal[1], th])
    end = turned(float(goal[2]), th)
    out.append([goal[0], goal[1], end])
    arr = np.round(np.array(out, dtype=float), 4)
    arr[0], arr[-1] = start, (goal[0], goal[1], end)
    return arr


def sample_witness(poses: np.ndarray, step: float = WITNESS_STEP,
                   rot_step: float = WITNESS_ROT_STEP) -> np.ndarray:
    """The poses of the witness every ``step`` m of translation and ``rot_step`` rad of
    rotation (both ends of every motion included)."""
    out = [poses[:1]]
    for a, b in zip(poses[:-1], poses[1:], strict=True):
        n = max(1, math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) / step - 1e-9),
                math.ceil(abs(b[2] - a[2]) / rot_step - 1e-9))
        out.append(a + (np.arange(1, n + 1) / n)[:, None] * (b - a))
    return np.concatenate(out)


@dataclass(frozen=True)
class Witness:
    """A certified witness route: every motion between its ``samples`` keeps exact
    clearance >= ``tau``; ``min_clearance`` is the least clearance of a sample."""

    poses: np.ndarray
    tau: float
    length: float
    rotation: float
    min_clearance: float
    samples: int

    def __post_init__(self) -> None:
        if self.poses.ndim != 2 or self.poses.shape[1] != 3 or len(self.poses) < 2:
            raise ValueError(f"poses must have shape (n >= 2, 3), got {self.poses.shape}")
        if not self.min_clearance >= self.tau:
            raise ValueError(
                f"min_clearance {self.min_clearance!r} is below the required {self.tau!r}"
            )

    def to_dict(self) -> dict[str, Any]:
        return {
            "required_clearance": self.tau,
            "length": round(self.length, 4),
            "rotation": round(self.rotation, 4),
            "min_clearance": round(self.min_clearance, 4),
            "samples": self.samples,
            "poses": self.poses.tolist(),
        }


def certify_witness(scene: Scene, poses: np.ndarray,
                    tau: float = WITNESS_MIN_CLEARANCE) -> Witness | None:
    """The witness through ``poses`` for the scene's object, or None when a sample has
    exact clearance < ``tau`` or a motion between samples is not certified to keep it."""
    shape = scene.objects[0].shape
    fp = C.footprint_of(shape)
    world = C.object_world(scene, 0)
    dense = np.ascontiguousarray(sample_witness(poses))
    c = C.clearance(shape, world, dense)
    if float(np.min(c)) < tau:
        return None
    for i in range(len(dense) - 1):
        if not K.motion_ok(dense[i], dense[i + 1], float(c[i]), float(c[i + 1]), tau,
                           C.MAX_DEPTH, *fp.args, *world.args):
            return None
    d = np.diff(poses, axis=0)
    return Witness(poses, tau, float(np.sum(np.hypot(d[:, 0], d[:, 1]))),
                   float(np.sum(np.abs(d[:, 2]))), float(np.min(c)), len(dense))


# --------------------------------------------------------------------------- scenes
@dataclass(frozen=True)
class CorridorReport:
    """Check results of a corridor scene (its manifest entry): the certified witness,
    exact start / goal clearances and robot reachability."""

    witness: Witness
    start_clearance: float
    goal_clearance: float
    reach: C.RobotReach

    def to_dict(self) -> dict[str, Any]:
        return {
            "start_clearance": round(self.start_clearance, 4),
            "goal_clearance": round(self.goal_clearance, 4),
            "witness": self.witness.to_dict(),
            "robots": self.reach.to_dict(),
        }


@dataclass(frozen=True)
class GeneratedCorridor:
    """A generated corridor scene with its file dict, loaded Scene and check report."""

    index: int
    scene_dict: dict[str, Any]
    scene: Scene
    report: CorridorReport
    attempts: int
    layout_info: dict[str, Any]


def _end_heading(rng: np.random.Generator, obj: CorridorObject, leg: float) -> float:
    if obj.period == 0.0:
        return 0.0
    turn = (1.0 if rng.random() < 0.5 else -1.0) * rng.uniform(*END_TURN_RANGE)
    return rnd(wrap_angle(leg - obj.axis + turn), 4)


def _in_start_room(lay: CorridorLayout, p: np.ndarray, margin: float) -> bool:
    a = lay.chain.angles[0]
    d = p - lay.chain.vertices[0]
    u = float(d @ CL.unit(a))
    v = float(d @ CL.unit(a + 0.5 * math.pi))
    (u0, u1), (v0, v1) = lay.rooms.start_u, lay.rooms.start_v
    return u0 + margin <= u <= u1 - margin and v0 + margin <= v <= v1 - margin


def generate_scene(index: int) -> GeneratedCorridor:
    """Generate scene ``index`` (0-based); deterministic in ``index``.

    The accepted scene loads, its witness route is certified (every motion keeps exact
    clearance >= WITNESS_MIN_CLEARANCE), its robots start in the start room behind the
    object and every robot reaches the object's contact ring.
    """
    if not (isinstance(index, int) and 0 <= index < N_SCENES):
        raise ValueError(f"index must be an int in [0, {N_SCENES}), got {index!r}")
    rng = np.random.default_rng([SUITE_SEED, STREAM, index])
    obj = sample_object(rng, index)
    shape = shape_from_dict(obj.shape)
    name = scene_name(index)
    rejected: dict[str, int] = {}

    def reject(why: str) -> None:
        rejected[why] = rejected.get(why, 0) + 1

    for attempt in range(1, MAX_ATTEMPTS + 1):
        lay = layout_corridor(rng, obj)
        if lay is None:
            reject("no layout fits")
            continue
        start = np.array([*lay.start_xy, _end_heading(rng, obj, lay.chain.angles[0])])
        goal = np.array([*lay.goal_xy, _end_heading(rng, obj, lay.chain.angles[-1])])
        world = C.build_world(lay.workspace, obstacles_of(lay.obstacles))
        away = math.remainder(lay.chain.angles[0] + math.pi, 2.0 * math.pi)
        robots = place_robots(rng, world, shape, start, obj.reach, lay.workspace,
                              sector=(away, ROBOT_SECTOR))
        if robots is None or not all(
            _in_start_room(lay, np.array(p), ROBOT_RADIUS) for p in robots
        ):
            reject("no robot starts")
            continue
        d = scene_dict(name, lay.workspace, robots, lay.obstacles, obj.shape, start, goal)
        scene = parse_scene(d)
        if scene is None:
            reject("invalid scene")
            continue
        witness = certify_witness(scene, witness_poses(lay, obj, start, goal))
        if witness is None:
            reject("witness not certified")
            continue
        reach = C.robot_reach(scene, 0, resolution=REACH_RESOLUTION,
                              ring_width=REACH_RING_WIDTH)
        if not reach.all_reach or reach.ring_fraction < 0.5:
            reject("robots cannot reach the object")
            continue
        c_start, c_goal = C.clearance(shape, world, np.array([start, goal]))
        report = CorridorReport(witness, float(c_start), float(c_goal), reach)
        return GeneratedCorridor(index, d, scene, report, attempt, lay.info(obj))
    raise RuntimeError(
        f"{name}: no valid scene after {MAX_ATTEMPTS} attempts (rejected: {rejected})"
    )
