"""The HTML replay viewer: one self-contained file (inline CSS, script and data, no network).

``write_html(recording, path)`` fills ``lamp/viz/viewer/viewer.html`` with the viewer's
stylesheet and script and the recording as JSON: trajectories as base64 of their
little-endian float arrays (the recording's own values, bit for bit), shapes, plans and
per-segment events as plain lists. The page draws on a canvas with play / pause / scrub /
speed, layer toggles, zoom and pan, and a side panel of per-segment timings and events;
after every draw it mirrors what it shows (row, segment, time, robot and object
positions) in the data attributes of ``#state``.
"""

from __future__ import annotations

import base64
import html
import json
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from lamp.geometry.shapes import half_extents, local_outline, world_outline
from lamp.io import write_text_atomic
from lamp.record.format import FORMAT, OUTCOMES, Recording
from lamp.scene.model import Circle
from lamp.viz.animation import PATH_COLOR, PENALISED_COLOR, VERIFIED_COLOR
from lamp.viz.replay_options import CONTACT_COLOR, TRAIL_COLOR, RenderOptions, outcome_text
from lamp.viz.scene_plot import GOAL_COLOR, OBSTACLE_COLOR, ROBOT_COLOR, object_color

#: Placeholders of a self-contained page (the viewer's, ``lamp serve``'s live page) that
#: :func:`inline_page` replaces, in this order.
PLACEHOLDERS = ("__LAMP_TITLE__", "__LAMP_CSS__", "__LAMP_JS__", "__LAMP_DATA__")


def _b64(arr: np.ndarray, dtype: str) -> str:
    return base64.b64encode(np.ascontiguousarray(arr, dtype=np.dtype(dtype).newbyteorder("<"))
                            .tobytes()).decode("ascii")


def shape_payload(shape: Any, pose: Any | None) -> dict[str, Any]:
    """A circle as its radius (plus its centre ``at`` for an obstacle), anything else as its
    outline: world frame for an obstacle (``pose`` given), the shape's own frame otherwise."""
    if isinstance(shape, Circle):
        d: dict[str, Any] = {"circle": float(shape.radius)}
        if pose is not None:
            d["at"] = [float(pose[0]), float(pose[1]), 0.0]
        return d
    pts = local_outline(shape) if pose is None else world_outline(shape, pose)
    return {"outline": np.asarray(pts, float).round(6).tolist()}


def payload(recording: Recording, options: RenderOptions | None = None) -> dict[str, Any]:
    """The JSON object the viewer reads (see the module docstring)."""
    opt = options or RenderOptions()
    scene = recording.scene_model()
    a = recording.arrays
    obstacles = [shape_payload(o.shape, o.pose) for o in scene.obstacles]
    objects = [{**shape_payload(o.shape, None), "color": object_color(k),
                "start": [float(v) for v in o.start], "goal": [float(v) for v in o.goal],
                "tick": float(half_extents(o.shape)[0])} for k, o in enumerate(scene.objects)]
    segments = []
    for g in range(recording.n_segments):
        segments.append({
            "object": int(a["segment_object"][g]),
            "plan": int(a["segment_plan"][g]),
            "outcome": OUTCOMES[int(a["segment_outcome"][g])],
            "replanned": bool(a["segment_replanned"][g]),
            "planning_s": float(a["planning_time_s"][g]),
            "sim_s": float(a["sim_time_s"][g]),
            "drift": [float(v) for v in a["drift"][g]],
            "contacts": recording.contacts_of(g).tolist(),
            "pushes": [p.tolist() for p in recording.pushes_of(g)],
        })
    plans = [{"object": int(a["plan_object"][i]),
              "path": recording.plan_path(i)[:, :2].tolist(),
              "verified": recording.verified_of(i).tolist(),
              "penalised": recording.penalised_of(i).tolist()}
             for i in range(len(a["plan_object"]))]
    result = recording.result
    return {
        "format": FORMAT,
        "title": f"{scene.name} - {recording.planner} (seed {recording.seed})",
        "planner": recording.planner,
        "seed": int(recording.seed),
        "outcome": outcome_text(recording),
        "success": recording.success,
        "result": {k: result.get(k, 0) for k in ("total_planning_time_s", "wall_time_s",
                                                  "replans", "makespan")},
        "workspace": [float(v) for v in scene.workspace],
        "robot_radius": float(scene.robot_radius),
        "n_robots": int(scene.n_robots),
        "n_objects": len(scene.objects),
        "n_rows": recording.n_rows,
        "row_dt_s": float(recording.row_dt_s),
        "trail_s": float(opt.trail_s),
        "min_robot_px": float(opt.min_robot_px),
        "obstacles": obstacles,
        "objects": objects,
        "colors": {"robot": ROBOT_COLOR, "goal": GOAL_COLOR, "obstacle": OBSTACLE_COLOR,
                   "inflated": "rgba(69, 69, 69, 0.28)", "path": PATH_COLOR,
                   "verified": VERIFIED_COLOR, "penalised": PENALISED_COLOR,
                   "trail": TRAIL_COLOR, "contact": CONTACT_COLOR},
        "times": _b64(a["times"], "float64"),
        "robots": _b64(a["robots"], "float32"),
        "object_poses": _b64(a["objects"], "float32"),
        "segment_rows": [int(v) for v in a["segment_rows"]],
        "robot_team": _b64(a["robot_team"], "int16") if "robot_team" in a else None,
        "segments": segments,
        "plans": plans,
        "tasks": [{k: t[k] for k in ("id", "object", "goal", "release_s", "start_s", "done_s",
                                     "status")} for t in result["tasks"]]
        if result.get("tasks") else None,
    }


def _asset(name: str) -> str:
    return (resources.files("lamp.viz") / "viewer" / name).read_text(encoding="utf-8")


def inline_page(template: str, title: str, css: str, js: str, data: Any,
                script: str) -> str:
    """``template`` (a page with the ``PLACEHOLDERS``) with ``title`` (escaped), ``css``,
    ``js`` and ``data`` (as JSON) inlined: no external reference. Each placeholder is
    replaced once, in order, the data last (nothing in it is read as a placeholder);
    inside ``<script>`` only ``</`` could end the element early, so the data's are
    written ``<\\/`` (valid JSON) and a script ``script`` containing ``</script`` is
    refused (RuntimeError)."""
    if "</script" in js.lower():
        raise RuntimeError(f"{script} must not contain '</script' (it is inlined)")
    text = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    parts = {"__LAMP_TITLE__": html.escape(title), "__LAMP_CSS__": css, "__LAMP_JS__": js,
             "__LAMP_DATA__": text}
    page = template
    for key in PLACEHOLDERS:
        page = page.replace(key, parts[key], 1)
    return page


def viewer_html(recording: Recording, options: RenderOptions | None = None) -> str:
    """The viewer page for ``recording``: no external reference (no src=, href= or url())."""
    return inline_page(_asset("viewer.html"), f"LAMP replay - {recording.planner}",
                       _asset("viewer.css"), _asset("viewer.js"),
                       payload(recording, options), "viewer.js")


def write_html(recording: Recording, path: str | Path,
               options: RenderOptions | None = None) -> Path:
    """Write the viewer page of ``recording`` to ``path`` atomically; returns the path."""
    write_text_atomic(path, viewer_html(recording, options))
    return Path(path)
