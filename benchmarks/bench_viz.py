"""Rendering speed of lamp.viz: seconds per animation frame and per scene PNG.

Run: ``python benchmarks/bench_viz.py``. Prints medians and p95 over repeated renders of
the spec example scene (tests/data/spec_example_fixed.yaml) at the animation defaults
(4.5 inch, 80 dpi: 360 x 360 px) and the end-to-end cost of ``write_animation``.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from lamp.scene import load_scene
from lamp.viz.animation import Frame, FrameRenderer, mp4_available, write_animation
from lamp.viz.scene_plot import save_scene_png

ROOT = Path(__file__).resolve().parents[1]


def frames_for(scene, n: int) -> list[Frame]:
    start, goal = scene.object_starts(), scene.object_goals()
    path = np.linspace(start[0], goal[0], 40)
    edges = [((a[0], a[1]), (b[0], b[1])) for a, b in zip(path[:-1], path[1:], strict=True)]
    out = []
    for k, t in enumerate(np.linspace(0.0, 1.0, n)):
        poses = start.copy()
        poses[0] = (1 - t) * start[0] + t * goal[0]
        robots = scene.robot_starts_array + np.array([2.5 * t, 3.0 * t])
        out.append(Frame(robots, poses, 0, path, edges[: k % 39], edges[30:], f"frame {k}"))
    return out


def stats(xs: list[float]) -> str:
    a = np.asarray(xs) * 1e3
    return f"median {np.median(a):.1f} ms, p95 {np.percentile(a, 95):.1f} ms (n={len(a)})"


def main() -> None:
    scene = load_scene(ROOT / "tests" / "data" / "spec_example_fixed.yaml")
    frames = frames_for(scene, 300)
    t0 = time.perf_counter()
    renderer = FrameRenderer(scene)
    print(f"figure set-up (first render of the static layer): {time.perf_counter() - t0:.3f} s")
    per = []
    for i, f in enumerate(frames):
        t0 = time.perf_counter()
        renderer.render(f, i)
        per.append(time.perf_counter() - t0)
    print(f"render one 360x360 frame (blit): {stats(per)}")
    with tempfile.TemporaryDirectory() as d:
        for name in ("run.gif", "run.mp4"):
            if name.endswith(".mp4") and not mp4_available():
                print("mp4: skipped (imageio-ffmpeg not installed)")
                continue
            t0 = time.perf_counter()
            s = write_animation(scene, frames, Path(d) / name)
            wall = time.perf_counter() - t0
            size = (Path(d) / name).stat().st_size / 1e6
            print(
                f"write_animation {name}: {s.frames_written} frames, {wall:.2f} s wall, "
                f"{wall / s.frames_written * 1e3:.1f} ms/frame all-in (render {s.render_s:.2f} s, "
                f"encode {s.write_s:.2f} s), {size:.2f} MB"
            )
        png = []
        for _ in range(5):
            t0 = time.perf_counter()
            save_scene_png(scene, Path(d) / "scene.png")
            png.append(time.perf_counter() - t0)
        print(f"save_scene_png 720x720: {stats(png)}")


if __name__ == "__main__":
    main()
