"""The plane's reachability verdict (``lamp.search.connectivity``): what it costs per task.

LAMP-Lazy builds one ``PlaneConnectivity`` per planner (per object and world) and asks it
once per ``plan`` call. Printed per built-in family: obstacles per task (the scene's plus
the other objects), components of the free space, and the median and largest time to
build it and answer one query (median of ``--repeats`` builds per object), over the first
``--scenes`` scenes of each family. Run:
``python benchmarks/bench_connectivity.py [--scenes 5] [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from lamp.geometry.object_space import ObjectSpace
from lamp.planners.lazy import JOIN_TOLERANCES
from lamp.search.connectivity import PlaneConnectivity
from lamp.suites.registry import suite_scenes

FAMILIES = ("random", "maze", "tilt", "warehouse", "corridor", "warehouse-xl", "fleet")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=5, help="first N scenes of each family")
    ap.add_argument("--repeats", type=int, default=3, help="builds per object (median)")
    args = ap.parse_args()
    print(f"{'family':<14}{'tasks':>6}{'obstacles':>10}{'parts':>6}{'median ms':>11}"
          f"{'max ms':>9}{'separated':>10}")
    for family in FAMILIES:
        times, obstacles, parts, separated = [], [], [], 0
        for i, scene in enumerate(suite_scenes(family)):
            if i >= args.scenes:
                break
            poses = np.array([list(o.start) for o in scene.objects], float)
            for k, obj in enumerate(scene.objects):
                space = ObjectSpace.from_scene(scene, k, poses)
                runs = []
                for _ in range(args.repeats):
                    t = time.perf_counter()
                    plane = PlaneConnectivity(space, slack=max(JOIN_TOLERANCES))
                    cut = plane.separated(obj.start, obj.goal)
                    runs.append(time.perf_counter() - t)
                times.append(statistics.median(runs))
                obstacles.append(len(space.obstacles))
                parts.append(len(plane.parts))
                separated += bool(cut)
        print(f"{family:<14}{len(times):>6}{statistics.median(obstacles):>10.0f}"
              f"{statistics.median(parts):>6.0f}{1000 * statistics.median(times):>11.1f}"
              f"{1000 * max(times):>9.1f}{separated:>10}")


if __name__ == "__main__":
    main()
