"""Benchmark of Gspi at fleet scale: hundreds of robots on MAPF benchmark maps.

Instances: a Moving AI map from ``../shared/data/mapf/`` (``lamp.scene.mapf``) with square
cells of ``--cell`` metres (0.15 m), every blocked cell an obstacle; robots of radius
0.05 m start and end at distinct free cell centres drawn with the seed (starts distinct,
goals distinct); any robot may take any goal. ``lamp.mrmp.plan_paths`` with its defaults.

Printed per map, robot count and seed: planning time of the call (the map's space and
lattices are built once per map beforehand, as a fleet planner reuses them; that set-up
is printed per map), Gspi steps, makespan (metres: the time at unit speed of the
synchronised plan, i.e. the sum over steps of the longest move), the slowest robot's path
length, the sum of path lengths, the assignment's bottleneck bound, and whether the
independent checker (``tests/fleet_checker.py``) accepts the plan; then medians per map
and robot count, and the peak memory of the process.

With ``--tswap ADAPTER`` (a script that runs TSWAP's public implementation, built from its
source outside this repository), the same instances are solved by TSWAP in its sum and
bottleneck assignment modes and printed beside ours (its makespan and sum of path
lengths converted to metres at one cell per time step).

Run: ``python benchmarks/bench_fleet.py [--maps random-64-64-20] [--robots 100,200,400,800]
[--seeds 3] [--tswap /path/to/adapter.py]``; ``--quick``: random-32-32-20 and
random-64-64-20 at 100 and 400 robots, one seed.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from fleet_checker import check_fleet_plan  # noqa: E402

from lamp.geometry.robot_space import RobotSpace  # noqa: E402
from lamp.mrmp import plan_paths  # noqa: E402
from lamp.mrmp.distance_field import get_lattice  # noqa: E402
from lamp.mrmp.gspi import warmup  # noqa: E402
from lamp.scene.mapf import load_grid_map, random_instance  # noqa: E402

MAP_DIR = ROOT.parent / "shared" / "data" / "mapf"
RADIUS = 0.05


def plan_figures(paths: np.ndarray) -> tuple[float, float, float]:
    """(makespan at unit speed, slowest robot's path length, sum of path lengths), m."""
    step = np.hypot(*np.diff(paths, axis=1).transpose(2, 0, 1))  # (N, T-1)
    if step.size == 0:
        return 0.0, 0.0, 0.0
    length = step.sum(axis=1)
    return float(step.max(axis=0).sum()), float(length.max()), float(length.sum())


def cells_of(gm, pts: np.ndarray) -> np.ndarray:
    """(row, col) of cell centres, row 0 at the top of the map file."""
    H = gm.blocked.shape[0]
    col = np.rint(pts[:, 0] / gm.cell - 0.5).astype(int)
    row = H - 1 - np.rint(pts[:, 1] / gm.cell - 0.5).astype(int)
    return np.stack([row, col], 1)


def run_tswap(adapter: str, map_path: Path, gm, S: np.ndarray, G: np.ndarray,
              mode: str) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        fs, fg = Path(tmp) / "s.txt", Path(tmp) / "g.txt"
        np.savetxt(fs, cells_of(gm, S), fmt="%d")
        np.savetxt(fg, cells_of(gm, G), fmt="%d")
        out = subprocess.run([sys.executable, adapter, "--map", str(map_path), "--starts",
                              str(fs), "--goals", str(fg), "--mode", mode, "--json"],
                             capture_output=True, text=True, timeout=600)
    try:
        return json.loads(out.stdout.strip().splitlines()[-1])
    except (json.JSONDecodeError, IndexError):
        return {"solved": False, "error": (out.stderr or out.stdout)[-200:]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--maps", default="random-32-32-20,random-64-64-20,empty-64-64,den520d")
    ap.add_argument("--robots", default="100,200,400,800")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--cell", type=float, default=0.15)
    ap.add_argument("--map-dir", type=Path, default=MAP_DIR, help="folder of the .map files")
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--tswap", default=None, help="TSWAP adapter script (optional)")
    ap.add_argument("--no-check", action="store_true", help="skip the independent checker")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    maps = a.maps.split(",")
    robots = [int(v) for v in a.robots.split(",")]
    seeds = a.seeds
    if a.quick:
        maps, robots, seeds = ["random-32-32-20", "random-64-64-20"], [100, 400], 1
    warmup()
    print("map | robots | seed | time s | steps | makespan m | slowest path m | sum m | "
          "bound m | valid" + (" | TSWAP sum: makespan m / sum m / ms | TSWAP bottleneck: "
                               "makespan m / sum m / ms" if a.tswap else ""))
    summary: list[tuple] = []
    for name in maps:
        path = a.map_dir / f"{name}.map"
        gm = load_grid_map(path, a.cell, RADIUS)
        t0 = time.perf_counter()
        space = RobotSpace.from_scene(gm.scene)
        for step in (0.05, 0.03, 0.02):
            get_lattice(space, step)
        setup = time.perf_counter() - t0
        free = int((~gm.blocked).sum())
        print(f"# {name}: {gm.blocked.shape[1]} x {gm.blocked.shape[0]} cells, "
              f"{gm.scene.workspace[0]:.1f} x {gm.scene.workspace[1]:.1f} m, {free} free, "
              f"{len(gm.scene.obstacles)} obstacle rectangles; space + lattices "
              f"{setup:.2f} s")
        for n in robots:
            if n > free:
                continue
            rows = []
            for seed in range(seeds):
                S, G = random_instance(gm, n, seed)
                t = time.perf_counter()
                plan = plan_paths(space, S, G, time_limit=a.time_limit, seed=seed)
                dt = time.perf_counter() - t
                mk, slow, tot = plan_figures(plan.paths)
                if a.no_check:
                    ok = "-"
                else:
                    errs = check_fleet_plan(gm.scene.to_dict(), S, G, plan, RADIUS)
                    ok = "yes" if not errs else "NO: " + errs[0]
                ok = ok if plan.success else f"failed ({plan.status.value})"
                line = (f"{name} | {n} | {seed} | {dt:.3f} | {plan.iterations} | {mk:.2f} | "
                        f"{slow:.2f} | {tot:.1f} | "
                        f"{plan.stats.get('assignment_bound', float('nan')):.2f} | {ok}")
                ts = {}
                if a.tswap:
                    for mode in ("sum", "bottleneck"):
                        r = run_tswap(a.tswap, path, gm, S, G, mode)
                        ts[mode] = r
                        if r.get("solved"):
                            line += (f" | {r['makespan'] * a.cell:.2f} / "
                                     f"{r.get('sum_of_path_lengths', float('nan')) * a.cell:.1f}"
                                     f" / {r.get('runtime_ms', float('nan')):.0f}")
                        else:
                            line += f" | failed {r.get('error', '')[:40]}"
                print(line, flush=True)
                rows.append((dt, mk, tot, plan.success and ok == "yes", ts))
            summary.append((name, n, rows))
    print("\nmedians | map | robots | solved+valid | time s | makespan m | sum m"
          + (" | makespan / TSWAP sum-mode makespan" if a.tswap else ""))
    for name, n, rows in summary:
        dt = np.median([r[0] for r in rows])
        mk = np.median([r[1] for r in rows])
        tot = np.median([r[2] for r in rows])
        good = sum(r[3] for r in rows)
        line = f"| {name} | {n} | {good}/{len(rows)} | {dt:.3f} | {mk:.2f} | {tot:.1f}"
        if a.tswap:
            ratio = [r[1] / (r[4]["sum"]["makespan"] * a.cell) for r in rows
                     if r[4].get("sum", {}).get("solved") and r[4]["sum"]["makespan"] > 0]
            line += f" | {np.median(ratio):.2f}" if ratio else " | -"
        print(line + " |")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\npeak memory (RSS) {peak:.0f} MB")


if __name__ == "__main__":
    main()
