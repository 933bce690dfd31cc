"""Scaling benchmark: LAMP-Lazy on L x L pillar maps, from the paper's 4 m to 50 m warehouses.

Each map is an L x L workspace with sparse round pillars (radius 8-20 cm, at least 0.8 m
apart, ``--density`` per square metre, default 0.15; at high densities fewer fit and the
``obstacles`` column says how many did), one 0.4 m x 0.3 m box pushed from (0.6, 0.6) to
(L - 0.6, L - 0.6) and 3 robots (or ``--robots``) starting next to it; optionally more
boxes (``--objects``) on the same diagonal band. The route length is the straight-line
distance from each object's start to its goal, summed over the objects.

Every point runs in its own subprocess, so that the peak resident memory printed is that
point's alone (``ru_maxrss`` of the child). Printed per point: success, executed segments,
planning time (sum over segments), planning time per metre of route, makespan (steps) and
peak RSS; with ``--repeats n`` each point runs n times and the medians are printed (the
plan itself is deterministic: success, segments and makespan do not change). Segments are limited as for any user scene (``lamp.planners.config.segment_limit``:
max(100, 30 per metre from start to goal)); ``--max-segments N`` sets a fixed limit.

Each of ``--sizes``, ``--robots``, ``--objects`` and ``--density`` takes a list; every
combination is a point. ``--json FILE`` writes the points (with each run's figures);
``benchmarks/plot_scale.py`` draws them.

Run: ``python benchmarks/bench_scale.py [--sizes 4,8,16,32,50] [--robots 3] [--objects 1]
[--density 0.15] [--repeats 3] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from lamp.io import write_json_atomic  # noqa: E402

SRC = Path(__file__).resolve().parents[1] / "src"
#: pillars per square metre of the default maps
DEFAULT_DENSITY = 0.15


def pillar_scene(size: float, robots: int = 3, objects: int = 1,
                 density: float = DEFAULT_DENSITY) -> dict:
    """The scene-file dict of an ``size`` x ``size`` pillar map with ``density`` pillars per
    square metre as far as they fit (deterministic in its size and density)."""
    rng = np.random.default_rng(int(size))
    L = float(size)
    n = int(round(density * L * L))
    keep_clear = [(0.6, 0.6), (L - 0.6, L - 0.6)]
    starts, goals = [], []
    for k in range(objects):
        off = 0.9 * k
        starts.append([0.6 + off, 0.6, 0.0])
        goals.append([L - 0.6, L - 0.6 - off, 0.0])
        keep_clear += [(0.6 + off, 0.6), (L - 0.6, L - 0.6 - off)]
    obs: list[dict] = []
    for _ in range(n * 20):
        if len(obs) >= n:
            break
        x, y = rng.uniform(0.8, L - 0.8, 2)
        r = float(rng.uniform(0.08, 0.2))
        if any(math.hypot(x - cx, y - cy) < 1.2 for cx, cy in keep_clear):
            continue
        if any(math.hypot(x - o["center"][0], y - o["center"][1]) < r + o["radius"] + 0.8
               for o in obs):
            continue
        obs.append({"type": "circle", "center": [round(float(x), 3), round(float(y), 3)],
                    "radius": round(r, 3)})
    robot_starts = [[0.3 + 0.2 * i, 0.15] for i in range(robots)]
    return {
        "format": "lamp-scene/1", "name": f"pillars-{int(L)}", "workspace": [L, L],
        "robots": {"radius": 0.05, "starts": robot_starts},
        "obstacles": obs,
        "objects": [{"type": "rectangle", "size": [0.4, 0.3], "start": s, "goal": g}
                    for s, g in zip(starts, goals, strict=True)],
    }


def run_point(size: float, robots: int, objects: int, density: float,
              max_segments: int | None, seed: int) -> dict:
    """Solve one map in this process; the figures of one point."""
    import resource
    import time

    from lamp import solve
    from lamp.planners.config import PlannerConfig
    from lamp.scene.loader import scene_from_dict

    d = pillar_scene(size, robots, objects, density)
    scene = scene_from_dict(d)
    route = sum(math.dist(o["start"][:2], o["goal"][:2]) for o in d["objects"])
    t0 = time.perf_counter()
    res = solve(scene, planner="lazy", seed=seed, config=PlannerConfig.of(max_segments=max_segments))
    wall = time.perf_counter() - t0
    out = res.to_dict()
    plan = float(out["total_planning_time_s"])
    return {
        "size_m": size, "robots": robots, "objects": objects, "density": density,
        "obstacles": len(d["obstacles"]),
        "route_m": round(route, 2), "success": out["success"], "segments": out["segments"],
        "planning_s": round(plan, 2), "s_per_m": round(plan / route, 3),
        "makespan": out["makespan"], "wall_s": round(wall, 1),
        "peak_gb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6, 3),
        "reasons": [o["failure_reason"] for o in out["objects"]],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="4,8,16,32,50", help="map sides in metres")
    ap.add_argument("--robots", default="3", help="robot counts, e.g. 3,6")
    ap.add_argument("--objects", default="1", help="object counts, e.g. 1,3")
    ap.add_argument("--density", default=f"{DEFAULT_DENSITY:g}",
                    help="pillars per square metre, e.g. 0.05,0.15,0.3")
    ap.add_argument("--max-segments", type=int, default=None,
                    help="fixed segment limit per object (default: scaled with the task)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=1, help="runs per point (medians)")
    ap.add_argument("--json", type=Path, help="also write all points to this file")
    ap.add_argument("--point", help=argparse.SUPPRESS)  # child: size,robots,objects,density
    args = ap.parse_args()
    if args.point:
        size, robots, objects, density = args.point.split(",")
        print(json.dumps(run_point(float(size), int(robots), int(objects), float(density),
                                   args.max_segments, args.seed)))
        return
    rows = []
    head = (f"{'size':>5} {'rob':>3} {'obj':>3} {'dens':>5} {'pil':>5} {'route':>6} {'ok':>3} "
            f"{'seg':>5} {'plan_s':>8} {'s/m':>7} {'makespan':>8} {'peak_GB':>7}")
    print(head, flush=True)
    env = dict(os.environ, PYTHONPATH=f"{SRC}{os.pathsep}{os.environ.get('PYTHONPATH', '')}")
    points = [(float(s), int(r), int(k), float(d)) for s in args.sizes.split(",")
              for r in args.robots.split(",") for k in args.objects.split(",")
              for d in args.density.split(",")]
    for size, robots, objects, density in points:
        cmd = [sys.executable, __file__, "--point",
               f"{size:g},{robots},{objects},{density:g}", "--seed", str(args.seed)]
        if args.max_segments is not None:
            cmd += ["--max-segments", str(args.max_segments)]
        runs = []
        for _ in range(max(1, args.repeats)):
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
            if proc.returncode != 0:
                print(f"{size:5g} {robots:3d} {objects:3d} failed: "
                      f"{proc.stderr.strip().splitlines()[-1:]}", flush=True)
                break
            runs.append(json.loads(proc.stdout.strip().splitlines()[-1]))
        if not runs:
            continue
        r = dict(runs[0])
        for k in ("planning_s", "s_per_m", "wall_s", "peak_gb"):
            r[k] = float(np.median([x[k] for x in runs]))
        r["runs"] = runs
        rows.append(r)
        print(f"{size:5g} {robots:3d} {objects:3d} {density:5.2f} {r['obstacles']:5d} "
              f"{r['route_m']:6.1f} "
              f"{'yes' if r['success'] else 'no':>3} {r['segments']:5d} "
              f"{r['planning_s']:8.1f} {r['s_per_m']:7.3f} {r['makespan']:8d} "
              f"{r['peak_gb']:7.2f}", flush=True)
    if args.json:
        write_json_atomic(args.json, rows)


if __name__ == "__main__":
    main()
