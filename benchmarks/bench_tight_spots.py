"""Tight spots: LAMP-Lazy where objects get pinned or wedged, over seeds 0-2.

Three hand-made scenes, each a failure seen before the narrow-passage refinement and the
recovery pushes:

* ``t-door``: a T-shape (0.5 m bar, 0.4 m tall) through a door 4 cm wider than its height,
  so it must turn stem-first in front of the door, with every robot behind it;
* ``bay-turn``: a 0.4 x 0.3 m box down a corridor 3 cm wider than it, turning 105 degrees
  in a bay barely larger than its diagonal plus the robots, into a second corridor;
* ``bar-zigzag``: a 1.2 m x 0.2 m bar through three corridor legs 2 cm wider than it, at
  arbitrary angles, turning in two bays.

Printed per scene and seed: success, segments, replans, planning time and the failure
reason. Run: ``python benchmarks/bench_tight_spots.py [--seeds 0,1,2] [--scenes t-door]``.
"""

from __future__ import annotations

import argparse
import math
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import shapely  # noqa: E402
from shapely.geometry import LineString, Point  # noqa: E402


def _walls(free: shapely.Geometry, w: float, h: float) -> list[dict]:
    """The workspace minus ``free`` as simple wall polygons (the corridor family's cutter)."""
    from lamp.suites.corridor_layout import wall_polygons

    return [{"type": "polygon", "points": pts.tolist()} for pts in wall_polygons((w, h), free)]


def corridor_chain(points, across: float, clearance: float, size, name: str,
                   goal_heading: float) -> dict:
    """Bays at ``points`` joined by straight corridors ``across + clearance`` wide; the
    object (a ``size`` rectangle) starts in the first bay aligned with the first leg."""
    pts = [np.asarray(p, float) for p in points]
    w = math.ceil(max(p[0] for p in pts) + 1.2)
    h = math.ceil(max(p[1] for p in pts) + 1.2)
    bay = 0.5 * (math.hypot(*size) + 0.35)
    free = shapely.union_all(
        [Point(*p).buffer(bay) for p in pts]
        + [LineString([a, b]).buffer(0.5 * (across + clearance), cap_style="flat")
           for a, b in zip(pts[:-1], pts[1:], strict=True)])
    d = (pts[1] - pts[0]) / np.linalg.norm(pts[1] - pts[0])
    back = pts[0] - d * (0.5 * size[0] + 0.12)
    n = np.array([-d[1], d[0]])
    return {"format": "lamp-scene/1", "name": name, "workspace": [w, h],
            "robots": {"radius": 0.05,
                       "starts": [[float(v) for v in back + k * 0.13 * n] for k in (-1, 0, 1)]},
            "obstacles": _walls(free, w, h),
            "objects": [{"type": "rectangle", "size": list(size),
                         "start": [float(pts[0][0]), float(pts[0][1]),
                                   float(math.atan2(d[1], d[0]))],
                         "goal": [float(pts[-1][0]), float(pts[-1][1]), goal_heading]}]}


def t_door(door: float = 0.44) -> dict:
    y0, y1 = 2.0 - door / 2, 2.0 + door / 2
    t_shape = [[-0.25, -0.15], [0.25, -0.15], [0.25, -0.05], [0.05, -0.05], [0.05, 0.25],
               [-0.05, 0.25], [-0.05, -0.05], [-0.25, -0.05]]
    return {"format": "lamp-scene/1", "name": "t-door", "workspace": [5.0, 4.0],
            "robots": {"radius": 0.05, "starts": [[0.6, 1.6], [0.6, 2.0], [0.6, 2.4]]},
            "obstacles": [
                {"type": "rectangle", "center": [2.5, y0 / 2], "size": [0.2, y0], "angle": 0.0},
                {"type": "rectangle", "center": [2.5, (4.0 + y1) / 2], "size": [0.2, 4.0 - y1],
                 "angle": 0.0}],
            "objects": [{"type": "polygon", "points": t_shape, "start": [1.4, 2.0, 0.0],
                         "goal": [3.8, 2.0, 0.0]}]}


SCENES = {
    "t-door": t_door,
    "bay-turn": lambda: corridor_chain([[1.0, 1.0], [3.6, 1.7], [3.0, 4.0]], 0.3, 0.03,
                                       (0.4, 0.3), "bay-turn", 2.0),
    "bar-zigzag": lambda: corridor_chain([[1.2, 1.2], [4.0, 2.1], [3.2, 4.6], [6.6, 4.9]],
                                         0.2, 0.02, (1.2, 0.2), "bar-zigzag", 1.0),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--model", default="learned")
    args = ap.parse_args()
    from lamp import solve
    from lamp.scene.loader import scene_from_dict

    print(f"{'scene':<11} {'seed':>4} {'ok':>3} {'seg':>4} {'replans':>7} {'plan_s':>7} "
          f"{'wall_s':>6}  reason", flush=True)
    for name in args.scenes.split(","):
        scene = scene_from_dict(SCENES[name]())
        for seed in (int(s) for s in args.seeds.split(",")):
            t0 = time.perf_counter()
            r = solve(scene, "lazy", seed=seed, model=args.model).to_dict()
            o = r["objects"][0]
            print(f"{name:<11} {seed:>4} {'yes' if r['success'] else 'no':>3} "
                  f"{r['segments']:>4} {r['replans']:>7} {r['total_planning_time_s']:>7.1f} "
                  f"{time.perf_counter() - t0:>6.1f}  {o['failure_reason']}", flush=True)


if __name__ == "__main__":
    main()
