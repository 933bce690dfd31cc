"""LAMP-Lazy's planning on cluttered grid maps: objects moved one after another on the
Moving AI maps of ``../shared/data/mapf/``.

Scenes come from ``lamp.suites.fleet.generate_on_map`` (the ``fleet`` family's checks on
a map it never saw): ``--objects`` objects and three robots per object on each map, run
with the sequential schedule (the paper's: one object after another, the whole team),
LAMP-Lazy, planner seed 0. Printed per map and generator seed: objects placed, executed
segments, planning in all, planning per executed segment and the run's wall time; then
the median per map. These maps are cluttered (20% of the cells blocked, hundreds of
rectangles), where Verify's windowed robot spaces and Gspi's lattices meet many obstacles.

    python benchmarks/bench_map_planning.py [--maps random-32-32-20:0.6 random-64-64-20:0.5]
        [--objects 2] [--seeds 0 1]
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import replace
from pathlib import Path

import lamp
from lamp.scene.mapf import load_grid_map
from lamp.suites.fleet import generate_on_map

MAP_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "mapf"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--maps", nargs="+", default=["random-32-32-20:0.6", "random-64-64-20:0.5"],
                    help="NAME:CELL per map (default: random-32-32-20:0.6 random-64-64-20:0.5)")
    ap.add_argument("--objects", type=int, default=2, help="objects per scene (default: 2)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1],
                    help="generator seeds (default: 0 1)")
    args = ap.parse_args()
    print("map | seed | placed | segments | planning (s) | per segment (s) | wall (s)")
    for item in args.maps:
        name, _, cell = item.partition(":")
        base = load_grid_map(MAP_DIR / f"{name}.map", float(cell or 0.5)).scene
        per_seg = []
        for seed in args.seeds:
            gen = generate_on_map(base, args.objects, 3 * args.objects, seed)
            scene = replace(gen.scene, schedule="sequential")
            t0 = time.perf_counter()
            res = lamp.solve(scene, "lazy", 0)
            wall = time.perf_counter() - t0
            placed = sum(o.success for o in res.objects)
            per_seg.append(res.planning_time_per_segment_s or float("nan"))
            print(f"{name} | {seed} | {placed}/{args.objects} | {res.segments} | "
                  f"{res.total_planning_time_s:.1f} | {per_seg[-1]:.3f} | {wall:.0f}", flush=True)
        print(f"{name}: median planning per segment {statistics.median(per_seg):.3f} s")


if __name__ == "__main__":
    main()
