"""Benchmark of Gspi at fleet scale: hundreds of robots on MAPF benchmark maps.

Instances: a Moving AI map from ``../shared/data/mapf/`` (``lamp.scene.mapf``) with square
cells of ``--cell`` metres (0.15 m), every blocked cell an obstacle; robots of radius
0.05 m start and end at distinct free cell centres drawn with the seed (starts distinct,
goals distinct); any robot may take any goal. ``lamp.mrmp.plan_paths`` with its defaults.

Printed per map, robot count and seed: planning time of the call (the map's space and
lattices are built once per map beforehand, as a fleet planner reuses them; that set-up
is printed per map), Gspi steps, makespan (metres: the time at unit speed of the
synchronised plan, i.e. the sum over steps of the longest move), the slowest robot's path
length, the sum of path lengths, Gspi's assignment bottleneck ``B*`` (lattice distances),
the lower bound ``LB`` and our makespan / ``LB``, and whether the independent checker
(``tests/fleet_checker.py``) accepts the plan; then medians per map and robot count, and
the peak memory of the process.

``LB`` is the bottleneck assignment of straight-line start-goal distances
(``lamp.mrmp.assignment.straight_line_bottleneck``): any planner whose robots take
interchangeable goals and move at unit speed needs at least this long, since some robot
must cover it; it ignores obstacles and other robots, so no planner need reach it.
``GLB`` (unless ``--no-geodesic``) is the same bottleneck over the shortest ways round the
obstacles for disks of the robots' radius (``lamp.mrmp.bottleneck.geodesic_bottleneck``,
the obstacles grown once per map, ``lamp.scene.bounds.grown_obstacles``): also a lower
bound, at least ``LB``, and where the two differ, what the obstacles alone cost.

With ``--tswap ADAPTER`` (``benchmarks/tswap/adapter.py``, which runs TSWAP's public
implementation built from its source outside this repository: see
``benchmarks/tswap/README.md``), the same instances are solved by TSWAP, first in its
default mode (``app -s TSWAP`` without ``-m``: bottleneck, then least sum), which is the
column our makespan and time are divided by (each as a median of per-instance ratios),
then in the modes of ``--tswap-modes`` after it. Its makespan and sum of path lengths are
converted to metres at one cell (``--cell``) per time step; its time is its own
``comp_time``; the adapter checks each TSWAP plan on the grid.

With ``--parts``, a second line per instance says where the makespan goes: the last
robot to arrive, its arrival split into its path length, its waits (rows in which it does
not move before its last move) and its slow moves (rows in which it moves less than the
row's longest move: a row lasts as long as its longest move), its exact lattice shortest
distance and its straight line; the waits and slow moves of all robots as shares of their
summed arrival times; each path against its lattice shortest path and its straight line
(median and max ratio, robots starting within two lattice steps of their goal left out);
and the longest lattice distance of the goals the robots end on beside ``B*``, the
assignment's at the start (goal swaps change it).

With ``--phases``, a line per instance gives the call's time by phase (``MRMPPlan.stats``,
milliseconds): the failed attempts on coarser lattices, then on the lattice that solved
the links, the assignment (its goal searches within), its descent over any-angle
estimates (``lamp.mrmp.anyangle``), the steps, the repair, the straight
lines, the retiming, the timed repair and the rest (input checks, set-up, output); medians
per map and robot count at the end. ``--repeat K`` plans each instance K times and keeps
the fastest call (plans are deterministic: every call gives the same plan), for times on a
busy machine.

Run: ``python benchmarks/bench_fleet.py [--maps random-64-64-20] [--robots 100,200,400,800]
[--seeds 3 | --seed-list 8,13,46] [--parts] [--tswap benchmarks/tswap/adapter.py
--tswap-bin BUILD/app]``;
``--quick``: random-32-32-20 and random-64-64-20 at 100 and 400 robots, one seed.
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
from lamp.mrmp.assignment import straight_line_bottleneck  # noqa: E402
from lamp.mrmp.bottleneck import geodesic_bottleneck  # noqa: E402
from lamp.mrmp.distance_field import get_lattice  # noqa: E402
from lamp.mrmp.gspi import warmup  # noqa: E402
from lamp.scene.bounds import grown_obstacles  # noqa: E402
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


def makespan_parts(paths: np.ndarray) -> dict[str, np.ndarray]:
    """Where each robot's time goes, from the synchronised rows: a row lasts as long as its
    longest move (unit speed). Per robot, up to its last move (its arrival): ``length``
    (its own moves), ``wait`` (rows it does not move in), ``slow`` (rows it moves in
    less than the row's longest move: the difference). ``arrival = length + wait + slow``;
    the makespan is the largest arrival."""
    step = np.hypot(*np.diff(paths, axis=1).transpose(2, 0, 1))  # (N, T-1)
    N = len(paths)
    if step.size == 0:
        z = np.zeros(N)
        return {"length": z, "wait": z, "slow": z, "arrival": z}
    dur = step.max(axis=0)
    moving = step > 0
    last = np.where(moving.any(axis=1), step.shape[1] - np.argmax(moving[:, ::-1], axis=1), 0)
    before = np.arange(step.shape[1])[None, :] < last[:, None]
    wait = np.where(before & ~moving, dur[None, :], 0.0).sum(axis=1)
    slow = np.where(before & moving, dur[None, :] - step, 0.0).sum(axis=1)
    length = step.sum(axis=1)
    return {"length": length, "wait": wait, "slow": slow, "arrival": length + wait + slow}


def lattice_distances(space: RobotSpace, plan, S: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Each robot's exact lattice distance from its start to the goal it ends on, on the
    lattice the plan was found on (the planner's own links and lazy searches; nan for a
    robot without a goal)."""
    from lamp.mrmp.goal_distances import GoalDistances, hval
    from lamp.mrmp.links import link_special_vertices

    L = plan.stats["attempts"][-1]["lattice_step"]
    lat = get_lattice(space, L)
    c_s = space.clearance(S, exact=True)
    c_g = space.clearance(G, exact=True)
    links = link_special_vertices(space, lat, S, G, c_s, c_g, 1.5 * L, {})
    N, M = len(S), len(G)
    hs = GoalDistances.build(links.goal_links, G, lat, N + M)
    return np.array([hval(int(g), lat.V + i, links.graph, lat.V, lat.V + N, hs) if g >= 0
                     else np.nan for i, g in enumerate(plan.goal_of.tolist())])


def cells_of(gm, pts: np.ndarray) -> np.ndarray:
    """(row, col) of cell centres, row 0 at the top of the map file."""
    H = gm.blocked.shape[0]
    col = np.rint(pts[:, 0] / gm.cell - 0.5).astype(int)
    row = H - 1 - np.rint(pts[:, 1] / gm.cell - 0.5).astype(int)
    return np.stack([row, col], 1)


def run_tswap(adapter: str, map_path: Path, gm, S: np.ndarray, G: np.ndarray,
              mode: str, tswap_bin: str | None = None) -> dict:
    """TSWAP's result on one instance through the adapter (``solved``, ``makespan`` in
    steps, ``sum_of_path_lengths`` in cells, ``runtime_ms``), or ``solved: False`` and
    ``error``."""
    with tempfile.TemporaryDirectory() as tmp:
        fs, fg = Path(tmp) / "s.txt", Path(tmp) / "g.txt"
        np.savetxt(fs, cells_of(gm, S), fmt="%d")
        np.savetxt(fg, cells_of(gm, G), fmt="%d")
        cmd = [sys.executable, adapter, "--map", str(map_path), "--starts", str(fs),
               "--goals", str(fg), "--mode", mode, "--json"]
        if tswap_bin:
            cmd += ["--bin", tswap_bin]
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    try:
        return json.loads(out.stdout.strip().splitlines()[-1])
    except (json.JSONDecodeError, IndexError):
        return {"solved": False, "error": (out.stderr or out.stdout)[-200:]}


def parts_line(plan, space: RobotSpace, S: np.ndarray, G: np.ndarray) -> str:
    """Where the makespan goes (``--parts``): the last robot to arrive (its path length,
    waits, slow moves and lattice shortest distance), all robots' summed waits and slow
    moves as shares of their summed arrival times, and each path against its lattice
    shortest path and its straight line (median and max of the ratios)."""
    p = makespan_parts(plan.paths)
    short = lattice_distances(space, plan, S, G)
    held = plan.goal_of >= 0
    line = np.hypot(*(S[held] - G[plan.goal_of[held]]).T)
    L = plan.stats["attempts"][-1]["lattice_step"]
    moved = held & (short > 2 * L)  # robots starting on or next to their goal left out
    det = p["length"][moved] / short[moved]
    straight = p["length"][held][line > 2 * L] / line[line > 2 * L]
    c = int(np.argmax(p["arrival"]))
    tot = p["arrival"].sum()
    return (f"last robot: arrival {p['arrival'][c]:.2f} = path {p['length'][c]:.2f} + wait "
            f"{p['wait'][c]:.2f} + slow {p['slow'][c]:.2f}, lattice shortest "
            f"{short[c]:.2f}, straight {np.hypot(*(S[c] - G[plan.goal_of[c]])):.2f} | "
            f"all: wait {p['wait'].sum() / tot:.0%}, slow {p['slow'].sum() / tot:.0%} of "
            f"summed arrivals; path / lattice shortest median {np.median(det):.2f} max "
            f"{det.max():.2f}; path / straight median {np.median(straight):.2f} max "
            f"{straight.max():.2f}; robots arriving after 0.9 x makespan "
            f"{int((p['arrival'] > 0.9 * p['arrival'].max()).sum())}; final goals' longest "
            f"lattice distance {np.nanmax(short):.2f} (B* {plan.stats['assignment_bound']:.2f})")


PHASES = ("links", "assignment", "descent", "steps", "repair", "shortcut", "retime",
          "timed_repair")


def phase_times(plan, dt: float) -> dict[str, float]:
    """The call's time by phase, seconds: ``failed`` (the attempts on lattices that did
    not solve), the phases of :data:`PHASES` on the last lattice (``plan.stats``), and
    ``rest`` (what they leave of the call's time ``dt``)."""
    att = plan.stats.get("attempts", [])
    out = {"failed": sum(sum(v for k, v in a.items() if k.startswith("time_"))
                         for a in att[:-1])}
    for k in PHASES:
        out[k] = float(plan.stats.get(f"time_{k}", 0.0)) if att else 0.0
    out["rest"] = dt - sum(out.values())
    return out


def _med(values: list[float]) -> str:
    """Median to two decimals, ``-`` for none."""
    return f"{np.median(values):.2f}" if values else "-"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--maps", default="random-32-32-20,random-64-64-20,empty-64-64,den520d")
    ap.add_argument("--robots", default="100,200,400,800")
    ap.add_argument("--seeds", type=int, default=3, help="seeds 0 .. SEEDS-1")
    ap.add_argument("--seed-list", default=None,
                    help="these seeds instead (comma-separated, e.g. 8,13,46)")
    ap.add_argument("--cell", type=float, default=0.15)
    ap.add_argument("--map-dir", type=Path, default=MAP_DIR, help="folder of the .map files")
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--tswap", default=None,
                    help="TSWAP adapter script, benchmarks/tswap/adapter.py (optional)")
    ap.add_argument("--tswap-bin", default=None,
                    help="TSWAP's binary, passed to the adapter (else its $TSWAP_BIN)")
    ap.add_argument("--tswap-modes", default="bottleneck,linear",
                    help="TSWAP modes run after its default, as extra columns")
    ap.add_argument("--no-check", action="store_true", help="skip the independent checker")
    ap.add_argument("--geodesic", action=argparse.BooleanOptionalAction, default=True,
                    help="the bound round the obstacles (GLB) beside LB (default: on)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--parts", action="store_true",
                    help="print where the makespan goes (waits, slow moves, detours)")
    ap.add_argument("--phases", action="store_true",
                    help="print the call's time by phase (ms) per instance, and medians")
    ap.add_argument("--repeat", type=int, default=1,
                    help="plan each instance this many times, keep the fastest call")
    a = ap.parse_args()
    maps = a.maps.split(",")
    robots = [int(v) for v in a.robots.split(",")]
    seeds = (list(range(a.seeds)) if a.seed_list is None
             else [int(v) for v in a.seed_list.split(",")])
    if a.quick:
        maps, robots, seeds = ["random-32-32-20", "random-64-64-20"], [100, 400], [0]
    modes = ["default"] + [m for m in a.tswap_modes.split(",") if m and m != "default"]
    if not a.tswap:
        modes = []
    warmup()
    print("map | robots | seed | time s | steps | makespan m | slowest path m | sum m | "
          "Gspi B* m | LB m | makespan / LB"
          + (" | GLB m | makespan / GLB" if a.geodesic else "") + " | valid"
          + "".join(f" | TSWAP {m}: makespan m / sum m / ms" for m in modes)
          + (" | TSWAP default makespan / LB"
             + (" | TSWAP default makespan / GLB" if a.geodesic else "")
             + " | makespan / TSWAP default | time / TSWAP default" if modes else ""))
    summary: list[tuple] = []
    for name in maps:
        path = a.map_dir / f"{name}.map"
        gm = load_grid_map(path, a.cell, RADIUS)
        t0 = time.perf_counter()
        space = RobotSpace.from_scene(gm.scene)
        for step in (0.05, 0.03, 0.02):
            get_lattice(space, step)
        setup = time.perf_counter() - t0
        t0 = time.perf_counter()
        grown = (grown_obstacles(tuple(gm.scene.obstacles), tuple(gm.scene.workspace), RADIUS,
                                 merge=True) if a.geodesic else None)
        grown_s = time.perf_counter() - t0
        free = int((~gm.blocked).sum())
        print(f"# {name}: {gm.blocked.shape[1]} x {gm.blocked.shape[0]} cells, "
              f"{gm.scene.workspace[0]:.1f} x {gm.scene.workspace[1]:.1f} m, {free} free, "
              f"{len(gm.scene.obstacles)} obstacle rectangles; space + lattices "
              f"{setup:.2f} s" + (f"; grown obstacles for GLB {grown_s:.1f} s" if grown else ""))
        for n in robots:
            if n > free:
                continue
            rows = []
            for seed in seeds:
                S, G = random_instance(gm, n, seed)
                dt = np.inf
                for _ in range(max(1, a.repeat)):
                    t = time.perf_counter()
                    got = plan_paths(space, S, G, time_limit=a.time_limit, seed=seed)
                    if time.perf_counter() - t < dt:
                        dt, plan = time.perf_counter() - t, got
                mk, slow, tot = plan_figures(plan.paths)
                lb = straight_line_bottleneck(S, G)
                glb = geodesic_bottleneck(grown, S, G) if grown else float("nan")
                if a.no_check:
                    ok = "-"
                else:
                    errs = check_fleet_plan(gm.scene.to_dict(), S, G, plan, RADIUS)
                    ok = "yes" if not errs else "NO: " + errs[0]
                ok = ok if plan.success else f"failed ({plan.status.value})"
                good = plan.success and ok in ("yes", "-")
                line = (f"{name} | {n} | {seed} | {dt:.3f} | {plan.iterations} | {mk:.2f} | "
                        f"{slow:.2f} | {tot:.1f} | "
                        f"{plan.stats.get('assignment_bound', float('nan')):.2f} | "
                        f"{lb:.2f} | {mk / lb:.2f}"
                        + (f" | {glb:.2f} | {mk / glb:.2f}" if grown else "") + f" | {ok}")
                ts = {}
                for mode in modes:
                    r = run_tswap(a.tswap, path, gm, S, G, mode, a.tswap_bin)
                    if r.get("solved"):
                        r["makespan_m"] = r["makespan"] * a.cell
                        r["sum_m"] = r.get("sum_of_path_lengths", float("nan")) * a.cell
                        line += (f" | {r['makespan_m']:.2f} / {r['sum_m']:.1f}"
                                 f" / {r.get('runtime_ms', float('nan')):.0f}")
                    else:
                        line += f" | failed {r.get('error', '')[:60]!r}"
                    ts[mode] = r
                if modes:
                    d = ts["default"]
                    line += (f" | {d['makespan_m'] / lb:.2f}"
                             + (f" | {d['makespan_m'] / glb:.2f}" if grown else "")
                             + f" | {mk / d['makespan_m']:.2f}"
                             if d.get("solved") and d["makespan"] > 0
                             else " | -" * (3 if grown else 2))
                    line += (f" | {1e3 * dt / d['runtime_ms']:.2f}"
                             if d.get("solved") and d.get("runtime_ms", 0) > 0 else " | -")
                print(line, flush=True)
                if a.parts and plan.success:
                    print("  " + parts_line(plan, space, S, G), flush=True)
                ph = phase_times(plan, dt)
                if a.phases:
                    print("  phases ms: " + " | ".join(f"{k} {1e3 * v:.1f}"
                                                        for k, v in ph.items()), flush=True)
                rows.append({"dt": dt, "mk": mk, "tot": tot, "good": good, "lb": lb, "glb": glb,
                             "ts": ts, "ph": ph})
            summary.append((name, n, rows))
    print("\nmedians over the seeds (ratios: medians of the per-instance ratios)")
    geo = a.geodesic
    head = ("| map | robots | LB m" + (" | GLB m" if geo else "")
            + " | ours: solved, valid | time s | makespan m | / LB" + (" | / GLB" if geo else "")
            + " | sum m")
    if modes:
        head += (" | TSWAP default: solved | time ms | makespan m | / LB"
                 + (" | / GLB" if geo else "") + " | sum m "
                 "| ours / TSWAP default | time / TSWAP default"
                 + "".join(f" | TSWAP {m}: makespan m / ms" for m in modes[1:]))
    print(head + " |")
    for name, n, rows in summary:
        lb = [r["lb"] for r in rows]
        line = (f"| {name} | {n} | {_med(lb)}"
                + (f" | {_med([r['glb'] for r in rows])}" if geo else "")
                + f" | {sum(r['good'] for r in rows)}/{len(rows)} | "
                f"{np.median([r['dt'] for r in rows]):.3f} | "
                f"{_med([r['mk'] for r in rows])} | "
                f"{_med([r['mk'] / r['lb'] for r in rows])}"
                + (f" | {_med([r['mk'] / r['glb'] for r in rows])}" if geo else "")
                + f" | {np.median([r['tot'] for r in rows]):.0f}")
        for k, mode in enumerate(modes):
            done = [r for r in rows if r["ts"][mode].get("solved")]
            ms = [r["ts"][mode]["runtime_ms"] for r in done]
            mks = [r["ts"][mode]["makespan_m"] for r in done]
            if k == 0:
                line += (f" | {len(done)}/{len(rows)} | "
                         + (f"{np.median(ms):.0f}" if ms else "-")
                         + f" | {_med(mks)} | "
                         f"{_med([r['ts'][mode]['makespan_m'] / r['lb'] for r in done])} | "
                         + (f"{_med([r['ts'][mode]['makespan_m'] / r['glb'] for r in done])}"
                            " | " if geo else "")
                         + (f"{np.median([r['ts'][mode]['sum_m'] for r in done]):.0f}"
                            if done else "-") + " | "
                         + _med([r["mk"] / r["ts"][mode]["makespan_m"] for r in done
                                 if r["ts"][mode]["makespan"] > 0]) + " | "
                         + _med([1e3 * r["dt"] / r["ts"][mode]["runtime_ms"] for r in done
                                 if r["ts"][mode].get("runtime_ms", 0) > 0]))
            else:
                line += (f" | {_med(mks)} / " + (f"{np.median(ms):.0f}" if ms else "-")
                         + ("" if len(done) == len(rows) else f" ({len(done)} solved)"))
        print(line + " |")
    if a.phases:
        print("\nmedian time by phase, ms (each phase's median over the seeds)")
        keys = list(summary[0][2][0]["ph"]) if summary and summary[0][2] else []
        print("| map | robots | " + " | ".join(keys) + " | call |")
        for name, n, rows in summary:
            print(f"| {name} | {n} | "
                  + " | ".join(f"{1e3 * np.median([r['ph'][k] for r in rows]):.1f}"
                               for k in keys)
                  + f" | {1e3 * np.median([r['dt'] for r in rows]):.1f} |")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\npeak memory (RSS) {peak:.0f} MB")


if __name__ == "__main__":
    main()
