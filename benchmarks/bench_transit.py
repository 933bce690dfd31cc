"""Fleet transit (``lamp.fleet.transit``): what the routes and one hop cost, and how that
grows with the map.

For each scene of the ``fleet`` family: the map, the route grid's cells, the time to
build the routes to object 0's staging area (median of ``--repeats``), the longest route
of a robot to it, and the time of one hop of every robot whose route is longer than
``TRANSIT_RADIUS`` (all robots as the team, as in the sequential schedule; "-" when none
is far). Then medians by map size. Run:
``python benchmarks/bench_transit.py [--scenes 25] [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from lamp.fleet.transit import far_robots, hop, routes
from lamp.suites.registry import suite_scenes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=25, help="first N fleet scenes")
    ap.add_argument("--repeats", type=int, default=3, help="route builds per scene (median)")
    args = ap.parse_args()
    print(f"{'scene':<10}{'map (m)':>10}{'cells':>9}{'routes ms':>11}{'longest m':>11}"
          f"{'far':>5}{'hop ms':>8}")
    by_size: dict[str, list[float]] = {"< 20 m": [], "20-35 m": [], "> 35 m": []}
    for i, scene in enumerate(suite_scenes("fleet")):
        if i >= args.scenes:
            break
        poses = np.array(scene.object_starts())
        runs = []
        for _ in range(args.repeats):
            t = time.perf_counter()
            field = routes(scene, 0, poses)
            runs.append(time.perf_counter() - t)
        pos = np.array(scene.robot_starts, float)
        cells = [field.cell_of(p) for p in pos]
        longest = max((float(field.dist[c]) for c in cells if c is not None), default=np.nan)
        far = far_robots(field, pos)
        hop_ms = "-"
        if far.any():
            t = time.perf_counter()
            plan = hop(scene, 0, poses, pos, far, field)
            hop_ms = f"{1000 * (time.perf_counter() - t):.0f}" + (
                "" if plan is not None and plan.success else " (failed)")
        W, H = scene.workspace
        side = max(W, H)
        key = "< 20 m" if side < 20 else "20-35 m" if side <= 35 else "> 35 m"
        by_size[key].append(statistics.median(runs))
        print(f"{scene.name:<10}{f'{W:g} x {H:g}':>10}{field.free.size:>9}"
              f"{1000 * statistics.median(runs):>11.1f}{longest:>11.1f}{int(far.sum()):>5}"
              f"{hop_ms:>8}")
    for key, times in by_size.items():
        if times:
            print(f"routes, maps {key}: median {1000 * statistics.median(times):.1f} ms over "
                  f"{len(times)} scenes")


if __name__ == "__main__":
    main()
