"""Pictures of recorded runs: GIF, MP4 and PNG frames drawn from a ``lamp.record.Recording``.

``render(recording, path)`` picks the output from the file name (``.gif``, ``.mp4``,
``.png``, ``.html``; HTML is ``lamp.viz.replay_html``). Raster frames show the scene
(``lamp.viz.scene_plot``), the object path planned at that moment (orange), the edges
verified (green) and penalised (red) so far, the current segment's contacts (black
crosses) and push paths, every robot's trail over the last ``trail_s`` simulated seconds,
a legend, and a caption with the planner, outcome, simulated time and segment counter.

Frames are taken at ``fps`` per video second, each showing the last recorded row at or
before its simulated time ``j * speed / fps``, then the final state is held for one second.
Robots are drawn at least ``min_robot_px`` pixels in radius, so they stay visible on large
maps; ``follow`` (metres) turns on a camera that frames that much around the moved object.
The output is a pure function of the recording and the options (same file, same pixels),
so a live run and a later ``lamp render`` of its recording draw the same frames.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lamp.record.format import OUTCOMES, Recording
from lamp.viz.animation import PATH_COLOR, PENALISED_COLOR, VERIFIED_COLOR, mp4_available
from lamp.viz.replay_options import (
    AUTO_SECONDS,
    CONTACT_COLOR,
    TRAIL_COLOR,
    RenderOptions,
    outcome_text,
)
from lamp.viz.scene_plot import (
    GOAL_COLOR,
    OBSTACLE_COLOR,
    ROBOT_COLOR,
    ScenePainter,
    atomic_output,
    new_figure,
)

#: Dots per inch of the raster figures; ``size`` pixels = ``size / DPI`` inches.
DPI = 100
#: Suffixes ``render`` writes.
SUFFIXES = (".gif", ".mp4", ".png", ".html", ".mcap")


def frame_rows(recording: Recording, options: RenderOptions) -> np.ndarray:
    """Row index of every video frame (see the module docstring); never empty."""
    times = recording.arrays["times"]
    end = float(times[-1])
    speed = options.speed or max(1.0, end / AUTO_SECONDS)
    n = int(math.floor(end * options.fps / speed + 1e-9)) + 1
    t = np.arange(n) * (speed / options.fps)
    rows = np.clip(np.searchsorted(times, t + 1e-9, side="right") - 1, 0, len(times) - 1)
    hold = np.full(max(1, int(round(options.fps))), len(times) - 1)
    return np.concatenate([rows, hold]).astype(int)


def still_row(recording: Recording, at: int | None) -> int:
    """The row a PNG shows: the end of segment ``at`` (None: the last row)."""
    if at is None:
        return recording.n_rows - 1
    if not 0 <= at < recording.n_segments:
        raise ValueError(f"at: segment {at} does not exist (the run has "
                         f"{recording.n_segments} segments: 0..{recording.n_segments - 1})")
    return int(recording.arrays["segment_rows"][at + 1])


class ReplayRenderer:
    """Draws frames of one recording on one reused figure (blitting unless following)."""

    def __init__(self, recording: Recording, options: RenderOptions) -> None:
        from matplotlib.collections import LineCollection
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch

        self.rec, self.opt = recording, options
        self.scene = recording.scene_model()
        self.fig, self.ax = new_figure(self.scene, options.size / DPI, DPI)
        ax = self.ax
        self.painter = ScenePainter(ax, self.scene)
        (self.path_line,) = ax.plot([], [], color=PATH_COLOR, lw=3.2, alpha=0.8, zorder=3)
        self.verified = LineCollection([], colors=VERIFIED_COLOR, linewidths=1.2, zorder=3.5)
        self.penalised = LineCollection([], colors=PENALISED_COLOR, linewidths=1.2, zorder=3.5)
        self.trails = LineCollection([], colors=TRAIL_COLOR, linewidths=1.0, zorder=3.2)
        self.pushes = LineCollection([], colors=CONTACT_COLOR, linewidths=0.6, linestyles=":",
                                     zorder=3.6)
        for c in (self.verified, self.penalised, self.trails, self.pushes):
            ax.add_collection(c)
        (self.contacts,) = ax.plot([], [], ls="", marker="x", ms=5, mew=1.2,
                                   color=CONTACT_COLOR, zorder=6)
        self.title = self.fig.text(0.5, 0.995, "", ha="center", va="top", fontsize=8)
        self.clock = self.fig.text(0.5, 0.962, "", ha="center", va="top", fontsize=7.5,
                                   family="monospace")
        handles = [
            Patch(fc=OBSTACLE_COLOR, label="obstacle"),
            Line2D([], [], marker="o", ls="", mfc=ROBOT_COLOR, mec=ROBOT_COLOR, label="robot"),
            Line2D([], [], color=TRAIL_COLOR, label="robot trail"),
            Patch(fill=False, ec=GOAL_COLOR, lw=1.4, label="goal"),
            Line2D([], [], color=PATH_COLOR, label="planned path"),
            Line2D([], [], color=VERIFIED_COLOR, label="verified edge"),
            Line2D([], [], color=PENALISED_COLOR, label="penalised edge"),
            Line2D([], [], marker="x", ls="", color=CONTACT_COLOR, label="contact"),
        ]
        self.fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=6.5,
                        frameon=False, handlelength=1.5, columnspacing=1.0)
        self.fig.tight_layout(rect=(0.0, 0.09, 1.0, 0.93))
        self.dynamic = [*self.painter.start_outlines, *self.painter.goal_outlines,
                        self.path_line, self.verified, self.penalised, self.trails,
                        self.pushes, *self.painter.dynamic_artists, self.contacts]
        self._set_robot_radius()
        self.blit = options.follow is None
        if self.blit:
            for a in (*self.dynamic, self.title, self.clock):
                a.set_animated(True)
            self.fig.canvas.draw()
            self.background = self.fig.canvas.copy_from_bbox(self.fig.bbox)
        self._trail_rows = int(round(options.trail_s / recording.row_dt_s))

    def _window(self, row: int) -> None:
        """Centre the camera on the moved object (``follow``)."""
        w = float(self.opt.follow)
        W, H = self.scene.workspace
        g = self.rec.segment_of_row(row)
        k = int(self.rec.arrays["segment_object"][g]) if g >= 0 else 0
        x, y = (float(v) for v in self.rec.arrays["objects"][row, k, :2])
        self.ax.apply_aspect()
        bbox = self.ax.get_window_extent()
        h = w * bbox.height / bbox.width
        x = min(max(x, w / 2), max(W - w / 2, w / 2))
        y = min(max(y, h / 2), max(H - h / 2, h / 2))
        self.ax.set_xlim(x - w / 2, x + w / 2)
        self.ax.set_ylim(y - h / 2, y + h / 2)

    def _set_robot_radius(self) -> None:
        if self.opt.follow is not None:
            self._window(0)
        self.ax.apply_aspect()  # the drawn box (equal aspect), not the layout's
        bbox = self.ax.get_window_extent()
        x0, x1 = self.ax.get_xlim()
        px_per_m = bbox.width / (x1 - x0)
        radius = max(self.scene.robot_radius, self.opt.min_robot_px / px_per_m)
        for patch in self.painter.robots:
            patch.set_radius(radius)

    def render(self, row: int, segment: int | None = None) -> np.ndarray:
        """The (H, W, 3) uint8 picture of recorded row ``row``, drawn with ``segment``'s
        plan and contacts (default: the segment the row belongs to)."""
        rec, a = self.rec, self.rec.arrays
        g = rec.segment_of_row(row) if segment is None else segment
        active = int(a["segment_object"][g]) if g >= 0 else None
        self.painter.update(a["objects"][row], a["robots"][row], active,
                            a["robot_team"][row] if "robot_team" in a else None)
        plan = int(a["segment_plan"][g]) if g >= 0 else -1
        self.path_line.set_data(*rec.plan_path(plan)[:, :2].T)
        self.verified.set_segments(rec.verified_of(plan))
        self.penalised.set_segments(rec.penalised_of(plan))
        lo = max(0, row - self._trail_rows)
        robots = a["robots"][lo : row + 1]
        self.trails.set_segments([robots[:, i] for i in range(robots.shape[1])])
        contacts = rec.contacts_of(g) if g >= 0 else np.zeros((0, 2))
        self.contacts.set_data(contacts[:, 0], contacts[:, 1])
        self.pushes.set_segments(rec.pushes_of(g) if g >= 0 else [])
        n_obj = len(self.scene.objects)
        seg_text = f"segment {g + 1}/{rec.n_segments}" if g >= 0 else "no segment executed"
        event = OUTCOMES[int(a["segment_outcome"][g])] if g >= 0 else ""
        obj_text = f"object {active + 1}/{n_obj}" if active is not None else ""
        self.clock.set_text(f"t = {a['times'][row]:7.2f} s   {seg_text}   {obj_text}"
                            + (f"   [{event}]" if event not in ("", "continue") else ""))
        self.title.set_text(f"{self.scene.name} - {rec.planner} (seed {rec.seed}) - "
                            f"{outcome_text(rec)}")
        canvas = self.fig.canvas
        if self.blit:
            canvas.restore_region(self.background)
            for artist in self.dynamic:
                self.ax.draw_artist(artist)
            self.fig.draw_artist(self.title)
            self.fig.draw_artist(self.clock)
        else:
            self._window(row)
            canvas.draw()
        return np.asarray(canvas.buffer_rgba())[..., :3].copy()


@dataclass(frozen=True)
class RenderStats:
    """What ``render`` wrote: the file, the frames drawn and the seconds it took."""

    path: Path
    frames: int
    seconds: float


def render(recording: Recording, path: str | Path, options: RenderOptions | None = None,
           **kwargs: Any) -> RenderStats:
    """Draw ``recording`` into ``path``: ``.gif``, ``.mp4`` (needs ``imageio-ffmpeg``),
    ``.png`` (one still, ``at``), ``.html`` (the interactive viewer) or ``.mcap`` (for
    Foxglove, needs ``mcap``; ``lamp.viz.replay_mcap``). Options are a
    :class:`RenderOptions` or its fields as keywords. The file is written atomically."""
    opt = options or RenderOptions(**kwargs)
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise ValueError(f"out: expected a file name ending in {', '.join(SUFFIXES)}, "
                         f"got {str(path)!r}")
    if suffix == ".mp4" and not mp4_available():
        raise RuntimeError(f"cannot write {str(path)!r}: MP4 needs imageio-ffmpeg; install "
                           "it with `pip install 'lamp[video]'`, or write a .gif")
    t0 = time.perf_counter()
    if suffix == ".html":
        from lamp.viz.replay_html import write_html

        write_html(recording, path, opt)
        return RenderStats(path, 0, time.perf_counter() - t0)
    if suffix == ".mcap":
        from lamp.viz.replay_mcap import write_mcap

        write_mcap(recording, path)
        return RenderStats(path, 0, time.perf_counter() - t0)
    renderer = ReplayRenderer(recording, opt)
    if suffix == ".png":
        row = still_row(recording, opt.at)
        image = renderer.render(row, opt.at)
        from PIL import Image

        with atomic_output(path) as tmp:
            Image.fromarray(image).save(tmp, format="PNG")
        return RenderStats(path, 1, time.perf_counter() - t0)
    rows = frame_rows(recording, opt)
    with atomic_output(path) as tmp:
        if suffix == ".gif":
            _write_gif(renderer, rows, tmp, opt.fps)
        else:
            _write_mp4(renderer, rows, tmp, opt.fps)
    return RenderStats(path, len(rows), time.perf_counter() - t0)


def _write_gif(renderer: ReplayRenderer, rows: np.ndarray, tmp: Path, fps: float) -> None:
    """One shared palette (from the first frame plus every layer colour), no dithering."""
    from PIL import Image

    from lamp.viz.animation import palette_image

    images, palette, last = [], None, None
    for row in rows:
        if row != last:
            rgb = renderer.render(int(row))
            if palette is None:
                palette = palette_image(rgb, extra=(TRAIL_COLOR,))
            image = Image.fromarray(rgb).quantize(palette=palette, dither=Image.Dither.NONE)
            last = row
        images.append(image)
    images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                   duration=1000.0 / fps, loop=0, optimize=False)


def _write_mp4(renderer: ReplayRenderer, rows: np.ndarray, tmp: Path, fps: float) -> None:
    import imageio.v2 as iio2

    writer: Any = iio2.get_writer(tmp, format="FFMPEG", mode="I", fps=fps, macro_block_size=1)
    try:
        last, rgb = None, None
        for row in rows:
            if row != last:
                rgb = renderer.render(int(row))
                h, w = (rgb.shape[0] // 2) * 2, (rgb.shape[1] // 2) * 2  # H.264: even sizes
                rgb = np.ascontiguousarray(rgb[:h, :w])
                last = row
            writer.append_data(rgb)
    finally:
        writer.close()
