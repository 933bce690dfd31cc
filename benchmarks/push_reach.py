"""How far pushed objects ran ahead of their pushers in recorded concurrent runs, against
the bound the fleet's admission takes (``lamp.fleet.spacetime``: every point of a pushed
object moves at most ``PUSH_SPEEDUP`` times as far as its sub-team's farthest-moving robot,
plus ``PUSH_LEAD``).

    python benchmarks/push_reach.py RUN_DIR [RUN_DIR ...] [--horizon 400]

RUN_DIR: a ``lamp run`` output folder, or a ``lamp bench --record`` folder (its run
folders are found below it). Prints, per run, the lead it needed at ``PUSH_SPEEDUP``
and at speedup 1, where, and the pairs of rows compared; exits 1 when a run needed more
than ``PUSH_LEAD``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from lamp.fleet.spacetime import PUSH_LEAD, PUSH_SPEEDUP
from lamp.record.audit import run_dirs
from lamp.record.push_reach import push_reach_run_dir


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--horizon", type=int, default=400, help="rows apart at most")
    args = ap.parse_args()
    dirs = sorted({d for r in args.runs for d in run_dirs(r)})
    worst = -float("inf")
    print(f"bound: {PUSH_SPEEDUP} x the pushers' way + {PUSH_LEAD} m; horizon {args.horizon} rows")
    print(f"{'run':40s} {'lead':>8s} {'lead@1x':>8s} {'object':>6s} {'from s':>8s} "
          f"{'to s':>8s} {'pairs':>10s}")
    for d in dirs:
        rep = push_reach_run_dir(d, PUSH_SPEEDUP, args.horizon)
        one = push_reach_run_dir(d, 1.0, args.horizon)
        worst = max(worst, rep.lead)
        print(f"{str(d)[-40:]:40s} {rep.lead:8.4f} {one.lead:8.4f} {rep.object:6d} "
              f"{rep.time_s:8.2f} {rep.until_s:8.2f} {rep.pairs:10d}")
    print(f"worst lead {worst:.4f} m of {PUSH_LEAD} m allowed")
    return 0 if worst <= PUSH_LEAD else 1


if __name__ == "__main__":
    sys.exit(main())
