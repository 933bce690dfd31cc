"""D* Lite's memo of the heuristic (``dstar_lite.H_KEPT``): a long haul's first search with
memos of several sizes.

On a long-haul depot (``depot_scene.depot``, 60 x 40 m by default) it builds LAMP-Lazy's
lattice for each given load, as the fleet's first loop would (the three nearest robots its
team, every other robot a disk obstacle), fills the lattice's caches with one search, then
times a fresh search from the load's pose for each memo size in turn, ``--repeats`` rounds
alternating the sizes. Printed per load and size: the expansions (the same for every size:
the memo changes no value) and the median time of a search. Single-threaded.

    python benchmarks/bench_memo.py [--loads 18 29] [--kept 1024 4096 16384] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from depot_scene import depot  # noqa: E402

from lamp.fleet.objects import sub_scene  # noqa: E402
from lamp.manip.models import load_proposer  # noqa: E402
from lamp.planners.config import PlannerConfig  # noqa: E402
from lamp.planners.lazy import LazyPlanner, join_lattice  # noqa: E402
from lamp.planners.task import ManipulationTask  # noqa: E402
from lamp.scene.loader import scene_from_dict  # noqa: E402
from lamp.search import dstar_lite  # noqa: E402
from lamp.search.dstar_lite import DStarLite  # noqa: E402


def search(lattice, start, edges, kept: int) -> tuple[float, int]:
    """A fresh search from ``start`` with a memo of ``kept`` vertices: (seconds, expansions)."""
    dstar_lite.H_KEPT = kept
    ds = DStarLite(lattice)
    ds.initialize(lattice.goal_node)
    t0 = time.perf_counter()
    path = ds.plan_shortest_path(start, edges)
    dt = time.perf_counter() - t0
    if not path:
        raise SystemExit(f"no path: {ds.status.value}")
    return dt, ds.stats.last_expansions


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=float, nargs=2, default=(60.0, 40.0), metavar=("W", "H"))
    ap.add_argument("--robots", type=int, default=144)
    ap.add_argument("--depot-loads", type=int, default=48)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--loads", type=int, nargs="+", default=[18, 29])
    ap.add_argument("--kept", type=int, nargs="+", default=[1024, 4096, 16384])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    scene = scene_from_dict(depot(*args.size, args.robots, args.depot_loads, args.seed))
    proposer = load_proposer("learned")
    poses = np.asarray(scene.object_starts(), float)
    robots = scene.robot_starts_array
    default = dstar_lite.H_KEPT
    print(f"depot {args.size[0]:g} x {args.size[1]:g} m, seed {args.seed}; "
          f"H_KEPT default {default}")
    print("load | memo (vertices) | expansions | search median (s)")
    for k in args.loads:
        q = poses[k]
        team = sorted(np.argsort(np.hypot(*(robots - q[:2]).T))[:3].tolist())
        task = ManipulationTask(sub_scene(scene, team, robots, np.inf, ()), k, poses,
                                proposer, PlannerConfig(), seed=k)
        lattice = LazyPlanner.from_task(task).lattice
        start, edges = join_lattice(lattice, q)
        search(lattice, start, edges, default)  # fills the lattice's caches
        times: dict[int, list[float]] = {n: [] for n in args.kept}
        expansions: dict[int, int] = {}
        for _ in range(args.repeats):
            for n in args.kept:
                dt, expansions[n] = search(lattice, start, edges, n)
                times[n].append(dt)
        for n in args.kept:
            print(f"{k} | {n} | {expansions[n]} | {statistics.median(times[n]):.2f}", flush=True)
        task.close()
    dstar_lite.H_KEPT = default


if __name__ == "__main__":
    main()
