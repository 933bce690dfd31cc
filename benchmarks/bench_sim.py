"""Simulator throughput and construction cost.

Prints, as medians (and p95) over repeats:
- real-time factor (simulated seconds per wall-clock second) and physics steps per second
  of a 3-robot + 1-box push (4 m x 4 m workspace, 1 m push, settle included), with and
  without a recorded trace, and of the same push in a cluttered scene (obstacles of every
  shape, an L-shaped polygon object and a disk object standing by);
- ``Simulator(scene)`` construction time with the compiled model cached (same structure,
  new poses: the data-generation case) and uncached (a new structure every time).

Run: ``python benchmarks/bench_sim.py [--repeats 20]`` (single-threaded).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle, Scene, SceneObject  # noqa: E402
from lamp.sim import MAX_STEP, Simulator  # noqa: E402
from lamp.sim.mjcf import _build_cached  # noqa: E402

L_SHAPE = Polygon(((0.0, 0.0), (0.4, 0.0), (0.4, 0.1), (0.1, 0.1), (0.1, 0.3), (0.0, 0.3)))


def line(a, b) -> np.ndarray:
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = max(1, int(np.ceil(np.linalg.norm(b - a) / MAX_STEP)))
    return a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)


def push_scene(cluttered: bool, box=(0.4, 0.3)) -> Scene:
    starts = ((1.75, 1.89), (1.75, 2.0), (1.75, 2.11))
    objects = [SceneObject(Rectangle(box), (2.0, 2.0, 0.0), (3.0, 2.0, 0.0))]
    obstacles: list[Obstacle] = []
    if cluttered:
        objects += [
            SceneObject(L_SHAPE, (0.5, 3.0, 0.3), (0.5, 3.0, 0.3)),
            SceneObject(Circle(0.2), (3.3, 0.6, 0.0), (3.3, 0.6, 0.0)),
        ]
        obstacles = [
            Obstacle(Circle(0.15), (3.0, 1.0, 0.0)),
            Obstacle(Rectangle((0.2, 1.5)), (1.0, 2.0, 0.3)),
            Obstacle(Polygon(((2.0, 3.0), (2.5, 3.0), (2.2, 3.6)))),
            Obstacle(
                Polygon(((3.0, 3.0), (3.6, 3.0), (3.6, 3.2), (3.2, 3.2), (3.2, 3.7), (3.0, 3.7)))
            ),
        ]
    return Scene("bench", (4.0, 4.0), starts, tuple(objects), tuple(obstacles), 0.05)


def stats(xs) -> str:
    xs = np.asarray(xs)
    return f"median {np.median(xs):.4g}  p95 {np.percentile(xs, 95):.4g}"


def bench_push(cluttered: bool, record_every: int | None, repeats: int) -> None:
    scene = push_scene(cluttered)
    paths = np.stack([line(p, (p[0] + 1.0, p[1])) for p in scene.robot_starts])
    rtf, sps = [], []
    for _ in range(repeats):
        sim = Simulator(scene)
        t0 = time.perf_counter()
        out = sim.execute(paths, record_every=record_every)
        dt = time.perf_counter() - t0
        rtf.append(out.sim_time / dt)
        sps.append(out.steps / dt)
    label = f"{'cluttered' if cluttered else 'open'} push, trace={record_every}"
    print(f"{label:32s} steps {out.steps}, box moved {out.object_poses[0, 0] - 2.0:.3f} m")
    print(f"  real-time factor (sim s / wall s): {stats(rtf)}")
    print(f"  physics steps per second:          {stats(sps)}")


def bench_construction(repeats: int) -> None:
    for cluttered in (False, True):
        scene = push_scene(cluttered)
        Simulator(scene)  # warm the cache
        cached = []
        rng = np.random.default_rng(0)
        for _ in range(repeats * 10):
            poses = scene.object_starts() + rng.uniform(-0.05, 0.05, (len(scene.objects), 3))
            t0 = time.perf_counter()
            Simulator(scene, object_poses=poses)
            cached.append(time.perf_counter() - t0)
        uncached = []
        for i in range(repeats):
            new = push_scene(cluttered, box=(0.4 + 1e-4 * (i + 1), 0.3))
            _build_cached.cache_clear()
            t0 = time.perf_counter()
            Simulator(new)
            uncached.append(time.perf_counter() - t0)
        kind = "cluttered" if cluttered else "open"
        print(f"Simulator() {kind:9s} cached model [ms]:   {stats(1e3 * np.array(cached))}")
        print(f"Simulator() {kind:9s} new structure [ms]:  {stats(1e3 * np.array(uncached))}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args()
    bench_push(cluttered=False, record_every=None, repeats=args.repeats)
    bench_push(cluttered=False, record_every=10, repeats=args.repeats)
    bench_push(cluttered=True, record_every=None, repeats=args.repeats)
    bench_construction(args.repeats)


if __name__ == "__main__":
    main()
