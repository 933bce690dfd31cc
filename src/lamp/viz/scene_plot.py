"""Drawing scenes with matplotlib: workspace, obstacles, robots, objects with start and goal
(a lifelong scene's task goals dotted, each labelled with its object).

``draw_scene`` draws onto any Axes and returns a :class:`ScenePainter` whose ``update``
moves the robots and objects in place; ``lamp.viz.animation`` reuses it to render many
frames on one figure. ``save_scene_png`` writes the picture ``lamp show`` produces.

matplotlib is imported inside the functions, so ``import lamp`` stays light; figures are
built on the Agg canvas directly (no pyplot, no global state, no display needed).

Colours: obstacles dark grey, robots blue disks, object k a colour of its own (filled at
its current pose, dashed outline at its start), every goal a green outline labelled with
the object's index (when there is more than one object). A short line
from an object's centre along its own +x axis (a "heading tick") shows its orientation.
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import AbstractContextManager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry.shapes import half_extents, world_outline
from lamp.io import atomic_output as _atomic_output
from lamp.scene.model import Circle, Scene, Shape

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

OBSTACLE_COLOR = "#454545"
ROBOT_COLOR = "#1f5fd6"
GOAL_COLOR = "#1a9e3a"
BORDER_COLOR = "black"
# Object colours avoid the robot blue and the goal green.
OBJECT_COLORS = (
    "#ff7f0e",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#bcbd22",
    "#17becf",
    "#f2c12e",
    "#7f3c8d",
    "#e68310",
)


def object_color(k: int) -> str:
    """The colour of object ``k`` (cycles after ``len(OBJECT_COLORS)`` objects)."""
    return OBJECT_COLORS[k % len(OBJECT_COLORS)]


def _check_array(name: str, value: ArrayLike, shape: tuple[int, int]) -> np.ndarray:
    """``value`` as a float array of exactly ``shape``; ValueError naming ``name`` otherwise."""
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise ValueError(f"{name}: expected shape {shape}, got {arr.shape}")
    return arr


def _patch(shape: Shape, pose: ArrayLike, **style: Any):
    """A matplotlib patch of ``shape`` at ``pose`` (exact circle, polygon otherwise)."""
    from matplotlib.patches import Circle as CirclePatch
    from matplotlib.patches import Polygon as PolygonPatch

    pose = np.asarray(pose, dtype=float)
    if isinstance(shape, Circle):
        return CirclePatch((pose[0], pose[1]), shape.radius, **style)
    return PolygonPatch(world_outline(shape, pose), closed=True, **style)


def _move_patch(patch: Any, shape: Shape, pose: np.ndarray) -> None:
    if isinstance(shape, Circle):
        patch.set_center((pose[0], pose[1]))
    else:
        patch.set_xy(world_outline(shape, pose))


def _tick_xy(length: float, pose: np.ndarray) -> tuple[list[float], list[float]]:
    """End points of the heading tick: from the centre along the object's +x axis."""
    x, y, th = pose
    return [x, x + length * np.cos(th)], [y, y + length * np.sin(th)]


class ScenePainter:
    """The artists of one scene on one Axes.

    The static layer (border, obstacles, start and goal outlines) is drawn once; ``update``
    moves the robots and objects and restyles the highlighted object, so an animation can
    redraw one figure frame after frame instead of rebuilding it.
    """

    def __init__(self, ax: Axes, scene: Scene) -> None:
        from matplotlib.collections import PatchCollection
        from matplotlib.patches import Rectangle as RectanglePatch

        self.ax = ax
        self.scene = scene
        W, H = scene.workspace
        margin = 0.02 * max(W, H)
        ax.set_xlim(-margin, W + margin)
        ax.set_ylim(-margin, H + margin)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
        ax.add_patch(
            RectanglePatch((0.0, 0.0), W, H, fill=False, lw=1.5, ec=BORDER_COLOR, zorder=1)
        )
        if scene.obstacles:
            ax.add_collection(
                PatchCollection(
                    [_patch(o.shape, o.pose) for o in scene.obstacles],
                    facecolor=OBSTACLE_COLOR,
                    edgecolor=OBSTACLE_COLOR,
                    zorder=1,
                )
            )
        self._ticks_len = [half_extents(o.shape)[0] for o in scene.objects]
        for t in scene.tasks:  # a lifelong scene's later goals: dotted, with their object
            ax.add_patch(_patch(scene.objects[t.object].shape, t.goal, fill=False,
                                ec=GOAL_COLOR, ls=":", lw=1.0, zorder=2))
            ax.text(t.goal[0], t.goal[1], str(t.object), color=object_color(t.object),
                    fontsize=6, ha="left", va="bottom", zorder=3)
        self.start_outlines = []
        self.goal_outlines = []
        self.objects = []
        self.object_ticks = []
        for k, o in enumerate(scene.objects):
            c = object_color(k)
            self.start_outlines.append(
                ax.add_patch(_patch(o.shape, o.start, fill=False, ec=c, ls="--", lw=1.0, zorder=2))
            )
            self.goal_outlines.append(
                ax.add_patch(_patch(o.shape, o.goal, fill=False, ec=GOAL_COLOR, lw=1.4, zorder=2))
            )
            ax.plot(*_tick_xy(self._ticks_len[k], np.asarray(o.goal)), color=GOAL_COLOR, lw=1.2,
                    zorder=2)  # fmt: skip
            if len(scene.objects) > 1:  # which goal is whose: the object's index, in its colour
                ax.text(o.goal[0], o.goal[1], str(k), color=c, fontsize=7, fontweight="bold",
                        ha="right", va="top", zorder=3)  # fmt: skip
            self.objects.append(
                ax.add_patch(
                    _patch(o.shape, o.start, fc=c, ec="black", lw=0.6, alpha=0.85, zorder=4)
                )
            )
            (tick,) = ax.plot(*_tick_xy(self._ticks_len[k], np.asarray(o.start)), color="black",
                              lw=1.2, zorder=6)  # fmt: skip
            self.object_ticks.append(tick)
        self.robots = [
            ax.add_patch(
                _patch(
                    Circle(scene.robot_radius),
                    (*p, 0.0),
                    fc=ROBOT_COLOR,
                    ec="white",
                    lw=0.5,
                    zorder=5,
                )
            )  # fmt: skip
            for p in scene.robot_starts
        ]

    @property
    def dynamic_artists(self) -> list[Any]:
        """Artists that ``update`` may change (for blitting)."""
        return [*self.objects, *self.object_ticks, *self.robots]

    def update(
        self,
        object_poses: ArrayLike | None = None,
        robot_positions: ArrayLike | None = None,
        highlight_object: int | None = None,
        robot_team: ArrayLike | None = None,
    ) -> None:
        """Move objects to ``object_poses`` (K, 3) and robots to ``robot_positions`` (N, 2);
        ``None`` means the scene's start poses. ``highlight_object`` draws that object, its
        start and goal with a heavy outline. ``robot_team`` (N,): the object whose
        sub-team each robot is in (-1: none); a robot in one takes its object's colour."""
        scene = self.scene
        K, N = len(scene.objects), scene.n_robots
        poses = (
            scene.object_starts()
            if object_poses is None
            else _check_array("object_poses", object_poses, (K, 3))
        )
        robots = (
            scene.robot_starts_array
            if robot_positions is None
            else _check_array("robot_positions", robot_positions, (N, 2))
        )
        if highlight_object is not None and not (0 <= int(highlight_object) < K):
            raise ValueError(
                f"highlight_object: expected an index in [0, {K}), got {highlight_object}"
            )
        for k, o in enumerate(scene.objects):
            _move_patch(self.objects[k], o.shape, poses[k])
            self.object_ticks[k].set_data(*_tick_xy(self._ticks_len[k], poses[k]))
            on = highlight_object is not None and k == int(highlight_object)
            self.objects[k].set_linewidth(2.2 if on else 0.6)
            self.start_outlines[k].set_linewidth(2.0 if on else 1.0)
            self.goal_outlines[k].set_linewidth(2.4 if on else 1.4)
        for i, (patch, p) in enumerate(zip(self.robots, robots, strict=True)):
            patch.set_center((p[0], p[1]))
            team = -1 if robot_team is None else int(robot_team[i])
            patch.set_facecolor(object_color(team) if 0 <= team < K else ROBOT_COLOR)
            patch.set_edgecolor("black" if 0 <= team < K else "white")


def draw_scene(
    ax: Axes,
    scene: Scene,
    object_poses: ArrayLike | None = None,
    robot_positions: ArrayLike | None = None,
    *,
    highlight_object: int | None = None,
) -> ScenePainter:
    """Draw ``scene`` on ``ax``: workspace border, obstacles (dark grey), robots (blue disks),
    each object filled at its current pose with a heading tick, its start (dashed) and its
    goal (green outline and tick).

    ``object_poses`` (K, 3) and ``robot_positions`` (N, 2) default to the start poses.
    Returns the :class:`ScenePainter`, whose ``update`` moves things for the next frame.
    """
    painter = ScenePainter(ax, scene)
    painter.update(object_poses, robot_positions, highlight_object)
    return painter


def new_figure(scene: Scene, size_in: float, dpi: float) -> tuple[Figure, Axes]:
    """An Agg figure whose longer side is ``size_in`` inches, shaped like the workspace."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    W, H = scene.workspace
    aspect = H / W
    w, h = (
        (size_in, max(size_in * aspect, 1.5))
        if aspect <= 1
        else (max(size_in / aspect, 1.5), size_in)
    )
    fig = Figure(figsize=(w, h), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def atomic_output(path: str | Path) -> AbstractContextManager[Path]:
    """Yield a temporary path beside ``path`` (same suffix); on success it replaces ``path``
    atomically (``os.replace``), on error it is removed. Creates missing parent folders.
    (``lamp.io.atomic_output`` with the suffix kept, so Matplotlib and imageio see the
    format.)"""
    return _atomic_output(path, keep_suffix=True)


def _legend(fig: Figure) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: Sequence[Any] = [
        Patch(fc=OBSTACLE_COLOR, label="obstacle"),
        Line2D([], [], marker="o", ls="", mfc=ROBOT_COLOR, mec=ROBOT_COLOR, label="robot"),
        Patch(fill=False, ec="black", ls="--", label="object start"),
        Patch(fill=False, ec=GOAL_COLOR, lw=1.4, label="goal"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=7, frameon=False)


#: Formats ``save_scene_image`` writes, by file extension.
SCENE_IMAGE_FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}


def image_format_of(path: str | Path) -> str:
    """The :data:`SCENE_IMAGE_FORMATS` format of ``path``'s extension; ``ValueError``
    naming the path for any other extension."""
    path = Path(path)
    fmt = SCENE_IMAGE_FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ValueError(f"{path}: unsupported image extension {path.suffix!r}; expected "
                         f"one of {', '.join(SCENE_IMAGE_FORMATS)}")
    return fmt


def save_scene_png(scene: Scene, path: str | Path, dpi: int = 120) -> Path:
    """Write a PNG of ``scene`` at its start state, titled with the scene name; returns the path.

    The picture is 6 inches on its longer side at ``dpi`` dots per inch; the file is written
    atomically (a reader never sees half a PNG).
    """
    return save_scene_image(scene, path, dpi, fmt="png")


def save_scene_image(scene: Scene, path: str | Path, dpi: int = 120,
                     fmt: str | None = None) -> Path:
    """As :func:`save_scene_png`, in the format of ``path``'s extension (PNG, SVG or PDF)
    unless ``fmt`` names one; ``ValueError`` for any other extension, before drawing."""
    path = Path(path)
    if fmt is None:
        fmt = image_format_of(path)
    if dpi <= 0:
        raise ValueError(f"dpi: must be > 0, got {dpi}")
    fig, ax = new_figure(scene, 6.0, dpi)
    draw_scene(ax, scene)
    ax.set_title(scene.name, fontsize=10)
    _legend(fig)
    fig.tight_layout(rect=(0.0, 0.05, 1.0, 1.0))
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=dpi)
    return path
