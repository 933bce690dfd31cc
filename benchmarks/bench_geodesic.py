"""Cost of the bounds round the obstacles: the grown obstacles' visibility graph, and the
fleet bound over it, by map and robot count.

Per map (a Moving AI map from ``../shared/data/mapf/``, cells of ``--cell`` m, robots of
radius 0.05 m, as ``bench_fleet.py``): the time and peak memory of building
``lamp.scene.bounds.grown_obstacles`` (the obstacles grown by the robots' radius, merged,
with their visibility graph), its vertices and edges. Per robot count and seed (starts
and goals as ``bench_fleet.py`` draws them): the straight-line bottleneck ``LB`` and its
time, the bound round the obstacles ``GLB`` (``lamp.mrmp.bottleneck.geodesic_bottleneck``)
and its time, and ``GLB / LB``; then the median time per map and robot count. Peak
memory is the process's (``ru_maxrss``), after the map's build and after the instances.

Run: ``python benchmarks/bench_geodesic.py [--maps random-32-32-20,random-64-64-20,den520d]
[--robots 100,400,800,1600] [--seeds 3]``
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

import numpy as np

from lamp.mrmp.bottleneck import geodesic_bottleneck, straight_line_bottleneck
from lamp.scene.bounds import grown_obstacles
from lamp.scene.mapf import load_grid_map, random_instance

MAP_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "mapf"
RADIUS = 0.05


def peak_mb() -> float:
    """The process's peak resident memory so far (MB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--maps", default="random-32-32-20,random-64-64-20,den520d")
    ap.add_argument("--robots", default="100,400,800,1600")
    ap.add_argument("--seeds", type=int, default=3, help="seeds 0 .. SEEDS-1")
    ap.add_argument("--cell", type=float, default=0.15)
    ap.add_argument("--map-dir", type=Path, default=MAP_DIR, help="folder of the .map files")
    a = ap.parse_args()
    print("map | robots | seed | LB m | LB s | GLB m | GLB s | GLB / LB")
    summary = []
    for name in a.maps.split(","):
        gm = load_grid_map(a.map_dir / f"{name}.map", a.cell, RADIUS)
        t = time.perf_counter()
        grown = grown_obstacles(tuple(gm.scene.obstacles), tuple(gm.scene.workspace), RADIUS,
                                merge=True)
        build = time.perf_counter() - t
        free = int((~gm.blocked).sum())
        print(f"# {name}: {gm.scene.workspace[0]:.1f} x {gm.scene.workspace[1]:.1f} m, "
              f"{len(gm.scene.obstacles)} obstacle rectangles; grown obstacles {build:.2f} s, "
              f"{len(grown.vertices)} vertices, {grown.n_edges} edges; "
              f"peak {peak_mb():.0f} MB", flush=True)
        for n in (int(v) for v in a.robots.split(",")):
            if n > free:
                continue
            times = []
            for seed in range(a.seeds):
                S, G = random_instance(gm, n, seed)
                t = time.perf_counter()
                lb = straight_line_bottleneck(S, G)
                t_lb = time.perf_counter() - t
                t = time.perf_counter()
                glb = geodesic_bottleneck(grown, S, G)
                t_glb = time.perf_counter() - t
                times.append(t_glb)
                print(f"{name} | {n} | {seed} | {lb:.3f} | {t_lb:.2f} | {glb:.3f} | "
                      f"{t_glb:.2f} | {glb / lb:.3f}", flush=True)
            summary.append((name, n, float(np.median(times))))
    print("\n| map | robots | GLB time, median (s) |\n|---|---|---|")
    for name, n, t in summary:
        print(f"| {name} | {n} | {t:.2f} |")
    print(f"\npeak memory (RSS) {peak_mb():.0f} MB")


if __name__ == "__main__":
    main()
