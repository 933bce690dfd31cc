"""An independent safety check of an executed recording: did anything collide?

``check_recording(scene, times, robots, objects)`` (or ``check_run_dir(RUN_DIR)``) re-checks
the recorded trajectories against the scene with Shapely and NumPy alone: none of the
planners' geometry code is used, only the scene model's shapes and poses, from which this
module builds its own polygons. At every checked state it measures, per pair of bodies, a
penetration depth (metres, 0 when apart or touching) and reports the pairs deeper than the
tolerance of their kind:

- ``robot-robot``: ``2 r - |c_i - c_j|`` (so "centre distance >= 2 r - tol");
- ``robot-obstacle``, ``robot-object``: ``r - sd(c, S)``, ``sd`` the signed distance of the
  robot centre from the shape (negative inside); two disks: ``r + R - |c - o|``;
- ``robot-border``, ``object-border``: how far the body reaches outside [0, W] x [0, H];
- ``object-object``, ``object-obstacle``: a disk against anything as above; two polygons
  (rectangles are polygons): the deepest point of either outline inside the other,
  measured to the other's boundary.

Guarantee. Disk depths and border depths are exact (up to float rounding). A polygon
pair's depth is evaluated on the boundary of their intersection (the parts of each outline
inside the other) at its vertices and every ``SAMPLE_SPACING`` (1 cm), so it is exact
whenever the deepest point is a vertex of either outline (a corner pressed into a side, a
side pressed flat against a side) and otherwise at most ``SAMPLE_SPACING / 2`` too small, never too large.

Between rows. The state is interpolated linearly between consecutive rows (positions,
angles the short way round, times): an interval in which some robot centre or object point
moves ``move > r / 2`` (``r`` the robot radius) is cut into ``ceil(move / (r / 2))`` equal
steps. Two bodies then move at most ``r`` relative to each other from one checked state to
the next, so a robot whose centre passes through an obstacle, an object or another robot
is caught at least ``r / 2`` deep (25 mm at the shipped radius); only object parts thinner
than ``r`` could pass through each other unseen. Motion between rows is taken as straight.
Rows are 0.08 s (2 cm of robot motion) apart, so this only acts where a robot catches up
fast or a state jumps.

Tolerances (``DEFAULT_TOL``) come from measurement: MuJoCo's soft contacts let touching
bodies sink into each other a little. On ten clean ``lamp run --planner lazy --seed 0``
recordings (tests/scenes.py's tiny scene, demo, random-01, random-05, maze-02, maze-05,
tilt-01, warehouse-01, corridor-01, iros-01: 10,639 rows, 3 robots, 1-9 objects, up to 27
obstacles) the deepest penetrations were robot-object 0.39 mm (a robot pressing on the
load it pushes), object-obstacle 0.16 mm (a load sliding along a corridor wall),
robot-robot 0.006 mm, and none robot-obstacle, robot-border, object-border, object-object.
Seven harsher runs (gco-var's zero buffer, open-loop astar, mapush, actuation noise 0.3
with 0.5 N s push impulses, a robot failing mid-run, a 100 kg load pushed at 60 N and at
1000 N force limits) reached robot-obstacle 0.31 mm, object-obstacle 0.16 mm, robot-object
0.23 mm, robot-robot 0.074 mm, robot-border 0.072 mm. The defaults: 2 mm (five times the
deepest of all), 3 mm robot-object, where contact is the job; a real collision is
centimetres deep. They hold for the shipped contact model (``lamp.sim.mjcf``'s
``CONTACT_SOLREF``); pass ``tol`` for another.

Pushing. Given each robot's sub-team per row (``robot_team``: the object it pushes, -1
none; a concurrent run's recording keeps it, and for a sequential one every robot works
for the object of the segment in force), a robot's contact with the object it pushes is
the kind ``robot-pushed-object``, tolerance 10 mm: a sub-team pressing on a load that is
stuck sinks in further (7.2 mm the deepest in the 25 concurrent runs of the ``fleet``
family, at the robots' 60 N force limit). Contact with any other object stays
``robot-object`` (3 mm): a robot of another sub-team touching a load is a collision.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely

from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, Shape

#: The kinds of violation, in report order.
KINDS = ("robot-robot", "robot-obstacle", "robot-border", "robot-object",
         "robot-pushed-object", "object-object", "object-obstacle", "object-border")
#: Default tolerance per kind [m] (see the module docstring for the measured depths).
DEFAULT_TOL: Mapping[str, float] = {**dict.fromkeys(KINDS, 0.002), "robot-object": 0.003,
                                    "robot-pushed-object": 0.010}
#: Spacing of the points checked along polygon edges (besides the vertices) [m].
SAMPLE_SPACING = 0.01


@dataclass(frozen=True)
class Violation:
    """Bodies ``a`` and ``b`` (indices into the scene's robots, objects or obstacles as
    ``kind`` says; ``b == -1`` for the border) first deeper than the tolerance at
    ``time_s``; ``depth_m`` is the deepest they got, at ``worst_time_s``."""

    time_s: float
    kind: str
    a: int
    b: int
    depth_m: float
    worst_time_s: float | None = None

    def describe(self) -> str:
        pa, _, pb = self.kind.partition("-")
        other = "the border" if pb == "border" else f"{pb} {self.b}"
        worst = "" if self.worst_time_s is None else f" (deepest at {self.worst_time_s:.2f} s)"
        return (f"t={self.time_s:.2f} s  {self.kind}: {pa} {self.a} / {other}: "
                f"{1000 * self.depth_m:.1f} mm{worst}")


@dataclass(frozen=True)
class SafetyReport:
    """What ``check_recording`` found: the violations (the worst per (kind, a, b), sorted
    by first time), the deepest penetration of each kind whether over tolerance or not,
    the tolerances used, and how many recorded rows and states (rows plus interpolated
    states) were checked."""

    violations: list[Violation]
    worst_depth: dict[str, float]
    tol: dict[str, float]
    rows_checked: int
    states_checked: int
    n_robots: int = 0
    n_objects: int = 0
    elapsed_s: float = field(default=0.0, compare=False)

    @property
    def ok(self) -> bool:
        return not self.violations

    def summary(self) -> str:
        verdict = "OK" if self.ok else f"{len(self.violations)} violation(s)"
        lines = [f"safety: {self.rows_checked} rows ({self.states_checked} states checked), "
                 f"{self.n_robots} robots, {self.n_objects} objects: {verdict}",
                 f"  {'kind':<20}{'deepest':>10}{'tol':>9}{'violations':>12}"]
        for kind in KINDS:
            n = sum(v.kind == kind for v in self.violations)
            lines.append(f"  {kind:<20}{1000 * self.worst_depth.get(kind, 0.0):>7.3f} mm"
                         f"{1000 * self.tol[kind]:>6.1f} mm{n:>12}")
        lines += ["  " + v.describe() for v in self.violations]
        return "\n".join(lines)


# ------------------------------------------------------------------------------ bodies
@dataclass(frozen=True)
class _Body:
    """A shape in its own frame: a disk of ``radius`` about the origin, or a polygon
    (``poly`` and its ``ring``, prepared) with its vertices ``verts``; ``bound``: the radius
    of a disk about the origin holding it."""

    bound: float
    radius: float | None = None
    poly: shapely.Polygon | None = None
    ring: shapely.LinearRing | None = None
    verts: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))


def _disk(radius: float) -> _Body:
    return _Body(bound=float(radius), radius=float(radius))


def _polygon(points: np.ndarray) -> _Body:
    poly = shapely.Polygon(np.asarray(points, dtype=float))
    if not poly.is_valid or poly.area <= 0.0:
        raise ValueError(f"not a simple polygon of positive area: {points.tolist()}")
    ring = poly.exterior
    shapely.prepare(poly)
    shapely.prepare(ring)
    verts = shapely.get_coordinates(ring)[:-1]
    return _Body(bound=float(np.max(np.hypot(verts[:, 0], verts[:, 1]))), poly=poly,
                 ring=ring, verts=verts)


def shape_body(shape: Shape) -> _Body:
    """A scene shape in its own frame."""
    if isinstance(shape, Circle):
        return _disk(shape.radius)
    if isinstance(shape, Rectangle):
        hx, hy = 0.5 * float(shape.size[0]), 0.5 * float(shape.size[1])
        return _polygon(np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]]))
    return _polygon(np.asarray(shape.points, dtype=float))


def _obstacle_body(obstacle: Obstacle) -> tuple[_Body, np.ndarray]:
    """A static obstacle as a body and its pose; polygons are re-centred on their bounding
    box so that ``bound`` is tight (world polygons come with the identity pose)."""
    pose = np.asarray(obstacle.pose, dtype=float)
    body = shape_body(obstacle.shape)
    if body.radius is not None:
        return body, np.array([pose[0], pose[1], 0.0])
    world = _to_world(pose[None], body.verts)[0]
    centre = 0.5 * (world.min(axis=0) + world.max(axis=0))
    return _polygon(world - centre), np.array([centre[0], centre[1], 0.0])


# ------------------------------------------------------------------------------ depths
def _to_world(poses: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Points in the body frame, (V, 2) or (P, V, 2), at poses (P, 3) -> (P, V, 2)."""
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    u, v = pts[..., 0], pts[..., 1]
    return np.stack([poses[:, :1] + c * u - s * v, poses[:, 1:2] + s * u + c * v], axis=-1)


def _to_local(poses: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """World points (P, V, 2) into the frames of poses (P, 3)."""
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    dx, dy = pts[..., 0] - poses[:, :1], pts[..., 1] - poses[:, 1:2]
    return np.stack([c * dx + s * dy, c * dy - s * dx], axis=-1)


def _signed_distance(body: _Body, xy: np.ndarray) -> np.ndarray:
    """Signed distance (negative inside) of body-frame points (M, 2) from a polygon body."""
    if len(xy) == 0:
        return np.zeros(0)
    d = shapely.distance(body.ring, shapely.points(xy))
    return np.where(shapely.contains_xy(body.poly, xy[:, 0], xy[:, 1]), -d, d)


def _disk_depth(radius: float, xy: np.ndarray, b: _Body) -> np.ndarray:
    """(M,) penetration of disks of ``radius`` centred at ``xy`` (M, 2) into polygon ``b``
    (its frame); only centres in a polygonised buffer of b that holds every point within
    ``radius`` of it (sagitta of 8 segments per quarter: 0.5 %) are measured."""
    zone = shapely.buffer(b.poly, 1.01 * radius + 1e-4, quad_segs=8)
    out = np.full(len(xy), -np.inf)
    near = np.flatnonzero(shapely.contains_xy(zone, xy[:, 0], xy[:, 1]))
    out[near] = radius - _signed_distance(b, xy[near])
    return out


def _placed(body: _Body, poses: np.ndarray):
    """Polygon ``body`` at poses (P, 3) in the world: one geometry when every pose is the
    same (a static obstacle), else an array of P."""
    if np.all(poses == poses[0]):
        return shapely.Polygon(_to_world(poses[:1], body.verts)[0])
    return shapely.polygons(_to_world(poses, body.verts))


def _take(geoms, idx: np.ndarray):
    return geoms[idx] if isinstance(geoms, np.ndarray) else geoms


def _overlap_depth(a: _Body, pa: np.ndarray, b: _Body, pb: np.ndarray) -> np.ndarray:
    """(P,) overlap depth of polygons ``a``, ``b`` (-inf: apart): the largest
    ``d(p, ring a) + d(p, ring b)`` over the boundary of their intersection, sampled at its
    vertices and every ``SAMPLE_SPACING`` (that boundary is the part of each ring inside the
    other, so this is the deepest point of either outline inside the other)."""
    if len(pa) == 0:
        return np.zeros(0)
    ga, gb = _placed(a, pa), _placed(b, pb)
    n = len(pa) if isinstance(ga, np.ndarray) or isinstance(gb, np.ndarray) else 1
    out = np.full(n, -np.inf)
    hit = np.flatnonzero(np.broadcast_to(shapely.intersects(ga, gb), (n,)))
    if hit.size:
        ga, gb = _take(ga, hit), _take(gb, hit)
        inter = shapely.segmentize(shapely.intersection(ga, gb), SAMPLE_SPACING)
        pts, idx = shapely.get_coordinates(inter, return_index=True)
        pts = shapely.points(pts)
        f = (shapely.distance(shapely.get_exterior_ring(_take(ga, idx)), pts)
             + shapely.distance(shapely.get_exterior_ring(_take(gb, idx)), pts))
        best = np.zeros(hit.size)
        np.maximum.at(best, idx, f)
        out[hit] = best
    return np.broadcast_to(out, (len(pa),))


def _pair_depth(a: _Body, pa: np.ndarray, b: _Body, pb: np.ndarray) -> np.ndarray:
    """Penetration depth (>= 0) of bodies ``a`` and ``b`` at broadcastable poses (..., 3)."""
    pa, pb = np.broadcast_arrays(np.asarray(pa, float), np.asarray(pb, float))
    shape = pa.shape[:-1]
    pa, pb = pa.reshape(-1, 3), pb.reshape(-1, 3)
    gap = np.hypot(pa[:, 0] - pb[:, 0], pa[:, 1] - pb[:, 1])
    if a.radius is not None and b.radius is not None:
        out = a.radius + b.radius - gap
    else:
        out = np.zeros(len(gap))
        near = np.flatnonzero(gap < a.bound + b.bound)
        if b.radius is not None:
            a, pa, b, pb = b, pb, a, pa
        pa, pb = pa[near], pb[near]
        if a.radius is not None:  # a disk against a polygon
            out[near] = _disk_depth(a.radius, _to_local(pb, pa[:, None, :2])[:, 0], b)
        else:
            out[near] = _overlap_depth(a, pa, b, pb)
    return np.maximum(out, 0.0).reshape(shape)


def _border_depth(body: _Body, poses: np.ndarray, size: tuple[float, float]) -> np.ndarray:
    """How far (>= 0) ``body`` at poses (..., 3) reaches outside [0, W] x [0, H]."""
    shape = poses.shape[:-1]
    flat = poses.reshape(-1, 3)
    if body.radius is not None:
        pts, reach = flat[:, None, :2], body.radius
    else:  # a polygon's extreme points are vertices
        pts, reach = _to_world(flat, body.verts), 0.0
    x, y = pts[..., 0], pts[..., 1]
    out = np.maximum.reduce([reach - x, x + reach - size[0], reach - y, y + reach - size[1]])
    return np.maximum(out.max(axis=1), 0.0).reshape(shape)


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _states(times, robots, objects, bounds, step):
    """The checked states: every row, plus linear interpolation where some robot centre or
    object point moves more than ``step`` (``r / 2``) between rows (module docstring)."""
    if len(times) < 2:
        return times, robots, objects
    move = np.hypot(*np.moveaxis(np.diff(robots, axis=0), -1, 0)).max(axis=1, initial=0.0)
    if objects.shape[1]:
        d = np.diff(objects, axis=0)
        obj = np.hypot(d[..., 0], d[..., 1]) + bounds * np.abs(_wrap(d[..., 2]))
        move = np.maximum(move, obj.max(axis=1))
    n = np.maximum(1, np.ceil(move / step - 1e-9)).astype(int)
    if n.max() == 1:
        return times, robots, objects
    idx = np.append(np.repeat(np.arange(len(n)), n), len(n) - 1)
    frac = np.append((np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n, n),
                     1.0)

    def lerp(arr, angle=False):
        f = frac.reshape((-1,) + (1,) * (arr.ndim - 1))
        delta = arr[idx + 1] - arr[idx]
        if angle:
            delta[..., 2] = _wrap(delta[..., 2])
        return arr[idx] + f * delta

    return lerp(times), lerp(robots), lerp(objects, angle=True)


# ------------------------------------------------------------------------------ check
class _Collector:
    def __init__(self, times: np.ndarray, tol: dict[str, float]):
        self.times, self.tol = times, tol
        self.worst = dict.fromkeys(KINDS, 0.0)
        self.violations: list[Violation] = []

    def add(self, kind: str, depth: np.ndarray, pairs: list[tuple[int, int]]) -> None:
        """``depth`` (T, P): the depth of each pair of ``pairs`` at every checked state."""
        if depth.size == 0:
            return
        self.worst[kind] = max(self.worst[kind], float(depth.max()))
        over = depth > self.tol[kind]
        for p in np.flatnonzero(over.any(axis=0)):
            first, deepest = int(np.argmax(over[:, p])), int(np.argmax(depth[:, p]))
            self.violations.append(Violation(float(self.times[first]), kind, pairs[p][0],
                                             pairs[p][1], float(depth[deepest, p]),
                                             float(self.times[deepest])))


def _tolerances(tol: float | Mapping[str, float] | None) -> dict[str, float]:
    if tol is None:
        return dict(DEFAULT_TOL)
    if isinstance(tol, Mapping):
        unknown = set(tol) - set(KINDS)
        if unknown:
            raise ValueError(f"tol: unknown kinds {sorted(unknown)}; expected {KINDS}")
        return {**DEFAULT_TOL, **{k: float(v) for k, v in tol.items()}}
    return dict.fromkeys(KINDS, float(tol))


def check_recording(scene: Scene, times, robot_positions, object_poses, *,
                    tol: float | Mapping[str, float] | None = None,
                    robot_team=None) -> SafetyReport:
    """Check a recorded run against ``scene``: ``times`` (S,), ``robot_positions``
    (S, N, 2), ``object_poses`` (S, K, 3) (the recording's ``times``, ``robots`` and
    ``objects``). ``tol``: one tolerance for every kind, or a mapping of kinds to
    tolerances overriding :data:`DEFAULT_TOL` [m]. ``robot_team`` (S, N): the object each
    robot pushes at each row (-1: none); None: every contact is ``robot-object``."""
    t0 = time.perf_counter()
    tols = _tolerances(tol)
    times = np.asarray(times, dtype=float).reshape(-1)
    robots = np.asarray(robot_positions, dtype=float)
    objects = np.asarray(object_poses, dtype=float)
    n, k, s = scene.n_robots, len(scene.objects), len(times)
    if robots.shape != (s, n, 2) or objects.shape != (s, k, 3):
        raise ValueError(f"expected robots ({s}, {n}, 2) and objects ({s}, {k}, 3) for "
                         f"{s} times, got {robots.shape} and {objects.shape}")
    r = float(scene.robot_radius)
    robot = _disk(r)
    bodies = [shape_body(o.shape) for o in scene.objects]
    statics = [_obstacle_body(o) for o in scene.obstacles]
    bounds = np.array([b.bound for b in bodies])
    times_x, robots_x, objects_x = _states(times, robots, objects, bounds, r / 2)
    out = _Collector(times_x, tols)
    rpose = np.concatenate([robots_x, np.zeros(robots_x.shape[:-1] + (1,))], axis=-1)

    for i in range(n - 1):  # robot i against every later one: memory (T, N), not (T, N^2)
        gap = np.linalg.norm(robots_x[:, i + 1:] - robots_x[:, i:i + 1], axis=-1)
        out.add("robot-robot", np.maximum(2 * r - gap, 0.0), [(i, j) for j in range(i + 1, n)])
    out.add("robot-border", _border_depth(robot, rpose, scene.workspace),
            [(i, -1) for i in range(n)])
    for m, (body, pose) in enumerate(statics):
        out.add("robot-obstacle", _pair_depth(robot, rpose, body, pose),
                [(i, m) for i in range(n)])
    team_x = None
    if robot_team is not None:
        team = np.asarray(robot_team).reshape(s, n)
        team_x = team[np.clip(np.searchsorted(times, times_x, side="right") - 1, 0, s - 1)]
    for a, body in enumerate(bodies):
        pa = objects_x[:, a]
        depth = _pair_depth(robot, rpose, body, pa[:, None])
        own = np.zeros_like(depth, bool) if team_x is None else team_x == a
        out.add("robot-object", np.where(own, 0.0, depth), [(i, a) for i in range(n)])
        out.add("robot-pushed-object", np.where(own, depth, 0.0), [(i, a) for i in range(n)])
        out.add("object-border", _border_depth(body, pa[:, None], scene.workspace), [(a, -1)])
        for m, (other, pose) in enumerate(statics):
            out.add("object-obstacle", _pair_depth(body, pa, other, pose)[:, None], [(a, m)])
        for b in range(a + 1, k):
            depth = _pair_depth(body, pa, bodies[b], objects_x[:, b])
            out.add("object-object", depth[:, None], [(a, b)])
    out.violations.sort(key=lambda v: (v.time_s, KINDS.index(v.kind), v.a, v.b))
    return SafetyReport(out.violations, out.worst, tols, s, len(times_x), n, k,
                        time.perf_counter() - t0)


def check_run_dir(path: str | Path, *,
                  tol: float | Mapping[str, float] | None = None) -> SafetyReport:
    """Check the recording a run left in folder ``path`` (``recording.npz`` +
    ``recording.json``) against the scene stored in it."""
    from lamp.record.format import load_recording

    rec = load_recording(path)
    return check_recording(rec.scene_model(), rec.arrays["times"], rec.arrays["robots"],
                           rec.arrays["objects"], tol=tol, robot_team=recorded_teams(rec))


def recorded_teams(rec) -> np.ndarray:
    """(S, N) the object each robot pushes at each row of recording ``rec``: its
    ``robot_team`` array when it has one (a concurrent run), else the object of the
    segment each row belongs to, for every robot (-1 before the first segment)."""
    a = rec.arrays
    if "robot_team" in a:
        return np.asarray(a["robot_team"])
    s, n = len(a["times"]), a["robots"].shape[1]
    team = np.full((s, n), -1, np.int64)
    rows = a["segment_rows"]
    for g, k in enumerate(a["segment_object"]):
        team[rows[g]:rows[g + 1] + 1] = int(k)
    return team


__all__ = ["DEFAULT_TOL", "KINDS", "SAMPLE_SPACING", "SafetyReport", "Violation",
           "check_recording", "check_run_dir", "recorded_teams", "shape_body"]
