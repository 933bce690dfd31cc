"""A recording as an MCAP file for Foxglove: ``lamp render RUN_DIR --out run.mcap``.

Needs the ``mcap`` package (``pip install 'lamp[foxglove]'``). Messages are JSON; log
times are the simulated time since the run started, in nanoseconds. Topics:

- ``/scene`` (``foxglove.SceneUpdate``, frame ``world``, z = 0 is the floor): at time 0 the
  workspace border, the obstacles and the goals (kept for the whole run); then at every
  row the robots (spheres of the robot diameter) and the objects (outlines at their poses);
- ``/plan`` (``foxglove.SceneUpdate``): whenever the plan in force changes, its object path
  and its verified (green) and penalised (red) edges;
- ``/robots`` (``lamp.RobotPositions``), ``/objects`` (``lamp.ObjectPoses``): every row's
  positions and poses with its segment, as plain numbers for plots;
- ``/segments`` (``lamp.Segment``): at each segment's start, its object, timings, drift,
  outcome and contacts.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from lamp.geometry.shapes import local_outline, world_outline
from lamp.record.format import OUTCOMES, Recording
from lamp.viz.animation import PATH_COLOR, PENALISED_COLOR, VERIFIED_COLOR
from lamp.viz.scene_plot import GOAL_COLOR, OBSTACLE_COLOR, ROBOT_COLOR, object_color

FRAME = "world"

SCHEMAS: dict[str, dict[str, Any]] = {
    "foxglove.SceneUpdate": {
        "type": "object",
        "properties": {"deletions": {"type": "array"}, "entities": {"type": "array"}},
    },
    "lamp.RobotPositions": {
        "type": "object",
        "properties": {"time": {"type": "number"}, "segment": {"type": "integer"},
                       "positions": {"type": "array", "items": {"type": "array"}}},
    },
    "lamp.ObjectPoses": {
        "type": "object",
        "properties": {"time": {"type": "number"}, "segment": {"type": "integer"},
                       "poses": {"type": "array", "items": {"type": "array"}}},
    },
    "lamp.Segment": {
        "type": "object",
        "properties": {k: {"type": t} for k, t in (
            ("index", "integer"), ("object", "integer"), ("planning_time_s", "number"),
            ("sim_time_s", "number"), ("drift", "array"), ("outcome", "string"),
            ("replanned", "boolean"), ("contacts", "array"))},
    },
}
TOPICS = {"/scene": "foxglove.SceneUpdate", "/plan": "foxglove.SceneUpdate",
          "/robots": "lamp.RobotPositions", "/objects": "lamp.ObjectPoses",
          "/segments": "lamp.Segment"}


def _rgba(color: str, alpha: float = 1.0) -> dict[str, float]:
    from matplotlib.colors import to_rgb

    r, g, b = to_rgb(color)
    return {"r": r, "g": g, "b": b, "a": alpha}


def _stamp(t: float) -> dict[str, int]:
    ns = int(round(t * 1e9))
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _pose(x: float = 0.0, y: float = 0.0, theta: float = 0.0) -> dict[str, Any]:
    return {"position": {"x": float(x), "y": float(y), "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(theta / 2),
                            "w": math.cos(theta / 2)}}


def _points(xy: np.ndarray) -> list[dict[str, float]]:
    return [{"x": float(x), "y": float(y), "z": 0.0} for x, y in np.asarray(xy)[:, :2]]


def _line(kind: int, xy: np.ndarray, color: str, thickness: float,
          pose: dict[str, Any] | None = None) -> dict[str, Any]:
    """A foxglove LinePrimitive: kind 0 strip, 1 loop, 2 list."""
    return {"type": kind, "pose": pose or _pose(), "thickness": thickness,
            "scale_invariant": False, "points": _points(xy), "color": _rgba(color),
            "colors": [], "indices": []}


def _entity(t: float, ident: str, **prims: list[dict[str, Any]]) -> dict[str, Any]:
    e: dict[str, Any] = {"timestamp": _stamp(t), "frame_id": FRAME, "id": ident,
                         "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": False,
                         "metadata": []}
    for kind in ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts",
                 "models"):
        e[kind] = prims.get(kind, [])
    return e


def _static(recording: Recording) -> list[dict[str, Any]]:
    scene = recording.scene_model()
    W, H = scene.workspace
    thick = 0.004 * max(W, H)
    border = np.array([[0, 0], [W, 0], [W, H], [0, H]], float)
    out = [_entity(0.0, "workspace", lines=[_line(1, border, "black", thick)])]
    for j, o in enumerate(scene.obstacles):
        out.append(_entity(0.0, f"obstacle-{j}", lines=[
            _line(1, world_outline(o.shape, o.pose), OBSTACLE_COLOR, thick)]))
    for k, o in enumerate(scene.objects):
        out.append(_entity(0.0, f"goal-{k}", lines=[
            _line(1, world_outline(o.shape, o.goal), GOAL_COLOR, thick)]))
    return out


def _messages(recording: Recording):
    """(topic, log time [s], message dict) in time order."""
    a = recording.arrays
    scene = recording.scene_model()
    outlines = [local_outline(o.shape) for o in scene.objects]
    thick = 0.004 * max(scene.workspace)
    diameter = 2.0 * scene.robot_radius
    yield "/scene", 0.0, {"deletions": [], "entities": _static(recording)}
    last_plan, last_segment = None, -1
    for row in range(recording.n_rows):
        t = float(a["times"][row])
        g = recording.segment_of_row(row)
        if g != last_segment and g >= 0:
            yield "/segments", t, {
                "index": g, "object": int(a["segment_object"][g]),
                "planning_time_s": float(a["planning_time_s"][g]),
                "sim_time_s": float(a["sim_time_s"][g]),
                "drift": [float(v) for v in a["drift"][g]],
                "outcome": OUTCOMES[int(a["segment_outcome"][g])],
                "replanned": bool(a["segment_replanned"][g]),
                "contacts": recording.contacts_of(g).astype(float).tolist()}
            last_segment = g
        plan = int(a["segment_plan"][g]) if g >= 0 else -1
        if plan != last_plan:
            lines = [_line(0, recording.plan_path(plan), PATH_COLOR, 2 * thick)]
            for edges, color in ((recording.verified_of(plan), VERIFIED_COLOR),
                                 (recording.penalised_of(plan), PENALISED_COLOR)):
                if len(edges):
                    lines.append(_line(2, edges.reshape(-1, 2), color, thick))
            yield "/plan", t, {"deletions": [], "entities": [_entity(t, "plan", lines=lines)]}
            last_plan = plan
        robots = a["robots"][row].astype(float)
        poses = a["objects"][row].astype(float)
        spheres = [{"pose": _pose(x, y), "size": {"x": diameter, "y": diameter, "z": diameter},
                    "color": _rgba(ROBOT_COLOR)} for x, y in robots]
        entities = [_entity(t, "robots", spheres=spheres)]
        for k, (x, y, th) in enumerate(poses):
            entities.append(_entity(t, f"object-{k}", lines=[
                _line(1, outlines[k], object_color(k), 2 * thick, _pose(x, y, th))]))
        yield "/scene", t, {"deletions": [], "entities": entities}
        yield "/robots", t, {"time": t, "segment": g, "positions": robots.tolist()}
        yield "/objects", t, {"time": t, "segment": g, "poses": poses.tolist()}


def mcap_available() -> bool:
    import importlib.util

    return importlib.util.find_spec("mcap") is not None


def write_mcap(recording: Recording, path: str | Path) -> Path:
    """Write ``recording`` as MCAP to ``path`` atomically; returns the path."""
    if not mcap_available():
        raise RuntimeError(f"cannot write {str(path)!r}: MCAP needs the mcap package; "
                           "install it with `pip install 'lamp[foxglove]'`")
    from mcap.writer import Writer

    from lamp.io import atomic_output

    path = Path(path)
    with atomic_output(path, keep_suffix=True) as tmp, open(tmp, "wb") as f:
        writer = Writer(f)
        writer.start(profile="", library="lamp")
        schema_ids = {name: writer.register_schema(name, "jsonschema",
                                                   json.dumps(body).encode())
                      for name, body in SCHEMAS.items()}
        channels = {topic: writer.register_channel(topic, "json", schema_ids[schema])
                    for topic, schema in TOPICS.items()}
        sequence = dict.fromkeys(TOPICS, 0)
        for topic, t, message in _messages(recording):
            ns = int(round(t * 1e9))
            writer.add_message(channels[topic], log_time=ns, publish_time=ns,
                               data=json.dumps(message, separators=(",", ":")).encode(),
                               sequence=sequence[topic])
            sequence[topic] += 1
        writer.finish()
    return path
