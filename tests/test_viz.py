"""Tests of ``lamp.viz``: scene pictures (pixels where things are) and animation files."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from matplotlib.colors import to_rgb

from lamp.scene import Scene, load_scene, scene_from_dict
from lamp.viz.animation import (
    Frame,
    FrameRenderer,
    mp4_available,
    subsample_indices,
    write_animation,
)
from lamp.viz.scene_plot import (
    OBSTACLE_COLOR,
    ROBOT_COLOR,
    draw_scene,
    new_figure,
    object_color,
    save_scene_png,
)

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="module")
def scene() -> Scene:
    return load_scene(DATA / "spec_example_fixed.yaml")


def rgb255(color: str) -> np.ndarray:
    return np.array(to_rgb(color)) * 255.0


def near(pixel: np.ndarray, color: np.ndarray, tol: float = 12.0) -> bool:
    return bool(np.max(np.abs(pixel[:3].astype(float) - color)) <= tol)


def moving_frames(scene: Scene, n: int) -> list[Frame]:
    """``n`` frames with robots and object 0 moving (every frame differs)."""
    start, goal = scene.object_starts(), scene.object_goals()
    path = np.linspace(start[0], goal[0], 6)
    edges = [((a[0], a[1]), (b[0], b[1])) for a, b in zip(path[:-1], path[1:], strict=True)]
    frames = []
    for k, t in enumerate(np.linspace(0.0, 1.0, n)):
        poses = start.copy()
        poses[0] = (1 - t) * start[0] + t * goal[0]
        robots = scene.robot_starts_array + np.array([2.5 * t, 3.0 * t])
        frames.append(
            Frame(robots, poses, 0, path, edges[: k % 5], edges[4:], caption=f"frame {k}")
        )
    return frames


# --------------------------------------------------------------------------- pictures


def test_draw_scene_puts_things_where_they_are(scene: Scene) -> None:
    """Pixels at obstacle, robot and object positions have the right colours."""
    fig, ax = new_figure(scene, 4.0, 100)
    poses = scene.object_starts()
    poses[1] = [3.0, 2.5, 0.0]  # the disk object away from its start
    robots = np.array([[0.5, 3.5], [1.5, 3.6], [3.5, 0.4]])
    draw_scene(ax, scene, poses, robots)
    fig.canvas.draw()
    img = np.asarray(fig.canvas.buffer_rgba())
    height = img.shape[0]

    def pixel(x: float, y: float) -> np.ndarray:
        px, py = ax.transData.transform((x, y))
        return img[int(round(height - py)), int(round(px))]

    for o in scene.obstacles:
        cx, cy = (o.pose[0], o.pose[1]) if o.pose != (0.0, 0.0, 0.0) else np.mean(o.shape.points, 0)
        assert near(pixel(cx, cy), rgb255(OBSTACLE_COLOR)), o
    for x, y in robots:
        assert near(pixel(x, y), rgb255(ROBOT_COLOR))
    # object 1 (disk) filled with its colour at 85 % opacity over white, below its tick
    blend = 0.85 * rgb255(object_color(1)) + 0.15 * 255.0
    assert near(pixel(3.0, 2.4), blend)
    # its start is now only a dashed outline: the inside is background
    assert near(pixel(2.0, 0.5), np.array([255.0, 255.0, 255.0]))
    # far corner of the workspace, nothing there
    assert near(pixel(3.9, 3.9), np.array([255.0, 255.0, 255.0]))


def test_draw_scene_validates_arrays(scene: Scene) -> None:
    _, ax = new_figure(scene, 2.0, 50)
    with pytest.raises(ValueError, match=r"object_poses: expected shape \(3, 3\), got \(3, 2\)"):
        draw_scene(ax, scene, object_poses=np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"robot_positions: expected shape \(3, 2\)"):
        draw_scene(ax, scene, robot_positions=np.zeros((2, 2)))
    with pytest.raises(
        ValueError, match="highlight_object: expected an index in \\[0, 3\\), got 3"
    ):
        draw_scene(ax, scene, highlight_object=3)


def test_save_scene_png(scene: Scene, tmp_path: Path) -> None:
    out = save_scene_png(scene, tmp_path / "sub" / "scene.png", dpi=60)
    assert out == tmp_path / "sub" / "scene.png"
    img = iio.imread(out)
    assert img.shape[:2] == (360, 360)  # 6 inches at 60 dpi, square workspace
    dark = np.all(np.abs(img[..., :3].astype(float) - rgb255(OBSTACLE_COLOR)) <= 12, axis=-1)
    assert dark.sum() > 200  # obstacles are drawn
    blue = np.all(np.abs(img[..., :3].astype(float) - rgb255(ROBOT_COLOR)) <= 12, axis=-1)
    assert blue.sum() > 10  # robots too
    assert sorted(p.name for p in (tmp_path / "sub").iterdir()) == ["scene.png"]
    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask  # not mkstemp's private 0600


def test_save_scene_png_shape_and_obstacle_pixels(tmp_path: Path) -> None:
    """A 3 x 1.5 workspace gives a 2:1 picture; a 0.5 m square obstacle adds about its area
    in dark pixels (the legend and text hold some dark pixels in both pictures)."""
    d = {
        "format": "lamp-scene/1",
        "name": "wide",
        "workspace": [3.0, 1.5],
        "robots": {"starts": [[0.2, 0.2]]},
        "objects": [{"type": "circle", "radius": 0.2, "start": [1, 0.7, 0], "goal": [2, 0.7, 0]}],
    }

    def dark_pixels(name: str, scene_dict: dict) -> int:
        img = iio.imread(save_scene_png(scene_from_dict(scene_dict), tmp_path / name, dpi=50))
        assert img.shape[:2] == (150, 300)
        return int(np.all(np.abs(img[..., :3] - rgb255(OBSTACLE_COLOR)) <= 12, axis=-1).sum())

    empty = dark_pixels("empty.png", d)
    d["obstacles"] = [{"type": "rectangle", "center": [2.5, 0.5], "size": [0.5, 0.5]}]
    with_obstacle = dark_pixels("one.png", d)
    # the axes are 200-270 px wide for 3.1 m (title, legend): the square is 32-44 px a side
    assert 32**2 * 0.9 < with_obstacle - empty < 44**2 * 1.1


def test_import_lamp_does_not_import_matplotlib() -> None:
    code = "import lamp, sys; sys.exit('matplotlib' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


# --------------------------------------------------------------------------- animations


@given(n=st.integers(1, 2000), m=st.integers(1, 500))
def test_subsample_indices(n: int, m: int) -> None:
    idx = subsample_indices(n, m)
    assert len(idx) == min(n, m)
    assert np.all(np.diff(idx) > 0) and idx[0] >= 0 and idx[-1] == n - 1
    if n > m >= 2:
        assert idx[0] == 0
        gaps = np.diff(idx)
        assert gaps.max() - gaps.min() <= 1  # evenly spread


def test_gif_frames_in_order(scene: Scene, tmp_path: Path) -> None:
    frames = moving_frames(scene, 12)
    stats = write_animation(scene, frames, tmp_path / "run.gif", fps=10, size_in=2.5, dpi=60)
    assert stats.frames_in == stats.frames_written == 12 and stats.seconds_per_frame > 0
    gif = iio.imread(tmp_path / "run.gif", index=None)
    assert gif.shape == (12, 150, 150, 3)
    renderer = FrameRenderer(scene, 2.5, 60)
    direct = [renderer.render(f).astype(float) for f in frames]
    for k in range(12):  # GIF frame k is (up to the palette) frame k, not another one
        err = [np.mean(np.abs(gif[k, ..., :3] - d)) for d in direct]
        assert int(np.argmin(err)) == k and err[k] < 2.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.gif"]  # no temp file left


def test_gif_subsampling(scene: Scene, tmp_path: Path) -> None:
    frames = moving_frames(scene, 50)
    stats = write_animation(scene, frames, tmp_path / "run.gif", max_frames=20, size_in=2.0, dpi=40)
    assert (stats.frames_in, stats.frames_written) == (50, 20)
    gif = iio.imread(tmp_path / "run.gif", index=None)
    assert gif.shape[0] == 20
    renderer = FrameRenderer(scene, 2.0, 40)
    last = renderer.render(frames[-1]).astype(float)
    assert np.mean(np.abs(gif[-1, ..., :3] - last)) < 2.0  # the last frame is kept


def test_failed_write_is_atomic(scene: Scene, tmp_path: Path) -> None:
    """A bad frame raises a ValueError naming it; the old file stays, no temp file is left."""
    path = tmp_path / "run.gif"
    path.write_bytes(b"old")
    frames = moving_frames(scene, 5)
    frames[3] = Frame(np.zeros((3, 2)), np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"frames\[3\]\.object_poses: expected shape \(3, 3\)"):
        write_animation(scene, frames, path, size_in=2.0, dpi=40)
    frames[3] = Frame(np.zeros((3, 2)), np.zeros((3, 3)), verified_edges=[(1.0, 2.0)])
    with pytest.raises(ValueError, match=r"frames\[3\]\.verified_edges"):
        write_animation(scene, frames, path, size_in=2.0, dpi=40)
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["run.gif"]


def test_bad_arguments(scene: Scene, tmp_path: Path) -> None:
    frames = moving_frames(scene, 2)
    with pytest.raises(ValueError, match=r"\.gif or \.mp4"):
        write_animation(scene, frames, tmp_path / "run.avi")
    with pytest.raises(ValueError, match="empty"):
        write_animation(scene, [], tmp_path / "run.gif")
    with pytest.raises(ValueError, match="fps: must be > 0, got 0"):
        write_animation(scene, frames, tmp_path / "run.gif", fps=0)
    with pytest.raises(ValueError, match="max_frames"):
        write_animation(scene, frames, tmp_path / "run.gif", max_frames=0)
    assert list(tmp_path.iterdir()) == []


def test_mp4_without_ffmpeg_is_a_clear_error(
    scene: Scene, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import lamp.viz.animation as animation

    monkeypatch.setattr(animation, "mp4_available", lambda: False)  # as without imageio-ffmpeg
    with pytest.raises(RuntimeError, match="pip install imageio-ffmpeg"):
        write_animation(scene, moving_frames(scene, 2), tmp_path / "run.mp4")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not mp4_available(), reason="needs imageio-ffmpeg")
def test_mp4(scene: Scene, tmp_path: Path) -> None:
    stats = write_animation(
        scene, moving_frames(scene, 10), tmp_path / "run.mp4", size_in=2.0, dpi=45
    )
    assert stats.frames_written == 10
    video = iio.imread(tmp_path / "run.mp4", index=None, plugin="FFMPEG")
    assert video.shape[0] == 10 and video.shape[1] % 2 == 0 and video.shape[2] % 2 == 0
    assert [p.name for p in tmp_path.iterdir()] == ["run.mp4"]
