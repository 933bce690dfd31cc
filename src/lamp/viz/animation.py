"""Animations of executed runs: a list of :class:`Frame` -> GIF (Pillow) or MP4 (imageio).

Planners record one ``Frame`` per rendered instant (robots, objects, the active object,
its planned path, the edges verified or penalised so far, a caption);
``write_animation`` draws them with :mod:`lamp.viz.scene_plot` on one small figure.

Speed: the figure is built once. The static layer (axes, border, obstacles, goal ticks)
is rendered once and saved; every frame restores it and draws only the changing artists
(objects, robots, outlines, path, edges, caption) with ``draw_artist`` (blitting), then
reads the RGB buffer. For a GIF each frame is mapped to one shared 256-colour palette as
soon as it is drawn, so memory stays at one byte per pixel per frame (360 x 360 px:
0.13 MB, 52 MB for 400 frames); MP4 frames are streamed to the encoder.
``python benchmarks/bench_viz.py`` measures seconds per frame.
"""

from __future__ import annotations

import importlib.util
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from lamp.scene.model import Scene
from lamp.viz.scene_plot import (
    GOAL_COLOR,
    OBJECT_COLORS,
    OBSTACLE_COLOR,
    ROBOT_COLOR,
    ScenePainter,
    atomic_output,
    new_figure,
)

VERIFIED_COLOR = "#2ca02c"
PENALISED_COLOR = "#d62728"
PATH_COLOR = "#ff9f1c"
Edge = tuple[tuple[float, float], tuple[float, float]]


@dataclass
class Frame:
    """One rendered instant of a run.

    ``robot_positions`` (N, 2) and ``object_poses`` (K, 3) are world-frame states;
    ``active_object`` is the index of the object being moved (highlighted) or None;
    ``planned_path`` (P, 3) the object path currently planned for it; ``verified_edges`` and
    ``penalised_edges`` object-level edges ((x, y), (x, y)) drawn green and red (extra
    coordinates per end point, e.g. theta, are ignored); ``caption`` a line of text.
    """

    robot_positions: ArrayLike
    object_poses: ArrayLike
    active_object: int | None = None
    planned_path: ArrayLike | None = None
    verified_edges: Sequence[Edge] = field(default_factory=list)
    penalised_edges: Sequence[Edge] = field(default_factory=list)
    caption: str = ""


@dataclass(frozen=True)
class AnimationStats:
    """What ``write_animation`` did: the file, frames written and where the time went."""

    path: Path
    frames_in: int
    frames_written: int
    render_s: float  # drawing + reading pixels + palette quantisation, all frames
    write_s: float  # encoding and writing the file

    @property
    def seconds_per_frame(self) -> float:
        return (self.render_s + self.write_s) / max(self.frames_written, 1)


def subsample_indices(n: int, max_frames: int) -> np.ndarray:
    """Indices of at most ``max_frames`` of ``n`` frames, evenly spread, first and last kept."""
    if max_frames < 1:
        raise ValueError(f"max_frames: must be >= 1, got {max_frames}")
    if n <= max_frames:
        return np.arange(n)
    if max_frames == 1:
        return np.array([n - 1])
    # Spacing (n-1)/(max_frames-1) > 1, so the rounded indices are distinct.
    return np.rint(np.linspace(0, n - 1, max_frames)).astype(int)


def _segments(edges: Sequence[Edge] | ArrayLike, what: str) -> np.ndarray:
    """Edges as an (E, 2, 2) array of (x, y) end points."""
    arr = np.asarray(edges, dtype=float)
    if arr.size == 0:
        return np.zeros((0, 2, 2))
    if arr.ndim != 3 or arr.shape[1] != 2 or arr.shape[2] < 2:
        raise ValueError(
            f"{what}: expected a list of ((x, y), (x, y)) edges, got shape {arr.shape}"
        )
    return arr[:, :, :2]


def _path_xy(path: ArrayLike | None, what: str) -> np.ndarray:
    if path is None:
        return np.zeros((0, 2))
    arr = np.asarray(path, dtype=float)
    if arr.ndim != 2 or arr.shape[1] < 2:
        raise ValueError(f"{what}: expected a (P, 3) array of poses, got shape {arr.shape}")
    return arr[:, :2]


def mp4_available() -> bool:
    """Whether imageio can write MP4 here (it needs the ``imageio-ffmpeg`` package)."""
    return importlib.util.find_spec("imageio_ffmpeg") is not None


class FrameRenderer:
    """Renders frames of one scene to RGB arrays on one reused figure (blitting)."""

    def __init__(self, scene: Scene, size_in: float = 4.5, dpi: float = 80) -> None:
        from matplotlib.collections import LineCollection

        self.scene = scene
        self.fig, self.ax = new_figure(scene, size_in, dpi)
        self.painter = ScenePainter(self.ax, scene)
        ax = self.ax
        (self.path_line,) = ax.plot([], [], color=PATH_COLOR, lw=1.6, zorder=3)
        self.verified = LineCollection([], colors=VERIFIED_COLOR, linewidths=1.2, zorder=3.5)
        self.penalised = LineCollection([], colors=PENALISED_COLOR, linewidths=1.2, zorder=3.5)
        ax.add_collection(self.verified)
        ax.add_collection(self.penalised)
        self.caption = self.fig.text(0.5, 0.985, "", ha="center", va="top", fontsize=8)
        self.fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.95))
        self.dynamic = [
            *self.painter.start_outlines,
            *self.painter.goal_outlines,
            self.path_line,
            self.verified,
            self.penalised,
            *self.painter.dynamic_artists,
        ]
        for a in (*self.dynamic, self.caption):
            a.set_animated(True)  # left out of canvas.draw(): drawn per frame instead
        canvas = self.fig.canvas
        canvas.draw()
        self.background = canvas.copy_from_bbox(self.fig.bbox)
        self._last_edges: tuple[int, int] = (0, 0)

    def render(self, frame: Frame, index: int = 0) -> np.ndarray:
        """The (H, W, 3) uint8 picture of ``frame``; ``index`` only names it in errors."""
        where = f"frames[{index}]"
        try:
            self.painter.update(frame.object_poses, frame.robot_positions, frame.active_object)
        except ValueError as exc:
            raise ValueError(f"{where}.{exc}") from None
        self.path_line.set_data(*_path_xy(frame.planned_path, f"{where}.planned_path").T)
        ids = (id(frame.verified_edges), id(frame.penalised_edges))
        if ids != self._last_edges:  # frames of one segment share their edge lists
            self.verified.set_segments(_segments(frame.verified_edges, f"{where}.verified_edges"))
            self.penalised.set_segments(
                _segments(frame.penalised_edges, f"{where}.penalised_edges")
            )
            self._last_edges = ids
        self.caption.set_text(frame.caption)
        canvas = self.fig.canvas
        canvas.restore_region(self.background)
        for a in self.dynamic:
            self.ax.draw_artist(a)
        self.fig.draw_artist(self.caption)
        return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def write_animation(
    scene: Scene,
    frames: Sequence[Frame],
    path: str | Path,
    fps: float = 15,
    max_frames: int = 400,
    *,
    size_in: float = 4.5,
    dpi: float = 80,
) -> AnimationStats:
    """Render ``frames`` of ``scene`` and write them to ``path`` (``.gif``, or ``.mp4`` when
    the ``imageio-ffmpeg`` package is installed); returns :class:`AnimationStats`.

    More than ``max_frames`` frames are subsampled evenly (first and last kept). The file is
    written atomically: a temporary file in the same folder, then ``os.replace``.
    Consecutive identical frames may be merged by the GIF encoder (the duration is kept).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"path: expected a .gif or .mp4 file name, got {str(path)!r}")
    if suffix == ".mp4" and not mp4_available():
        raise RuntimeError(
            f"cannot write {str(path)!r}: MP4 needs an ffmpeg writer for imageio; "
            "install it with `pip install imageio-ffmpeg`, or write a .gif"
        )
    if not fps > 0:
        raise ValueError(f"fps: must be > 0, got {fps}")
    if len(frames) == 0:
        raise ValueError("frames: nothing to render (empty list)")
    chosen = subsample_indices(len(frames), max_frames)
    renderer = FrameRenderer(scene, size_in, dpi)
    render_s = write_s = 0.0
    with atomic_output(path) as tmp:
        if suffix == ".gif":
            render_s, write_s = _write_gif(renderer, frames, chosen, tmp, fps)
        else:
            render_s, write_s = _write_mp4(renderer, frames, chosen, tmp, fps)
    return AnimationStats(path, len(frames), len(chosen), render_s, write_s)


def palette_image(first: np.ndarray, extra: Sequence[str] = ()) -> Any:
    """One 256-colour palette for a whole GIF (a PIL image to ``quantize`` each frame
    with): the first frame ``first`` (H, W, 3 ``uint8``) plus swatches of every colour the
    frames may show later (objects, robots, path, edges, and ``extra``), so that no later
    frame's colours shift. The animation and the recording replay share it."""
    from matplotlib.colors import to_rgb
    from PIL import Image

    colors = [
        *OBJECT_COLORS,
        ROBOT_COLOR,
        GOAL_COLOR,
        OBSTACLE_COLOR,
        PATH_COLOR,
        VERIFIED_COLOR,
        PENALISED_COLOR,
        "black",
        "white",
        *extra,
    ]
    rgb = np.array([to_rgb(c) for c in colors])
    # each colour pure and half-blended with white (anti-aliased edges), 8 px per swatch
    swatch = np.concatenate([rgb, 0.5 + 0.5 * rgb]) * 255.0
    strip = np.repeat(np.repeat(swatch[None, :, :], 8, axis=0), 8, axis=1).astype(np.uint8)
    canvas = np.zeros((first.shape[0] + 8, max(first.shape[1], strip.shape[1]), 3), np.uint8)
    canvas[: first.shape[0], : first.shape[1]] = first
    canvas[first.shape[0] :, : strip.shape[1]] = strip
    return Image.fromarray(canvas).quantize(colors=256, method=Image.Quantize.FASTOCTREE)


def _write_gif(
    renderer: FrameRenderer, frames: Sequence[Frame], chosen: np.ndarray, tmp: Path, fps: float
) -> tuple[float, float]:
    """GIF through Pillow (imageio's own GIF back end), with one shared palette.

    Going through ``imageio.v3.imwrite`` instead costs 25-70 ms per frame more: its
    Pillow plugin re-quantises every frame (median cut) or remaps a given palette in Python.
    Mapping to a fixed palette costs about 1 ms per frame and keeps colours flat.
    """
    from PIL import Image

    render_s = 0.0
    images = []
    palette = None
    for i in chosen:
        t0 = time.perf_counter()
        rgb = renderer.render(frames[int(i)], int(i))
        if palette is None:
            palette = palette_image(rgb)
        images.append(Image.fromarray(rgb).quantize(palette=palette, dither=Image.Dither.NONE))
        render_s += time.perf_counter() - t0
    t0 = time.perf_counter()
    images[0].save(
        tmp,
        format="GIF",
        save_all=True,
        append_images=images[1:],
        duration=1000.0 / fps,
        loop=0,
        optimize=False,
    )
    return render_s, time.perf_counter() - t0


def _write_mp4(
    renderer: FrameRenderer, frames: Sequence[Frame], chosen: np.ndarray, tmp: Path, fps: float
) -> tuple[float, float]:
    import imageio.v2 as iio2

    render_s = write_s = 0.0
    writer: Any = iio2.get_writer(tmp, format="FFMPEG", mode="I", fps=fps, macro_block_size=1)
    try:
        for i in chosen:
            t0 = time.perf_counter()
            rgb = renderer.render(frames[int(i)], int(i))
            h, w = (rgb.shape[0] // 2) * 2, (rgb.shape[1] // 2) * 2  # H.264 wants even sizes
            t1 = time.perf_counter()
            writer.append_data(np.ascontiguousarray(rgb[:h, :w]))
            render_s += t1 - t0
            write_s += time.perf_counter() - t1
    finally:
        t0 = time.perf_counter()
        writer.close()
        write_s += time.perf_counter() - t0
    return render_s, write_s
