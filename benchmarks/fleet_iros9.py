"""The IROS case study with a fleet: its map and 9 objects, 9 robots (its 3 and six more),
moved one after another and concurrently; prints both makespans and their ratio, and the
critical chain's bound on the ratio.

The bound: ``teams.start_order`` starts an object after those whose way its goal lies in
(``teams.in_the_way``). Along the longest chain of that relation, weighted by each
object's running time in the sequential run (the team's approach and pushes, alone in the
room), no schedule that keeps the chain's order, and sends each object's team to it only
once the one before is placed, can place the last object sooner than the chain's sum;
divided by the sequential makespan it bounds the ratio from below. A team already at its
object when the one before is placed saves its approach: the same chain counting only
the time from the object's first motion to its placement (its pushes and the
re-approaches between them) is printed beside it, the bound such a schedule faces. (A
chain broken costs more than it saves on this scene: ``docs/fleet.md``, Limits.)

A seed whose sequential or concurrent run leaves an object unplaced gets no ratio (the
makespan of a failed run is not the time to place every object); the median is over the
seeds with one.

The six robots are placed deterministically at the free spots of a 0.2 m grid nearest the
three robots' centre (clear of obstacles and of every object's start and goal by 0.1 m,
0.2 m apart). ``--write FILE`` saves the scene.

    python benchmarks/fleet_iros9.py [--seeds 0 1 2] [--write iros9.yaml]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np
import shapely

import lamp
from lamp.fleet.teams import goal_blocks
from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.scene.model import Scene
from lamp.scene.save import save_scene
from lamp.suites.registry import resolve_scene


def with_robots(scene: Scene, extra: int) -> Scene:
    """``scene`` with ``extra`` more robots at the free grid spots nearest its robots."""
    r = scene.robot_radius
    taken = [obstacle_geometry(o) for o in scene.obstacles]
    taken += [to_shapely(o.shape, q) for o in scene.objects for q in (o.start, o.goal)]
    blocked = shapely.union_all(taken).buffer(r + 0.05)
    starts = [tuple(p) for p in scene.robot_starts]
    c = np.mean(starts, axis=0)
    W, H = scene.workspace
    grid = [(x, y) for x in np.arange(0.2, W - 0.15, 0.2) for y in np.arange(0.2, H - 0.15, 0.2)]
    grid.sort(key=lambda p: (np.hypot(p[0] - c[0], p[1] - c[1]), p))
    for p in grid:
        if len(starts) == scene.n_robots + extra:
            break
        if blocked.intersects(shapely.Point(p)):
            continue
        if min(np.hypot(p[0] - q[0], p[1] - q[1]) for q in starts) < 2 * r + 0.1:
            continue
        starts.append((round(float(p[0]), 3), round(float(p[1]), 3)))
    return replace(scene, robot_starts=tuple(starts), name=f"{scene.name}-{len(starts)}r")


def running_times(recording) -> tuple[dict[int, float], dict[int, float]]:
    """Each object's running time (s) in a sequential run, the sum of its segments' spans;
    and the part of it from the object's first motion (more than 1 cm) on."""
    a = recording.arrays
    t, rows, obj, poses = a["times"], a["segment_rows"], a["segment_object"], a["objects"]
    out: dict[int, float] = {}
    pushing: dict[int, float] = {}
    moved = np.hypot(*np.moveaxis(poses[:, :, :2] - poses[:1, :, :2], -1, 0)) > 0.01
    first = np.where(moved.any(axis=0), t[np.argmax(moved, axis=0)], np.inf)
    for g, k in enumerate(obj):
        k, start, end = int(k), float(t[rows[g]]), float(t[rows[g + 1]])
        out[k] = out.get(k, 0.0) + end - start
        pushing[k] = pushing.get(k, 0.0) + max(0.0, end - max(start, float(first[k])))
    return out, pushing


def critical_chain(scene: Scene, weight: dict[int, float]) -> tuple[list[int], float]:
    """The chain ``k -> j`` (``j``'s goal lies in ``k``'s way, so ``j`` starts after ``k``)
    of the objects at their starts with the largest sum of ``weight``, and that sum. An
    edge back into the chain being built is skipped (a cycle is no chain)."""
    ks = range(len(scene.objects))
    _, blocks = goal_blocks(scene, scene.object_starts(), list(ks))
    after = {k: [j for j in ks if k in blocks[j]] for k in ks}

    def longest(k: int, on: frozenset[int]) -> tuple[float, list[int]]:
        tails = [longest(j, on | {j}) for j in after[k] if j not in on]
        best = max(tails, default=(0.0, []))
        return weight.get(k, 0.0) + best[0], [k, *best[1]]

    span, chain = max(longest(k, frozenset({k})) for k in ks)
    return chain, span


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", help="also save the scene to this file")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0],
                    help="planner seeds to run (default: 0); several print each and the median")
    args = ap.parse_args()
    scene = with_robots(resolve_scene("iros-01"), 6)
    if args.write:
        save_scene(scene, args.write)
    ratios = []
    for seed in args.seeds:
        spans, placed_all = {}, {}
        for schedule in ("sequential", "concurrent"):
            t0 = time.perf_counter()
            result = lamp.solve(scene, "lazy", seed, schedule=schedule)
            spans[schedule], placed_all[schedule] = result.makespan_s, result.success
            if schedule == "sequential":
                alone, pushing = running_times(result.recording)
                chain, bound = critical_chain(scene, alone)
                pushes = sum(pushing[k] for k in chain)
            placed = sum(o.success for o in result.objects)
            print(f"seed {seed} {schedule:10s} success {result.success} ({placed}/9 placed)  "
                  f"makespan {result.makespan_s:.1f} s  planning "
                  f"{result.total_planning_time_s:.1f} s  wall {time.perf_counter() - t0:.0f} s")
        if not all(placed_all.values()):  # a ratio against a failed run means nothing
            print(f"seed {seed}: not every object placed "
                  f"({', '.join(k for k, ok in placed_all.items() if not ok)}): no ratio")
            continue
        ratios.append(spans["concurrent"] / spans["sequential"])
        print(f"seed {seed} makespan concurrent / sequential: {ratios[-1]:.2f}  (critical chain "
              f"{' -> '.join(map(str, chain))}: {bound:.1f} s alone, bound "
              f"{bound / spans['sequential']:.3f}; from each object's first motion "
              f"{pushes:.1f} s, {pushes / spans['sequential']:.3f})")
    if len(ratios) > 1:
        print(f"median over the {len(ratios)} seeds of {args.seeds} with a ratio: "
              f"{float(np.median(ratios)):.3f} "
              f"({min(ratios):.3f}-{max(ratios):.3f})")


if __name__ == "__main__":
    main()
