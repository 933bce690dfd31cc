"""Success of the ``mapush`` runs of a ``lamp bench`` results file under both criteria.

Prints, per suite, the share of scenes solved under MAPush's criterion (every object within
0.5 m of its goal position within two simulated minutes, orientation ignored:
``stats.mapush_success``) and under the scene format's strict one (0.1 m / 0.1 rad).

Run: ``python scripts/mapush_criteria.py OUT/results.jsonl``
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict


def main(path: str) -> None:
    rows: dict[str, list[tuple[bool, bool]]] = defaultdict(list)
    with open(path, encoding="utf-8") as f:
        for line in f:
            rec = json.loads(line)
            if rec.get("planner") != "mapush" or rec.get("status") != "ok":
                continue
            loose = bool(rec.get("stats", {}).get("mapush_success", False))
            rows[rec.get("suite", "?")].append((loose, bool(rec["success"])))
    print("| suite | scenes | MAPush criterion (0.5 m, 120 s) | strict (0.1 m, 0.1 rad) |")
    print("|---|---|---|---|")
    for suite, runs in rows.items():
        n = len(runs)
        loose = sum(a for a, _ in runs)
        strict = sum(b for _, b in runs)
        print(f"| {suite} | {n} | {loose}/{n} ({100 * loose / n:.0f}%) "
              f"| {strict}/{n} ({100 * strict / n:.0f}%) |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
