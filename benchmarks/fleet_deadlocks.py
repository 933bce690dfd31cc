"""Loads that block each other for good unless one moves aside (``lamp.fleet.makeway``):
places swapped, rotated round, a corridor swap, a dead end, and a goal in the gap another
load must pass through; run concurrently (LAMP-Lazy,
seed 0) with every robot and with one team (the first three robots only), and, for
comparison, one after another. Prints per scene and run: objects placed, makespan
(simulated s), moves aside, wall time and the violations the independent safety check
finds in the recording (``lamp.record.safety``).

    python benchmarks/fleet_deadlocks.py [--write DIR] [--scenes swap dead-end]
    python benchmarks/fleet_deadlocks.py --random 12   # random rotations of 2-4 loads
"""

from __future__ import annotations

import argparse
import copy
import time
from pathlib import Path

import numpy as np

import lamp
from lamp.record.safety import check_recording, recorded_teams
from lamp.scene import scene_from_dict
from lamp.scene.save import save_scene


def _box(size: float, start: tuple[float, float], goal: tuple[float, float]) -> dict:
    return {"type": "rectangle", "size": [size, size], "start": [*start, 0.0],
            "goal": [*goal, 0.0]}


def _scene(name: str, workspace: list[float], robots: list[list[float]],
           obstacles: list[dict], objects: list[dict]) -> dict:
    return {"format": "lamp-scene/1", "name": name, "workspace": workspace,
            "schedule": "concurrent", "robots": {"radius": 0.05, "starts": robots},
            "obstacles": obstacles, "objects": objects}


def _wall(cx: float, cy: float, w: float, h: float) -> dict:
    return {"type": "rectangle", "center": [cx, cy], "size": [w, h], "angle": 0.0}


SCENES = {
    # two boxes in an open yard, each to go where the other stands
    "swap": _scene("swap", [6.0, 4.0],
                   [[1.0, 1.0], [1.2, 1.0], [1.4, 1.0], [4.6, 1.0], [4.8, 1.0], [5.0, 1.0]],
                   [], [_box(0.4, (2.0, 2.0), (4.0, 2.0)), _box(0.4, (4.0, 2.0), (2.0, 2.0))]),
    # three loads rotating round a pillar: each to the next one's place
    "rotate-3": _scene(
        "rotate-3", [6.0, 5.0],
        [[0.5, 0.5], [0.7, 0.5], [0.9, 0.5], [5.1, 0.5], [5.3, 0.5], [5.5, 0.5], [2.8, 4.5],
         [3.0, 4.5], [3.2, 4.5]],
        [{"type": "circle", "center": [3.0, 2.2], "radius": 0.3}],
        [{"type": "rectangle", "size": [0.4, 0.3], "start": [2.0, 1.5, 0.0],
          "goal": [4.0, 1.5, 0.0]},
         {"type": "circle", "radius": 0.2, "start": [4.0, 1.5, 0.0], "goal": [3.0, 3.3, 0.0]},
         _box(0.3, (3.0, 3.3), (2.0, 1.5))]),
    # four boxes in a 2 x 2 block, each to the next corner round
    "rotate-4": _scene(
        "rotate-4", [6.0, 5.0],
        [[0.4, 0.4], [0.6, 0.4], [0.8, 0.4], [5.2, 0.4], [5.4, 0.4], [5.6, 0.4],
         [0.4, 4.6], [0.6, 4.6], [0.8, 4.6], [5.2, 4.6], [5.4, 4.6], [5.6, 4.6]],
        [], [_box(0.4, (2.5, 2.0), (3.5, 2.0)), _box(0.4, (3.5, 2.0), (3.5, 3.0)),
             _box(0.4, (3.5, 3.0), (2.5, 3.0)), _box(0.4, (2.5, 3.0), (2.5, 2.0))]),
    # a 1.2 m corridor open at both ends; the boxes swap places inside it, one to its
    # lower side, one to its upper side (placed on the centre line, a box would leave
    # 0.4 m beside it: no room to pass it with robots)
    "corridor-swap": _scene(
        "corridor-swap", [8.0, 4.0],
        [[0.4, 2.0], [0.4, 1.8], [0.4, 2.2], [7.6, 2.0], [7.6, 1.8], [7.6, 2.2]],
        [_wall(4.0, 0.7, 4.0, 1.4), _wall(4.0, 3.3, 4.0, 1.4)],
        [_box(0.4, (3.0, 2.0), (5.0, 1.7)), _box(0.4, (5.0, 2.0), (3.0, 2.3))]),
    # a dead end 1.2 m wide: the box inside to come out, the one at its mouth to go in
    "dead-end": _scene(
        "dead-end", [8.0, 4.0],
        [[6.5, 2.0], [6.5, 1.8], [6.5, 2.2], [7.0, 2.0], [7.0, 1.8], [7.0, 2.2]],
        [_wall(2.5, 0.7, 5.0, 1.4), _wall(2.5, 3.3, 5.0, 1.4)],
        [_box(0.4, (2.0, 2.0), (6.0, 3.3)), _box(0.4, (4.0, 2.0), (1.0, 2.0))]),
    # a wall with a 1 m gap at its top: box 0's goal is in the gap, box 1 must pass
    # through it first (``fleet.precedence``; no move aside needed)
    "gap-goal": _scene(
        "gap-goal", [8.0, 6.0],
        [[0.4, 0.4], [0.6, 0.4], [0.8, 0.4], [0.4, 5.6], [0.6, 5.6], [0.8, 5.6]],
        [_wall(4.0, 2.5, 0.2, 5.0)],
        [_box(0.4, (2.5, 5.5), (4.0, 5.5)), _box(0.4, (2.0, 1.0), (6.0, 1.0))]),
}


def random_rotation(seed: int) -> dict:
    """A yard of 6-10 x 4-8 m with up to four pillars and 2-4 objects (boxes, disks and
    oblong boxes, at places at least 1.2 m apart) each to go to the next one's place, three
    robots per object along the bottom edge; deterministic in ``seed``."""
    rng = np.random.default_rng(seed)
    W, H = float(rng.uniform(6, 10)), float(rng.uniform(4, 8))
    n = int(rng.integers(2, 5))
    places: list[tuple[float, float]] = []
    while len(places) < n:
        p = (float(rng.uniform(1.0, W - 1.0)), float(rng.uniform(1.5, H - 1.0)))
        if all(np.hypot(p[0] - q[0], p[1] - q[1]) >= 1.2 for q in places):
            places.append(p)
    pillars = []
    for _ in range(int(rng.integers(0, 5))):
        c, rad = (float(rng.uniform(0.5, W - 0.5)), float(rng.uniform(1.0, H - 0.5))), 0.2
        if all(np.hypot(c[0] - q[0], c[1] - q[1]) >= 0.8 for q in places):
            pillars.append({"type": "circle", "center": list(c), "radius": rad})
    shapes = [{"type": "rectangle", "size": [0.4, 0.4]}, {"type": "circle", "radius": 0.2},
              {"type": "rectangle", "size": [0.5, 0.3]}]
    objects = []
    for i, p in enumerate(places):
        q = places[(i + 1) % n]
        objects.append({**shapes[int(rng.integers(0, 3))], "start": [*p, 0.0],
                        "goal": [*q, 0.0]})
    robots = [[0.4 + 0.2 * i, 0.3] for i in range(3 * n)]
    return _scene(f"rotation-{seed}", [round(W, 2), round(H, 2)], robots, pillars, objects)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="+", choices=sorted(SCENES), default=list(SCENES))
    ap.add_argument("--random", type=int, default=0, metavar="N",
                    help="instead: N random rotations (``random_rotation``, seeds 0..N-1)")
    ap.add_argument("--write", type=Path, help="also save the scenes to this folder")
    args = ap.parse_args()
    if args.random:
        SCENES.clear()
        SCENES.update({f"rotation-{i}": random_rotation(i) for i in range(args.random)})
        args.scenes = list(SCENES)
    print("scene | run | placed | makespan (s) | moves aside | wall (s) | violations")
    for name in args.scenes:
        scene = scene_from_dict(copy.deepcopy(SCENES[name]))
        if args.write:
            args.write.mkdir(parents=True, exist_ok=True)
            save_scene(scene, args.write / f"{name}.yaml")
        one_team = scene.with_robot_starts(scene.robot_starts[:3])
        for label, schedule, case in (("concurrent", "concurrent", scene),
                                      ("concurrent, one team", "concurrent", one_team),
                                      ("sequential", "sequential", scene)):
            t0 = time.perf_counter()
            result = lamp.solve(case, "lazy", 0, schedule=schedule)
            wall = time.perf_counter() - t0
            rec = result.recording
            report = check_recording(rec.scene_model(), rec.arrays["times"],
                                     rec.arrays["robots"], rec.arrays["objects"],
                                     robot_team=recorded_teams(rec))
            placed = sum(o.success for o in result.objects)
            moves = result.stats.get("fleet", {}).get("made_way", "-")
            print(f"{name} | {label} | {placed}/{len(result.objects)} | "
                  f"{result.makespan_s:.1f} | {moves} | {wall:.1f} | {len(report.violations)}",
                  flush=True)


if __name__ == "__main__":
    main()
