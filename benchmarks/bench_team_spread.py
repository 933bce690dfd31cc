"""Verify with a team spread over a large map: LAMP-Lazy, one object after another, on the
largest ``fleet`` scenes (17-23 robots over 38-50 m maps), first objects only.

Every Verify of such a run sees robots standing tens of metres apart. The planner must
not pay for a robot space over the whole spread in every call (``Verifier._unreachable``
and ``leave_contact`` look in the object's own window first). Prints, per scene, each
object's segments and planning seconds and the run's wall time and peak RSS so far. Run:
``python benchmarks/bench_team_spread.py [--scenes fleet-12 fleet-04] [--objects 4]``.
"""

from __future__ import annotations

import argparse
import resource
import time
from dataclasses import replace

import lamp
from lamp.suites.registry import resolve_scene


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=["fleet-12", "fleet-04", "fleet-16"])
    ap.add_argument("--objects", type=int, default=4, help="first N objects of each scene")
    args = ap.parse_args()
    print(f"{'scene':<10}{'robots':>7}{'map (m)':>12}  per object: segments / planning s"
          f"{'':>4}{'wall s':>8}{'peak GB':>9}")
    for name in args.scenes:
        scene = resolve_scene(name)
        scene = replace(scene, objects=tuple(replace(o, after=()) for o in
                                             scene.objects[:args.objects]))
        t = time.perf_counter()
        result = lamp.solve(scene, "lazy", 0, schedule="sequential")
        wall = time.perf_counter() - t
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
        per = "  ".join(f"{o.segments}/{o.planning_time_s:.2f}" for o in result.objects)
        w, h = scene.workspace
        print(f"{name:<10}{scene.n_robots:>7}{f'{w:.0f} x {h:.0f}':>12}  {per:<40}"
              f"{wall:>8.1f}{peak:>9.2f}")


if __name__ == "__main__":
    main()
