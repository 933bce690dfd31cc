"""Loads that block each other for good unless one moves aside (``lamp.fleet.makeway``):
places swapped, rotated round, a corridor swap and a dead end; run concurrently (LAMP-Lazy,
seed 0) with every robot and with one team (the first three robots only), and, for
comparison, one after another. Prints per scene and run: objects placed, makespan
(simulated s), moves aside, wall time and the violations the independent safety check
finds in the recording (``lamp.record.safety``).

    python benchmarks/fleet_deadlocks.py [--write DIR] [--scenes swap dead-end]
"""

from __future__ import annotations

import argparse
import copy
import time
from pathlib import Path

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
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="+", choices=sorted(SCENES), default=list(SCENES))
    ap.add_argument("--write", type=Path, help="also save the scenes to this folder")
    args = ap.parse_args()
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
