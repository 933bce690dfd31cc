"""Run TSWAP's public implementation (https://github.com/Kei18/tswap, built with
``build.sh``) on one instance and print its figures.

    python benchmarks/tswap/adapter.py --bin BUILD/app --map MAP.map --starts S.txt \
        --goals G.txt [--mode default] [--json]

``--starts`` / ``--goals``: one ``row col`` pair per line (row 0 at the top of the map
file, as ``benchmarks/bench_fleet.py`` writes them); robot i starts in line i of the
starts, and any robot may take any goal. ``--bin`` defaults to ``$TSWAP_BIN``.

``--mode`` names TSWAP's target-assignment mode (its ``-m``): ``default`` is what
``app -s TSWAP`` does without ``-m`` (``0``, bottleneck then linear: the least longest
distance, then the least sum among those); ``bottleneck`` (``2``), ``linear`` (``3``,
least sum only), ``greedy`` (``4``), ``greedy-swap`` (``5``); or the number itself.

The adapter writes TSWAP's instance file (the map is read from where it is, not copied),
runs ``app -s TSWAP -m MODE``, reads the result file and checks the plan itself: starts
and goals as given (goals as a set), every step stays or moves to a 4-neighbouring free
cell, no two robots on one cell, no two robots swapping cells. It prints ``solved``,
``makespan`` (time steps), ``soc`` (TSWAP's sum of costs: each robot's last arrival time
at its final cell), ``sum_of_path_lengths`` (moves, i.e. cells travelled, waits not
counted), ``runtime_ms`` (TSWAP's own ``comp_time``: target assignment, including its
lazy distance searches, and path planning; not reading the map, building the grid graph
or writing the result) and ``wall_ms`` (the whole process); with ``--json`` one JSON
object on the last line.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: TSWAP's ``-m`` values (``GoalAllocator::MODE``; ``app --help``).
MODES = {"default": 0, "bottleneck-linear": 0, "bottleneck": 2, "linear": 3, "sum": 3,
         "greedy": 4, "greedy-swap": 5}
#: Longer than any path below the root: the binary opens ``<its map folder> + map_file``
#: (a folder compiled in), so a relative path that climbs to ``/`` reaches any map.
_UP = "../" * 64


def read_cells(path: Path) -> np.ndarray:
    """(K, 2) ``row col`` cells of a file."""
    return np.loadtxt(path, dtype=int, ndmin=2).reshape(-1, 2)


def free_cells(map_path: Path) -> np.ndarray:
    """``free[row, col]`` of a Moving AI map, as TSWAP reads it (``@`` and ``T`` blocked)."""
    lines = Path(map_path).read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.strip() == "map")
    rows = [ln.rstrip("\r") for ln in lines[i + 1:] if ln.strip()]
    return np.array([[ch not in "@T" for ch in r] for r in rows])


def write_instance(path: Path, map_path: Path, S: np.ndarray, G: np.ndarray,
                   max_timestep: int, max_comp_ms: int) -> None:
    lines = [f"map_file={_UP}{Path(map_path).resolve().as_posix().lstrip('/')}",
             f"agents={len(S)}", "seed=0", "random_problem=0",
             f"max_timestep={max_timestep}", f"max_comp_time={max_comp_ms}"]
    # TSWAP's locations are (x, y) = (column, row), (0, 0) the top left
    lines += [f"{s[1]},{s[0]},{g[1]},{g[0]}" for s, g in zip(S.tolist(), G.tolist(), strict=True)]
    path.write_text("\n".join(lines) + "\n")


def parse_result(text: str) -> dict:
    """The ``key=value`` lines and the plan, (T+1, N, 2) ``row col``, of a result file."""
    out: dict = {}
    plan = []
    in_plan = False
    for ln in text.splitlines():
        if in_plan:
            m = re.match(r"(\d+):(.*)", ln)
            if m:
                xy = re.findall(r"\((\d+),(\d+)\)", m.group(2))
                plan.append([(int(y), int(x)) for x, y in xy])
            continue
        if ln.startswith("solution="):
            in_plan = True
        elif "=" in ln:
            k, v = ln.split("=", 1)
            out[k] = v
    out["plan"] = np.array(plan, dtype=int).reshape(len(plan), -1, 2)
    return out


def check_plan(plan: np.ndarray, S: np.ndarray, G: np.ndarray, free: np.ndarray) -> str:
    """The first fault of a grid plan (``""`` if none); see the module docstring."""
    if len(plan) == 0 or plan.shape[1] != len(S):
        return "plan has no steps or not one cell per robot"
    if not (plan[0] == S).all():
        return "plan does not start at the starts"
    if sorted(map(tuple, plan[-1].tolist())) != sorted(map(tuple, G.tolist())):
        return "plan does not end on the goals"
    H, W = free.shape
    r, c = plan[..., 0], plan[..., 1]
    if (r < 0).any() or (r >= H).any() or (c < 0).any() or (c >= W).any() or \
            not free[r, c].all():
        return "plan leaves the free cells"
    if (np.abs(np.diff(plan, axis=0)).sum(axis=2) > 1).any():
        return "a move longer than one 4-connected cell"
    ids = r * W + c  # (T+1, N)
    for t in range(len(plan)):
        if len(np.unique(ids[t])) != ids.shape[1]:
            return f"two robots on one cell at step {t}"
    for t in range(len(plan) - 1):
        moved = ids[t] != ids[t + 1]
        a = dict(zip(ids[t][moved].tolist(), ids[t + 1][moved].tolist(), strict=True))
        if any(a.get(v) == u for u, v in a.items()):
            return f"two robots swap cells at step {t}"
    return ""


def run(bin_path: str, map_path: Path, S: np.ndarray, G: np.ndarray, mode: str,
        max_comp_ms: int = 60000, max_timestep: int = 5000) -> dict:
    m = MODES[mode] if mode in MODES else int(mode)
    with tempfile.TemporaryDirectory() as tmp:
        inst, res = Path(tmp) / "instance.txt", Path(tmp) / "result.txt"
        write_instance(inst, map_path, S, G, max_timestep, max_comp_ms)
        t0 = time.perf_counter()
        p = subprocess.run([bin_path, "-i", str(inst), "-s", "TSWAP", "-o", str(res),
                            "-m", str(m)], capture_output=True, text=True,
                           timeout=max_comp_ms / 1000 + 120)
        wall = (time.perf_counter() - t0) * 1000
        if p.returncode != 0 or not res.exists():
            return {"solved": False, "mode": mode, "m": m,
                    "error": (p.stderr or p.stdout)[-300:]}
        r = parse_result(res.read_text())
    plan = r["plan"]
    fault = check_plan(plan, S, G, free_cells(map_path)) if r.get("solved") == "1" else ""
    moves = int((np.abs(np.diff(plan, axis=0)).sum(axis=2) > 0).sum()) if len(plan) else 0
    out = {"solved": r.get("solved") == "1" and not fault, "mode": mode, "m": m,
           "makespan": int(r["makespan"]), "soc": int(r["soc"]),
           "sum_of_path_lengths": moves, "runtime_ms": float(r["comp_time"]),
           "wall_ms": round(wall, 1)}
    if fault:
        out["error"] = "plan check: " + fault
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=os.environ.get("TSWAP_BIN"),
                    help="TSWAP's app binary (default $TSWAP_BIN)")
    ap.add_argument("--map", type=Path, required=True)
    ap.add_argument("--starts", type=Path, required=True)
    ap.add_argument("--goals", type=Path, required=True)
    ap.add_argument("--mode", default="default", help=", ".join(MODES) + " or a number")
    ap.add_argument("--max-comp-ms", type=int, default=60000)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    if not a.bin:
        sys.exit("give TSWAP's binary with --bin or $TSWAP_BIN (see build.sh)")
    r = run(a.bin, a.map, read_cells(a.starts), read_cells(a.goals), a.mode, a.max_comp_ms)
    print(json.dumps(r) if a.json else " ".join(f"{k}={v}" for k, v in r.items()))


if __name__ == "__main__":
    main()
