"""The concurrent schedule as the fleet grows: robots and loads beyond the ``fleet`` family.

Scenes come from ``lamp.suites.fleet.generate_custom`` (the family's generator and checks,
any size): one map kind and size, robots and objects scaled together, three robots per
object by default; or, with ``--map``, from ``generate_on_map`` on a map the family never
saw (a scene file, or a Moving AI grid map such as ``../shared/data/mapf/den520d.map``
with ``--cell`` metres per cell). Each point is one ``lamp run --schedule concurrent --record`` in its own
process (LAMP-Lazy, seed 0); printed per point: objects placed, makespan (simulated s),
wall time, planning per executed segment, planning in all, peak RSS of the process, and
the violations the independent safety check finds in the recording
(``lamp.record.safety``); and each point's wall time and memory against the first's.

    python benchmarks/bench_fleet_scale.py [--kind aisles] [--size 40 30]
        [--points 12x4 24x8 48x16 96x32] [--time-cap 1800] [--out DIR]
    python benchmarks/bench_fleet_scale.py --map MAP [--cell 0.5] --points 18x6 36x12

Finished points are kept in ``DIR`` and not rerun: a point's folder is named by its size and
a digest of its scene file, so only the same scene reuses it (delete it to rerun).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

from lamp.record.safety import check_run_dir
from lamp.scene.mapf import load_map
from lamp.scene.model import Scene
from lamp.scene.save import save_scene
from lamp.suites.fleet import KINDS, generate_custom, generate_on_map


def point(text: str) -> tuple[int, int]:
    """``ROBOTSxOBJECTS`` as (robots, objects)."""
    try:
        n_robots, n_objects = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected ROBOTSxOBJECTS such as 24x8, got {text!r}") from None
    return n_robots, n_objects


def run_point(scene: Path, out: Path, time_cap: float) -> tuple[float, float]:
    """``lamp run`` of ``scene`` concurrently into ``out``, killed after ``time_cap`` s:
    (wall s, peak RSS GB)."""
    lamp = shutil.which("lamp", path=str(Path(sys.executable).parent)) or "lamp"
    cmd = [lamp, "run", str(scene), "--schedule", "concurrent", "--seed", "0", "--quiet",
           "--out", str(out)]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL)
    timer = threading.Timer(time_cap, proc.kill)
    timer.start()
    _, status, usage = os.wait4(proc.pid, 0)
    timer.cancel()
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status) not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)} exited with {os.waitstatus_to_exitcode(status)}")
    return wall, usage.ru_maxrss / 2**20  # kB -> GB (Linux)


def point_folder(out: Path, n_robots: int, n_objects: int, scene: Scene) -> Path:
    """The folder of a point's run: named by its size and a digest of its scene file, which
    it holds (a point of another map, kind or size never reuses a finished run)."""
    staged = out / f".{n_robots}r{n_objects}o.yaml"
    save_scene(scene, staged)
    digest = hashlib.sha256(staged.read_bytes()).hexdigest()[:12]
    folder = out / f"{n_robots}r{n_objects}o-{digest}"
    folder.mkdir(exist_ok=True)
    staged.replace(folder / "scene.yaml")
    return folder


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kind", default="aisles", choices=KINDS,
                    help="fleet map kind (default: aisles)")
    ap.add_argument("--size", type=float, nargs=2, default=[40.0, 30.0], metavar=("W", "H"),
                    help="map size in metres (default: 40 30)")
    ap.add_argument("--map", type=Path, help="a scene file or Moving AI .map to put the "
                    "objects on instead of a generated map (--kind and --size unused)")
    ap.add_argument("--cell", type=float, default=0.5,
                    help="side of a .map file's cells in metres (default: 0.5)")
    ap.add_argument("--points", nargs="+", type=point,
                    default=[(12, 4), (24, 8), (48, 16), (96, 32)],
                    help="ROBOTSxOBJECTS per point (default: 12x4 24x8 48x16 96x32)")
    ap.add_argument("--time-cap", type=float, default=1800.0,
                    help="wall-clock cap per run in seconds (default: 1800)")
    ap.add_argument("--out", type=Path, default=Path("fleet-scale"), help="output folder")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    try:
        base = None if args.map is None else load_map(args.map, args.cell)
    except ValueError as err:  # InputError: names the file and what is wrong
        ap.error(str(err))
    if base is None:
        print(f"{args.kind} {args.size[0]:g} x {args.size[1]:g} m, LAMP-Lazy concurrent, "
              "seed 0")
    else:
        W, H = base.workspace
        print(f"{args.map.name} ({W:g} x {H:g} m), LAMP-Lazy concurrent, seed 0")
    print("robots | objects | placed | makespan (s) | wall (s) | plan/seg (s) | "
          "plan total (s) | peak RSS (GB) | safety violations")
    first = None
    for n_robots, n_objects in args.points:
        try:
            gen = (generate_custom(args.kind, tuple(args.size), n_objects, n_robots)
                   if base is None else generate_on_map(base, n_objects, n_robots))
        except ValueError as err:
            ap.error(str(err))
        folder = point_folder(args.out, n_robots, n_objects, gen.scene)
        done = folder / "point.json"
        if not done.exists():
            wall, rss = run_point(folder / "scene.yaml", folder / "run", args.time_cap)
            done.write_text(json.dumps({"wall_s": wall, "peak_rss_gb": rss}))
        point_info = json.loads(done.read_text())
        res = json.loads((folder / "run" / "result.json").read_text())
        placed = sum(o["success"] for o in res["objects"])
        violations = len(check_run_dir(folder / "run").violations)
        span = f"{res['makespan_s']:.1f}" if res["success"] else "-"
        print(f"{n_robots} | {n_objects} | {placed}/{n_objects} | {span} | "
              f"{point_info['wall_s']:.0f} | {res['planning_time_per_segment_s']:.3f} | "
              f"{res['total_planning_time_s']:.1f} | {point_info['peak_rss_gb']:.2f} | "
              f"{violations}", flush=True)
        first = first or point_info
        if point_info is not first:
            print(f"   vs first point: wall {point_info['wall_s'] / first['wall_s']:.1f}x, "
                  f"memory {point_info['peak_rss_gb'] / first['peak_rss_gb']:.2f}x")


if __name__ == "__main__":
    main()
