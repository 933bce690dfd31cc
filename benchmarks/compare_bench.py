"""Compare two ``lamp bench`` output folders run by run: success, segments, makespan, the
final object poses (exact), replans, failure reasons and the stats counters.

    python benchmarks/compare_bench.py BEFORE AFTER

Prints one line per differing run and a summary; exits 1 when any compared field differs
or a run is missing from either side (wall and planning times are not compared).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

#: Counters of ``stats`` that depend on the clock only through the outer caps.
STATS = ("verify_calls", "verify_success", "model_calls", "gspi_calls", "gspi_success",
         "gspi_timeouts", "cache_hits", "failure_reasons")


def load(folder: Path) -> dict[tuple, dict]:
    runs = {}
    for line in (folder / "results.jsonl").read_text().splitlines():
        if line.strip():
            r = json.loads(line)
            runs[(r["suite"], r["scene"], r["planner"], r["seed"])] = r
    return runs


def fields(r: dict) -> dict:
    out = {k: r.get(k) for k in ("status", "success", "segments", "makespan", "replans")}
    out["final_poses"] = [o["final_pose"] for o in r.get("objects", [])]
    out["stats"] = {k: r.get("stats", {}).get(k) for k in STATS}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before", type=Path)
    ap.add_argument("after", type=Path)
    args = ap.parse_args(argv)
    a, b = load(args.before), load(args.after)
    bad = 0
    for key in sorted(set(a) | set(b)):
        if key not in a or key not in b:
            print(f"{'/'.join(map(str, key))}: only in {'after' if key in b else 'before'}")
            bad += 1
            continue
        fa, fb = fields(a[key]), fields(b[key])
        diff = [k for k in fa if fa[k] != fb[k]]
        if diff:
            bad += 1
            print(f"{'/'.join(map(str, key))}: differs in {', '.join(diff)}")
            for k in diff:
                print(f"    {k}: {fa[k]!r} -> {fb[k]!r}")
    same = len(set(a) & set(b)) - sum(1 for k in set(a) & set(b) if fields(a[k]) != fields(b[k]))
    print(f"{len(a)} runs before, {len(b)} after: {same} identical "
          "(success, segments, makespan, replans, final poses, stats counters), "
          f"{bad} differing or missing")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
