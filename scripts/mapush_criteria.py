"""Success of the ``mapush`` runs of a ``lamp bench`` results file under both criteria.

Prints, per suite, the share of scenes solved under MAPush's criterion (every object within
0.5 m of its goal position within two simulated minutes, orientation ignored:
``stats.mapush_objects``) and under the scene format's strict one (0.1 m / 0.1 rad), and
the objects placed under each; the newest run of each job counts.

Run: ``python scripts/mapush_criteria.py OUT/results.jsonl``
"""

from __future__ import annotations

import sys
from collections import defaultdict

from lamp.bench.jobs import latest_by_key, read_records


def main(path: str) -> None:
    rows: dict[str, list[tuple[int, int, int]]] = defaultdict(list)
    for (suite, _, planner, _), rec in latest_by_key(read_records(path)).items():
        if planner != "mapush" or rec.get("status") != "ok":
            continue
        per_object = rec.get("stats", {}).get("mapush_objects", [])
        loose = sum(bool(o.get("mapush_success")) for o in per_object)
        strict = sum(bool(o["success"]) for o in rec["objects"])
        rows[suite].append((loose, strict, len(rec["objects"])))
    print("| suite | scenes | MAPush criterion (0.5 m, 120 s) | strict (0.1 m, 0.1 rad) "
          "| objects: MAPush / strict |")
    print("|---|---|---|---|---|")
    for suite, runs in rows.items():
        n = len(runs)
        loose = sum(a == k for a, _, k in runs)
        strict = sum(b == k for _, b, k in runs)
        objects = sum(k for _, _, k in runs)
        print(f"| {suite} | {n} | {loose}/{n} ({100 * loose / n:.0f}%) "
              f"| {strict}/{n} ({100 * strict / n:.0f}%) "
              f"| {sum(a for a, _, _ in runs)} / {sum(b for _, b, _ in runs)} of {objects} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
