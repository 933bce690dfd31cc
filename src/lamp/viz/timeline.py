"""Where a fleet's time went: one bar per robot over simulated time, coloured by the object
its sub-team pushes, drawn from a recording (``lamp timeline RUN_DIR --out FILE``).

Each robot's recorded samples split into spans (:func:`robot_spans`):

- *moving* for object k: in k's sub-team, and faster than ``MOVING_FRACTION`` of the
  robot speed between two samples (driving to the object, or pushing it);
- *holding* for k: in k's sub-team, standing (its segment waits for another sub-team's,
  it holds while its teammates move, or its loop settles);
- *idle*: in no sub-team (``robot_team`` -1; a sequential recording puts every robot in
  the team of the object being moved).

The interval between samples ``j`` and ``j + 1`` takes sample ``j + 1``'s sub-team.
Objects' placement times (``stats.fleet.placed_at_s`` of the recorded result; else the
end of each placed object's last segment) are marked with their index; in a lifelong run,
every task's completion is, and its release is a triangle at the top.

Guarantee (``tests/test_timeline.py``): a robot's spans tile ``[times[0], times[-1]]``
without gap or overlap, and every sample interval of positive length lies in the span of
its own kind.

matplotlib is imported inside the functions (``import lamp`` stays light); the figure is
built on the Agg canvas (no pyplot, no display).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from lamp.viz.scene_plot import atomic_output, image_format_of, object_color

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from lamp.record.format import Recording

__all__ = ["IDLE", "MOVING_FRACTION", "Span", "placement_times", "robot_spans",
           "save_timeline", "timeline_figure"]

#: A robot moves when faster than this share of the robot speed between two samples.
MOVING_FRACTION = 0.1
#: The ``object`` of an idle span.
IDLE = -1
IDLE_COLOR = "#e4e4e4"
HOLD_ALPHA = 0.3


@dataclass(frozen=True)
class Span:
    """A stretch ``[start, end)`` of simulated time in which a robot did one thing: moved
    for ``object`` (``moving``), held for it, or was idle (``object`` == ``IDLE``)."""

    start: float
    end: float
    object: int
    moving: bool


def robot_spans(times: np.ndarray, positions: np.ndarray, team: np.ndarray,
                speed: float) -> list[list[Span]]:
    """The spans of every robot (see the module docstring) from samples ``times`` (S,),
    robot ``positions`` (S, N, 2) and ``team`` (S, N) (the object of each robot's
    sub-team, -1 none), robots driving at ``speed`` m/s."""
    times = np.asarray(times, float)
    positions = np.asarray(positions, float)
    team = np.asarray(team, np.int64)
    n = positions.shape[1]
    if len(times) < 2:
        return [[] for _ in range(n)]
    dt = np.diff(times)
    keep = dt > 0
    step = np.hypot(*np.moveaxis(np.diff(positions, axis=0), -1, 0))  # (S-1, N)
    fast = step > MOVING_FRACTION * speed * dt[:, None]
    owner = team[1:]
    moving = fast & (owner >= 0)
    owner = np.where(owner >= 0, owner, IDLE)
    starts, ends = times[:-1][keep], times[1:][keep]
    out = []
    for i in range(n):
        who, mov = owner[keep, i], moving[keep, i]
        if len(who) == 0:
            out.append([])
            continue
        cut = np.flatnonzero((np.diff(who) != 0) | (np.diff(mov) != 0)) + 1
        first = np.r_[0, cut]
        last = np.r_[cut, len(who)] - 1
        out.append([Span(float(starts[a]), float(ends[b]), int(who[a]), bool(mov[a]))
                    for a, b in zip(first, last, strict=True)])
    return out


def placement_times(recording: Recording) -> dict[int, float]:
    """Object -> simulated time it was placed: the recorded result's
    ``stats.fleet.placed_at_s`` when it has them, else the end of each placed object's
    last segment."""
    result = recording.result
    placed = ((result.get("stats") or {}).get("fleet") or {}).get("placed_at_s")
    if placed is not None:
        return {k: float(t) for k, t in enumerate(placed) if t is not None}
    a = recording.arrays
    rows, objs, times = a["segment_rows"], a["segment_object"], a["times"]
    ok = [bool(o.get("success")) for o in result.get("objects", [])]
    out: dict[int, float] = {}
    for g, k in enumerate(objs):
        if int(k) < len(ok) and ok[int(k)]:
            out[int(k)] = float(times[rows[g + 1]])
    return out


def _title(recording: Recording) -> str:
    r = recording.result
    parts = [str(recording.scene.get("name", "run")), str(recording.planner)]
    if r.get("makespan_s") is not None:
        parts.append(f"makespan {float(r['makespan_s']):.1f} s")
    share = ((r.get("stats") or {}).get("fleet") or {}).get("utilisation")
    if share:
        parts.append(" ".join(f"{k} {100 * float(share[k]):.0f}%"
                              for k in ("working", "waiting", "idle") if k in share))
    return "  ·  ".join(parts)


def timeline_figure(recording: Recording, width_in: float = 10.0, dpi: float = 120) -> Figure:
    """The timeline of ``recording`` (see the module docstring) on a new Agg figure."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from lamp.record.safety import recorded_teams

    scene = recording.scene_model()
    a = recording.arrays
    spans = robot_spans(a["times"], a["robots"], recorded_teams(recording),
                        float(scene.physics.robot_speed))
    n = len(spans)
    height = min(14.0, 1.6 + 0.24 * n)
    fig = Figure(figsize=(width_in, height), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for i, row in enumerate(spans):  # one collection per robot and kind
        kinds: dict[tuple[int, bool], list[tuple[float, float]]] = {}
        for s in row:
            kinds.setdefault((s.object, s.moving), []).append((s.start, s.end - s.start))
        for (k, moving), ranges in kinds.items():
            ax.broken_barh(ranges, (i - 0.4, 0.8), linewidth=0,
                           facecolors=IDLE_COLOR if k == IDLE else object_color(k),
                           alpha=1.0 if moving or k == IDLE else HOLD_ALPHA)
    tasks = recording.result.get("tasks")
    done = ([(int(t["object"]), float(t["done_s"])) for t in tasks if t["status"] == "done"]
            if tasks else sorted(placement_times(recording).items()))
    for k, t in done:
        ax.axvline(t, color=object_color(k), lw=1.0, ls="--")
        ax.annotate(f"{k}", (t, 1.0), xycoords=("data", "axes fraction"), ha="center",
                    va="bottom", fontsize=7, color=object_color(k))
    for t in tasks or ():  # releases: a triangle under the top edge, the object's colour
        ax.plot([float(t["release_s"])], [0.985], marker="v", ms=5, ls="none",
                color=object_color(int(t["object"])), transform=ax.get_xaxis_transform())
    ax.set_ylim(-0.6, n - 0.4)
    ax.invert_yaxis()
    ax.set_xlim(float(a["times"][0]), float(a["times"][-1]))
    ax.set_xlabel("simulated time (s); dashed: object k placed"
                  + ("; triangles: tasks released" if tasks else ""))
    ax.set_ylabel("robot")
    if n <= 40:
        ax.set_yticks(range(n))
        ax.tick_params(axis="y", labelsize=7)
    ax.set_title(_title(recording), fontsize=9, pad=14)
    fig.legend(handles=[Patch(color="#777777", label="moving (colour: its object)"),
                        Patch(color="#777777", alpha=HOLD_ALPHA,
                              label="holding in its sub-team"),
                        Patch(color=IDLE_COLOR, label="idle (no sub-team)")],
               loc="lower center", ncol=3, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0.0, 0.3 / height, 1.0, 1.0))
    return fig


def save_timeline(recording: Recording, path: str | Path, width_in: float = 10.0,
                  dpi: float = 120) -> Path:
    """Write :func:`timeline_figure` to ``path`` (PNG, SVG or PDF by its extension;
    ``ValueError`` for another, before drawing), atomically; returns the path."""
    path = Path(path)
    fmt = image_format_of(path)
    if not width_in > 0:
        raise ValueError(f"width: must be > 0, got {width_in}")
    fig = timeline_figure(recording, width_in, dpi)
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=dpi)
    return path
