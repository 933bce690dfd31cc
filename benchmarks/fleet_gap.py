"""Where a concurrent run's time goes between the lower bound and the makespan.

For each recorded run folder (``lamp run ... --schedule concurrent`` or ``lamp bench
--record``), per object: its own lower bound (``lamp.scene.bounds``: nearest robot's drive
plus its travel round the obstacles, at the robots' speed), when it was placed, and how
its time until then splits, from the recording (``lamp.viz.timeline.robot_spans``):

- ``unstarted``: before any robot was in its sub-team (waiting to start or for robots);
- ``moving``: some robot of its sub-team moving (driving to it, repositioning, pushing);
- ``holding``: a sub-team, none of its robots moving (its segment waits for admission,
  its planner waits for a change, or it settles).

``moving - bound`` is then what the plan costs beyond the bound while it moves: approaches
round obstacles, repositioning between pushes, turns, slower pushes. The critical object
(placed last) is summarised on one line; the table then gives every object.

    python benchmarks/fleet_gap.py RUN_DIR [RUN_DIR ...]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from lamp.record.safety import recorded_teams
from lamp.scene.bounds import makespan_lower_bound
from lamp.viz.timeline import placement_times, robot_spans


def object_times(run: Path) -> tuple[list[dict], float, float]:
    """Per object: bound, placed, unstarted, moving, holding (s); the makespan and bound."""
    import lamp

    rec = lamp.load_recording(run)
    scene = rec.scene_model()
    a = rec.arrays
    times = np.asarray(a["times"], float)
    spans = robot_spans(times, a["robots"], recorded_teams(rec), float(scene.physics.robot_speed))
    bound = makespan_lower_bound(scene)
    placed = placement_times(rec)
    end = float(times[-1])
    rows = []
    for k in range(len(scene.objects)):
        until = placed.get(k, end)
        moving = np.zeros(0)
        cover = []  # (start, end, moving) of its team's spans
        for row in spans:
            cover += [(s.start, min(s.end, until), s.moving) for s in row
                      if s.object == k and s.start < until]
        grid = np.union1d([0.0, until], [t for s in cover for t in s[:2]])
        mid = 0.5 * (grid[:-1] + grid[1:])
        any_team = np.zeros(len(mid), bool)
        moving = np.zeros(len(mid), bool)
        for s0, s1, mv in cover:
            inside = (mid >= s0) & (mid < s1)
            any_team |= inside
            moving |= inside & mv
        width = np.diff(grid)
        rows.append({"object": k, "bound": bound.per_object[k], "placed": placed.get(k),
                     "unstarted": float(width[~any_team].sum()),
                     "moving": float(width[moving].sum()),
                     "holding": float(width[any_team & ~moving].sum())})
    return rows, float(rec.result.get("makespan_s") or end), bound.seconds


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    args = ap.parse_args(argv)
    for run in args.runs:
        rows, makespan, bound = object_times(run)
        last = max(rows, key=lambda r: -1 if r["placed"] is None else r["placed"])
        print(f"## {run}: makespan {makespan:.1f} s, bound {bound:.1f} s "
              f"({makespan / bound:.2f}x)")
        print(f"critical object {last['object']}: bound {last['bound']:.1f} s; unstarted "
              f"{last['unstarted']:.1f}, moving {last['moving']:.1f} (bound + "
              f"{last['moving'] - last['bound']:.1f}), holding {last['holding']:.1f}")
        print("| object | bound (s) | placed (s) | unstarted | moving | holding | moving / bound |")
        print("|---|---|---|---|---|---|---|")
        for r in rows:
            placed = "-" if r["placed"] is None else f"{r['placed']:.1f}"
            print(f"| {r['object']} | {r['bound']:.1f} | {placed} | {r['unstarted']:.1f} | "
                  f"{r['moving']:.1f} | {r['holding']:.1f} | {r['moving'] / r['bound']:.2f} |")
        tot = {k: sum(r[k] for r in rows) for k in ("unstarted", "moving", "holding")}
        span = sum(tot.values())
        print(f"all objects until placed: unstarted {tot['unstarted'] / span:.0%}, moving "
              f"{tot['moving'] / span:.0%}, holding {tot['holding'] / span:.0%}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
