"""LAMP-Lazy with a fleet standing by: what robots far from the push cost.

A 30 m x 20 m hall with 60 round pillars (radius 0.10-0.25 m) and one 0.4 m x 0.3 m box
pushed 7.6 m, from (2, 2) to (9, 5); three robots start next to the box and the others
stand anywhere in the hall (at least 0.2 m from pillars and 0.3 m from each other). All
robots are in every Verify call (the paper's Reassign sends those without a contact to
waiting spots; Gspi routes them all), so this measures how planning grows with robots
that have nothing to do.

Printed per robot count: success, executed segments, planning time per executed segment
(the figure ``lamp bench`` reports), total planning time, Gspi calls; and the ratio of
each count's per-segment time to the first count's. One process per point (``--repeats``
runs, medians).

Run: ``python benchmarks/bench_fleet_lamp.py [--robots 3,6,12,24] [--repeats 1]
[--model learned]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

W, H = 30.0, 20.0
BOX_START, BOX_GOAL = (2.0, 2.0), (9.0, 5.0)


def hall_scene(robots: int) -> dict:
    """The scene-file dict of the hall with ``robots`` robots (deterministic)."""
    rng = np.random.default_rng(5)
    obs = []
    for _ in range(60):
        x, y = rng.uniform(1, W - 1), rng.uniform(1, H - 1)
        if min(np.hypot(x - BOX_START[0], y - BOX_START[1]),
               np.hypot(x - BOX_GOAL[0], y - BOX_GOAL[1])) < 1.5:
            continue
        obs.append({"type": "circle", "center": [float(x), float(y)],
                    "radius": float(rng.uniform(0.1, 0.25))})
    starts = [[1.4, 1.6], [1.4, 2.0], [1.4, 2.4]][:robots]
    while len(starts) < robots:
        x, y = rng.uniform(0.5, W - 0.5), rng.uniform(0.5, H - 0.5)
        if (all(np.hypot(x - o["center"][0], y - o["center"][1]) > o["radius"] + 0.2
                for o in obs) and np.hypot(x - BOX_START[0], y - BOX_START[1]) > 1.0
                and all(np.hypot(x - a, y - b) > 0.3 for a, b in starts)):
            starts.append([float(x), float(y)])
    return {"format": "lamp-scene/1", "name": f"hall-{robots}", "workspace": [W, H],
            "robots": {"radius": 0.05, "starts": starts}, "obstacles": obs,
            "objects": [{"type": "rectangle", "size": [0.4, 0.3],
                         "start": [*BOX_START, 0.0], "goal": [*BOX_GOAL, 0.0]}]}


def _point(robots: int, model: str) -> dict:
    import lamp
    from lamp.scene.loader import scene_from_dict

    r = lamp.solve(scene_from_dict(hall_scene(robots)), "lazy", seed=0, model=model).to_dict()
    return {"success": r["success"], "segments": r["segments"],
            "per_segment": r["planning_time_per_segment_s"],
            "total": r["total_planning_time_s"], "gspi": r["stats"].get("gspi_calls")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robots", default="3,6,12,24")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--model", default="learned")
    ap.add_argument("--point", type=int, default=None, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.point is not None:
        print(json.dumps(_point(a.point, a.model)))
        return
    print("robots | success | segments | planning per segment s | total s | Gspi calls | "
          "ratio to the first count")
    base = None
    for n in (int(v) for v in a.robots.split(",")):
        runs = []
        for _ in range(a.repeats):
            out = subprocess.run([sys.executable, __file__, "--point", str(n), "--model",
                                  a.model], capture_output=True, text=True, check=True)
            runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
        per = float(np.median([r["per_segment"] for r in runs]))
        base = per if base is None else base
        r = runs[0]
        print(f"{n} | {r['success']} | {r['segments']} | {per:.4f} | "
              f"{np.median([x['total'] for x in runs]):.2f} | {r['gspi']} | {per / base:.1f}",
              flush=True)


if __name__ == "__main__":
    main()
