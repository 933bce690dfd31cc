"""The first D* Lite plan of LAMP-Lazy on the scaling benchmark's pillar maps, by heuristic.

For each map side (``bench_scale.pillar_scene``: one 0.4 x 0.3 m box from corner to
corner, pillars at ``--density`` per square metre) this builds the goal lattice (0.1 m, 16
headings) and runs the first ``plan_shortest_path`` from the box's start, lazy collision
checks included, with three heuristics:

* ``euclid``: ``hypot(dx, dy) + w_rot * |dtheta|`` (the heuristic before the octile metric);
* ``octile``: the lattice metric without a landmark;
* ``landmark``: the lattice metric with the start as landmark (what LAMP-Lazy uses), the
  potential's construction included in the time.

Printed per map and heuristic: D* Lite expansions, pose and motion checks, time (median
over ``--repeats``, each on a fresh lattice) and the path cost, which must agree (all three
are admissible and consistent, so D* Lite returns an optimal path with each).

Run: ``python benchmarks/bench_heuristic.py [--sizes 4,16,50] [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_scale import DEFAULT_DENSITY, pillar_scene  # noqa: E402

from lamp.geometry import se2  # noqa: E402
from lamp.planners.lazy import join_lattice  # noqa: E402
from lamp.scene.loader import scene_from_dict  # noqa: E402
from lamp.search.dstar_lite import DStarLite  # noqa: E402
from lamp.search.lattice import ObjectLattice  # noqa: E402


class EuclideanLattice(ObjectLattice):
    """The lattice with the Euclidean SE(2) heuristic (a lower bound of every motion)."""

    def heuristic(self, u, v) -> float:  # type: ignore[override]
        ax, ay, at = self._xyt(u)
        bx, by, bt = self._xyt(v)
        d = abs(at - bt) % (2 * math.pi)
        return math.hypot(ax - bx, ay - by) + self.w_rot * min(d, 2 * math.pi - d)

    def distance(self, a, b):  # type: ignore[override]
        dt, dr = se2.pose_distance(a, b)
        return dt + self.w_rot * dr


def first_plan(scene, kind: str) -> dict:
    obj = scene.objects[0]
    cls = EuclideanLattice if kind == "euclid" else ObjectLattice
    landmark = obj.start[:2] if kind == "landmark" else None
    t0 = time.perf_counter()
    lat = cls.from_scene(scene, 0, landmark=landmark)
    dstar = DStarLite(lat)
    dstar.initialize(lat.goal_node)
    start, edges = join_lattice(lat, np.asarray(obj.start, dtype=float))
    path = dstar.plan_shortest_path(start, edges)
    dt = time.perf_counter() - t0
    return {"time_s": dt, "expansions": dstar.stats.last_expansions, "cost": dstar.path_cost(),
            "pose_checks": lat.n_pose_checks, "motion_checks": lat.n_motion_checks,
            "ok": bool(path)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="4,16,50", help="map sides in metres")
    ap.add_argument("--density", type=float, default=DEFAULT_DENSITY,
                    help="pillars per square metre")
    ap.add_argument("--heuristics", default="euclid,octile,landmark")
    ap.add_argument("--repeats", type=int, default=1)
    args = ap.parse_args()
    warm = scene_from_dict(pillar_scene(4.0, density=args.density))
    first_plan(warm, "landmark")  # compile the kernels outside the figures
    print(f"{'size':>5} {'heuristic':>9} {'expansions':>10} {'poses':>8} {'motions':>8} "
          f"{'time_s':>7} {'cost':>8}")
    for size in [float(s) for s in args.sizes.split(",")]:
        scene = scene_from_dict(pillar_scene(size, density=args.density))
        costs = []
        for kind in args.heuristics.split(","):
            runs = [first_plan(scene, kind) for _ in range(max(1, args.repeats))]
            r = runs[0]
            costs.append(r["cost"])
            print(f"{size:5g} {kind:>9} {r['expansions']:10d} {r['pose_checks']:8d} "
                  f"{r['motion_checks']:8d} {np.median([x['time_s'] for x in runs]):7.2f} "
                  f"{r['cost']:8.3f}", flush=True)
        if max(costs) - min(costs) > 1e-9 * max(1.0, max(costs)):
            raise SystemExit(f"path costs differ on the {size:g} m map: {costs}")


if __name__ == "__main__":
    main()
