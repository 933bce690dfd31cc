"""Building the MuJoCo model (MJCF) of a scene's static structure, with a compile cache.

The simulated world is planar: every body lives in the plane z = 0 and has only planar
degrees of freedom, so nothing can tip, sink or fly. What is built here:

- **walls**: four thick boxes just outside the workspace border [0, W] x [0, H];
- **obstacles**: circles as spheres (their cross-section in the plane z = 0 is exactly the
  disk, and sphere contacts are analytic in MuJoCo, cheaper and more robust than cylinder
  contacts found by convex collision detection), rectangles as boxes, polygons split into
  convex pieces, each a prism mesh;
- **objects**: one free planar body each (slide x, slide y, hinge z at the shape's area
  centroid), with the same geometry rules as obstacles, fixed mass ``OBJECT_MASS`` and the
  planar inertia of a uniform plate of that shape. Ground friction is viscous (isotropic
  joint damping ``GROUND_DAMPING`` per kg on the slides and ``GROUND_DAMPING * rho^2`` on the
  hinge, rho the radius of gyration: the ellipsoidal limit surface of a plate with uniform
  viscous contact pressure) plus a small dry friction loss so that an object not being
  pushed comes to a complete stop;
- **robots**: spheres of the robot radius (disks in the plane) with mass ``ROBOT_MASS`` on
  slide x / slide y joints, each joint driven by a force-limited position actuator with
  damping. The force limit bounds how hard a robot presses on anything that blocks it, so a
  robot commanded into a wall or an obstacle stops at it.

The model depends only on the scene's static structure (workspace, obstacles, object
shapes, robot count and radius); poses live in ``qpos``. Compiled models are cached on that
structure, so many simulators of one structure (e.g. a data generator that places robots
and one object at many poses) share one compiled model and cost only an ``MjData``.

Units: metres, radians, kilograms, seconds.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import mujoco
import numpy as np
import shapely

from lamp.geometry.shapes import local_outline
from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, Shape
from lamp.scene.physics import DEFAULT_PHYSICS, ObjectPhysics, Physics
from lamp.scene.physics import OBJECT_MASS as _OBJECT_MASS

#: Physics time step [s].
TIMESTEP = 0.002
#: Mass of every robot [kg]: heavier than objects so pushes stay stable.
ROBOT_MASS = 2.2
#: Mass of an object [kg] whose scene file gives none (fixed, independent of size;
#: owned by ``lamp.scene.physics``).
OBJECT_MASS = _OBJECT_MASS
#: Default viscous ground friction of objects [N s / m per kg of object mass]; at the robot
#: speed of 0.25 m/s a 1 kg object needs 7.5 N to be pushed, and a released object stops
#: within about 1 cm (time constant 1 / GROUND_DAMPING = 33 ms). A scene sets its own
#: (``physics.ground_damping``).
GROUND_DAMPING = DEFAULT_PHYSICS.ground_damping
#: Dry ground friction per object slide joint [N] (per unit radius of gyration on the hinge).
GROUND_FRICTIONLOSS = 0.3
#: Position gain of the robot actuators [N/m].
ROBOT_KP = 4000.0
#: Velocity gain of the robot actuators [N s/m] (critically damped for ROBOT_MASS).
ROBOT_KV = 2.0 * float(np.sqrt(ROBOT_KP * ROBOT_MASS))
#: Default force limit of each robot actuator (per axis) [N]; a scene sets its own
#: (``robots.force_limit``).
ROBOT_FORCE_LIMIT = DEFAULT_PHYSICS.robot_force_limit
#: Default Coulomb friction of all contacts (robot-object, object-object, object-wall); a
#: scene sets its own (``physics.contact_friction``), an object its own (``friction``).
CONTACT_FRICTION = DEFAULT_PHYSICS.contact_friction
#: Contact softness: (time constant [s], damping ratio); stiff, yet >= 2 time steps.
CONTACT_SOLREF = (0.004, 1.0)
#: Half height of object prisms [m] (objects are 4 cm tall).
OBJECT_HALF_HEIGHT = 0.02
#: Half height of walls and obstacle prisms [m].
STATIC_HALF_HEIGHT = 0.1
#: Thickness of the border walls [m].
WALL_THICKNESS = 0.5


@dataclass(frozen=True)
class ObjectBody:
    """How an object's pose maps to its body coordinates.

    The body frame sits at the shape's area ``centroid`` (object frame), so the joint
    coordinates are (centroid_x, centroid_y, theta) in the world.
    """

    centroid: tuple[float, float]
    outline: np.ndarray  # (V, 2) vertices in the object frame for footprint checks (circles: empty)
    radius: float  # circles: radius about the origin; polygons: 0


@dataclass(frozen=True)
class BuiltModel:
    """A compiled model plus the index maps the simulator needs."""

    model: mujoco.MjModel
    n_robots: int
    n_objects: int
    robot_qpos: np.ndarray  # (N, 2) qpos addresses of each robot's x and y slides
    object_qpos: np.ndarray  # (K, 3) qpos addresses of each object's x, y, theta joints
    robot_dof: np.ndarray  # (N, 2) dof addresses
    object_dof: np.ndarray  # (K, 3) dof addresses
    objects: tuple[ObjectBody, ...]
    xml: str


def _fmt(values) -> str:
    return " ".join(f"{float(v):.10g}" for v in values)


@functools.lru_cache(maxsize=1024)
def convex_pieces(points: tuple[tuple[float, float], ...]) -> tuple[np.ndarray, ...]:
    """Split a simple polygon into convex pieces (counter-clockwise vertex arrays).

    Constrained Delaunay triangulation, then greedy Hertel-Mehlhorn merging: two pieces
    sharing an edge are merged while their union stays convex. Fewer, fatter pieces give
    better contacts than slivers. Convex input comes back as one piece.
    """
    poly = shapely.Polygon(points)
    if not poly.is_valid or poly.area <= 0.0:
        raise ValueError(f"polygon points={points!r} are not a valid simple polygon")
    hull = poly.convex_hull
    if abs(hull.area - poly.area) <= 1e-12 * max(hull.area, 1.0):
        return (_ccw(np.asarray(hull.exterior.coords)[:-1]),)
    tris = [g for g in shapely.constrained_delaunay_triangles(poly).geoms if g.area > 1e-14]
    pieces = list(tris)
    merged = True
    while merged:
        merged = False
        for i in range(len(pieces)):
            for j in range(i + 1, len(pieces)):
                shared = pieces[i].boundary.intersection(pieces[j].boundary)
                if shared.length <= 1e-12:
                    continue
                union = shapely.union(pieces[i], pieces[j])
                hull = union.convex_hull
                if abs(hull.area - union.area) <= 1e-9 * hull.area:
                    pieces[i] = hull
                    del pieces[j]
                    merged = True
                    break
            if merged:
                break
    return tuple(_ccw(np.asarray(p.exterior.coords)[:-1]) for p in pieces)


def _ccw(pts: np.ndarray) -> np.ndarray:
    pts = np.asarray(pts, dtype=float)
    area2 = np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
    return pts if area2 > 0 else pts[::-1].copy()


def plate_properties(shape: Shape) -> tuple[np.ndarray, float]:
    """(area centroid (2,), squared radius of gyration about it) of a uniform plate."""
    if isinstance(shape, Circle):
        return np.zeros(2), 0.5 * float(shape.radius) ** 2
    pts = local_outline(shape)
    x, y = pts[:, 0], pts[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = 0.5 * cross.sum()
    cx = ((x + xn) * cross).sum() / (6.0 * area)
    cy = ((y + yn) * cross).sum() / (6.0 * area)
    # polar second moment about the origin, then shifted to the centroid
    jz = ((x * x + x * xn + xn * xn + y * y + y * yn + yn * yn) * cross).sum() / 12.0
    rho2 = jz / area - (cx * cx + cy * cy)
    return np.array([cx, cy]), float(rho2)


class _MeshBank:
    """Collects prism meshes for the <asset> section."""

    def __init__(self) -> None:
        self.assets: list[str] = []

    def prism(self, pts: np.ndarray, half_height: float) -> str:
        name = f"mesh{len(self.assets)}"
        verts = np.concatenate(
            [
                np.column_stack([pts, np.full(len(pts), -half_height)]),
                np.column_stack([pts, np.full(len(pts), half_height)]),
            ]
        )
        self.assets.append(f'<mesh name="{name}" vertex="{_fmt(verts.ravel())}"/>')
        return name


def _shape_geoms(
    shape: Shape,
    offset: np.ndarray,
    angle: float,
    half_height: float,
    meshes: _MeshBank,
    cls: str,
) -> list[str]:
    """Geoms of ``shape`` in a frame where the shape's own origin is at ``offset`` rotated by
    ``angle`` (shape points are mapped p -> R(angle) p + offset)."""
    if isinstance(shape, Circle):
        return [
            f'<geom class="{cls}" type="sphere" size="{shape.radius:.10g}" pos="{_fmt([*offset, 0.0])}"/>'
        ]
    if isinstance(shape, Rectangle):
        c, s = np.cos(0.5 * angle), np.sin(0.5 * angle)
        size = [0.5 * shape.size[0], 0.5 * shape.size[1], half_height]
        return [
            f'<geom class="{cls}" type="box" size="{_fmt(size)}" pos="{_fmt([*offset, 0.0])}" '
            f'quat="{_fmt([c, 0.0, 0.0, s])}"/>'
        ]
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s], [s, c]])
    out = []
    for piece in convex_pieces(tuple(tuple(map(float, p)) for p in shape.points)):
        name = meshes.prism(piece @ rot.T + offset, half_height)
        out.append(f'<geom class="{cls}" type="mesh" mesh="{name}"/>')
    return out


def _obstacle_geoms(obstacle: Obstacle, meshes: _MeshBank) -> list[str]:
    x, y, th = (float(v) for v in obstacle.pose)
    return _shape_geoms(obstacle.shape, np.array([x, y]), th, STATIC_HALF_HEIGHT, meshes, "static")


def structure_key(scene: Scene) -> tuple:
    """Hashable description of everything the compiled model depends on."""
    return (
        tuple(float(v) for v in scene.workspace),
        tuple(scene.obstacles),
        tuple(o.shape for o in scene.objects),
        scene.n_robots,
        float(scene.robot_radius),
        scene.physics,
        tuple(o.physics for o in scene.objects),
    )


def build_model(scene: Scene) -> BuiltModel:
    """The compiled model of ``scene`` (cached on its static structure)."""
    return _build_cached(structure_key(scene))


@functools.lru_cache(maxsize=256)
def _build_cached(key: tuple) -> BuiltModel:
    workspace, obstacles, shapes, n_robots, radius, physics, object_physics = key
    xml, objects = _make_xml(workspace, obstacles, shapes, n_robots, radius, physics,
                             object_physics)
    model = mujoco.MjModel.from_xml_string(xml)
    jnt = model.jnt_qposadr
    dof = model.jnt_dofadr
    robot_ids = np.array(
        [[model.joint(f"r{i}x").id, model.joint(f"r{i}y").id] for i in range(n_robots)], dtype=int
    ).reshape(-1, 2)
    object_ids = np.array(
        [[model.joint(f"o{k}{a}").id for a in "xyt"] for k in range(len(shapes))], dtype=int
    ).reshape(-1, 3)
    return BuiltModel(
        model=model,
        n_robots=n_robots,
        n_objects=len(shapes),
        robot_qpos=jnt[robot_ids],
        object_qpos=jnt[object_ids],
        robot_dof=dof[robot_ids],
        object_dof=dof[object_ids],
        objects=objects,
        xml=xml,
    )


def _object_bodies(shapes: tuple[Shape, ...], physics: Physics,
                   object_physics: tuple[ObjectPhysics, ...], meshes: _MeshBank
                   ) -> tuple[list[str], list[ObjectBody]]:
    """The objects' free planar bodies (mass, inertia, ground friction, geoms)."""
    bodies: list[str] = []
    objects: list[ObjectBody] = []
    for k, shape in enumerate(shapes):
        own = object_physics[k] if k < len(object_physics) else ObjectPhysics()
        mass = OBJECT_MASS if own.mass is None else own.mass
        centroid, rho2 = plate_properties(shape)
        cls = "object" if own.friction is None else f"object{k}"
        geoms = _shape_geoms(shape, -centroid, 0.0, OBJECT_HALF_HEIGHT, meshes, cls)
        izz = mass * rho2
        rho = float(np.sqrt(rho2))
        damp = physics.ground_damping * mass
        bodies.append(
            f'<body name="o{k}">'
            f'<inertial pos="0 0 0" mass="{mass:.10g}" diaginertia="{_fmt([izz, izz, izz])}"/>'
            f'<joint name="o{k}x" type="slide" axis="1 0 0" damping="{damp:.10g}" '
            f'frictionloss="{GROUND_FRICTIONLOSS:.10g}"/>'
            f'<joint name="o{k}y" type="slide" axis="0 1 0" damping="{damp:.10g}" '
            f'frictionloss="{GROUND_FRICTIONLOSS:.10g}"/>'
            f'<joint name="o{k}t" type="hinge" axis="0 0 1" damping="{damp * rho2:.10g}" '
            f'frictionloss="{GROUND_FRICTIONLOSS * rho:.10g}"/>' + "".join(geoms) + "</body>"
        )
        if isinstance(shape, Circle):
            objects.append(ObjectBody((0.0, 0.0), np.zeros((0, 2)), float(shape.radius)))
        else:
            objects.append(
                ObjectBody((float(centroid[0]), float(centroid[1])), local_outline(shape), 0.0)
            )
    return bodies, objects


def _make_xml(
    workspace: tuple[float, float],
    obstacles: tuple[Obstacle, ...],
    shapes: tuple[Shape, ...],
    n_robots: int,
    radius: float,
    physics: Physics = DEFAULT_PHYSICS,
    object_physics: tuple[ObjectPhysics, ...] = (),
) -> tuple[str, tuple[ObjectBody, ...]]:
    w, h = workspace
    t = WALL_THICKNESS
    meshes = _MeshBank()
    static: list[str] = []
    # border walls: boxes whose inner faces are the workspace border lines
    for cx, cy, sx, sy in (
        (0.5 * w, -0.5 * t, 0.5 * w + t, 0.5 * t),
        (0.5 * w, h + 0.5 * t, 0.5 * w + t, 0.5 * t),
        (-0.5 * t, 0.5 * h, 0.5 * t, 0.5 * h + t),
        (w + 0.5 * t, 0.5 * h, 0.5 * t, 0.5 * h + t),
    ):
        static.append(
            f'<geom class="static" type="box" size="{_fmt([sx, sy, STATIC_HALF_HEIGHT])}" '
            f'pos="{_fmt([cx, cy, 0.0])}"/>'
        )
    for obstacle in obstacles:
        static.extend(_obstacle_geoms(obstacle, meshes))

    bodies, objects = _object_bodies(shapes, physics, object_physics, meshes)
    actuators: list[str] = []
    force = physics.robot_force_limit
    for i in range(n_robots):
        bodies.append(
            f'<body name="r{i}">'
            f'<inertial pos="0 0 0" mass="{ROBOT_MASS:.10g}" diaginertia="1e-3 1e-3 1e-3"/>'
            f'<joint name="r{i}x" type="slide" axis="1 0 0"/>'
            f'<joint name="r{i}y" type="slide" axis="0 1 0"/>'
            f'<geom class="robot" type="sphere" size="{radius:.10g}"/>'
            "</body>"
        )
        for a in "xy":
            actuators.append(
                f'<position joint="r{i}{a}" kp="{ROBOT_KP:.10g}" kv="{ROBOT_KV:.10g}" '
                f'forcelimited="true" forcerange="{-force:.10g} {force:.10g}"/>'
            )
    solref = _fmt(CONTACT_SOLREF)
    # an object with its own friction: its geoms take priority, so its contacts use it
    own_friction = [f'<default class="object{k}"><geom rgba="0.8 0.5 0.2 1" '
                    f'friction="{o.friction:.10g} 0.005 0.0001" priority="1"/></default>'
                    for k, o in enumerate(object_physics) if o.friction is not None]
    xml = (
        '<mujoco model="lamp">'
        '<compiler angle="radian" autolimits="true"/>'
        f'<option timestep="{TIMESTEP:.10g}" gravity="0 0 0" integrator="implicitfast" '
        'cone="pyramidal" solver="Newton" iterations="50"/>'
        "<default>"
        f'<geom friction="{physics.contact_friction:.10g} 0.005 0.0001" solref="{solref}" '
        'condim="3"/>'
        '<default class="static"><geom rgba="0.4 0.4 0.4 1"/></default>'
        '<default class="object"><geom rgba="0.8 0.5 0.2 1"/></default>'
        + "".join(own_friction) +
        '<default class="robot"><geom rgba="0.2 0.4 0.8 1"/></default>'
        "</default>"
        "<asset>" + "".join(meshes.assets) + "</asset>"
        "<worldbody>" + "".join(static) + "".join(bodies) + "</worldbody>"
        "<actuator>" + "".join(actuators) + "</actuator>"
        "</mujoco>"
    )
    return xml, tuple(objects)
