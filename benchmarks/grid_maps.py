"""Write three grid maps of kinds the built-in suites do not have, in the Moving AI format
(``lamp suite fleet-scene OUT --map FILE --cell C`` and ``bench_fleet_scale.py --map``
read them), for trying the planners on maps they were never tuned on:

- ``maze-31-4.map``: a 6 x 6 perfect maze (depth-first, seeded) of 4-cell corridors and
  1-cell walls (the kind of Moving AI's ``maze-32-32-4``);
- ``rooms-41-9.map``: 4 x 4 rooms of 9 x 9 cells, each wall between two rooms with one
  2-cell door at a seeded place (the kind of ``room-64-64-8``);
- ``warehouse-57-33.map``: 7 rows of shelf blocks (2 cells deep, 10 long, 2-cell gaps)
  between 2-cell aisles, open ends (the kind of ``warehouse-10-20-10-2-1``).

The same seed writes the same files. Results on them: ``docs/fleet.md``, "On a map of
your own".

    python benchmarks/grid_maps.py --out maps [--seed 3]
"""

from __future__ import annotations

import argparse
import random
from pathlib import Path

Grid = list[list[str]]


def maze(n: int, corridor: int, rng: random.Random) -> Grid:
    """An ``n`` x ``n`` perfect maze of ``corridor``-cell passages and 1-cell walls."""
    side = n * (corridor + 1) + 1
    g = [["@"] * side for _ in range(side)]

    def open_room(i: int, j: int) -> None:
        for y in range(corridor):
            for x in range(corridor):
                g[1 + i * (corridor + 1) + y][1 + j * (corridor + 1) + x] = "."

    seen, stack = {(0, 0)}, [(0, 0)]
    open_room(0, 0)
    while stack:
        i, j = stack[-1]
        nbrs = [(i + a, j + b) for a, b in ((1, 0), (-1, 0), (0, 1), (0, -1))
                if 0 <= i + a < n and 0 <= j + b < n and (i + a, j + b) not in seen]
        if not nbrs:
            stack.pop()
            continue
        a, b = rng.choice(nbrs)
        seen.add((a, b))
        open_room(a, b)
        stack.append((a, b))
        for t in range(corridor):  # the wall between the two rooms
            if a != i:
                g[max(a, i) * (corridor + 1)][1 + j * (corridor + 1) + t] = "."
            else:
                g[1 + i * (corridor + 1) + t][max(b, j) * (corridor + 1)] = "."
    return g


def rooms(n: int, room: int, door: int, rng: random.Random) -> Grid:
    """``n`` x ``n`` rooms of ``room`` cells, one ``door``-cell door in each inner wall."""
    side = n * (room + 1) + 1
    g = [["."] * side for _ in range(side)]
    for k in range(0, side, room + 1):
        for t in range(side):
            g[k][t] = g[t][k] = "@"
    for i in range(n):
        for j in range(n):
            if i + 1 < n:
                x0 = j * (room + 1) + 1 + rng.randrange(room - door + 1)
                for t in range(door):
                    g[(i + 1) * (room + 1)][x0 + t] = "."
            if j + 1 < n:
                y0 = i * (room + 1) + 1 + rng.randrange(room - door + 1)
                for t in range(door):
                    g[y0 + t][(j + 1) * (room + 1)] = "."
    return g


def warehouse(width: int, height: int, margin: int = 6, block: int = 10, gap: int = 2,
              aisle: int = 2, depth: int = 2) -> Grid:
    """Rows of shelf blocks (``depth`` x ``block`` cells, ``gap`` apart) between
    ``aisle``-cell aisles, ``margin`` free cells at the ends, 4 above and at least 3 below."""
    g = [["."] * width for _ in range(height)]
    for y0 in range(4, height - 4, depth + aisle):
        for x in range(margin, width - margin):
            if (x - margin) % (block + gap) < block:
                for d in range(depth):
                    g[y0 + d][x] = "@"
    return g


def write(path: Path, g: Grid) -> None:
    rows = "\n".join("".join(r) for r in g)
    path.write_text(f"type octile\nheight {len(g)}\nwidth {len(g[0])}\nmap\n{rows}\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="maps", help="folder to write the maps to (made)")
    ap.add_argument("--seed", type=int, default=3, help="seed of the maze and the doors")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rng = random.Random(args.seed)
    for name, g in (("maze-31-4", maze(6, 4, rng)), ("rooms-41-9", rooms(4, 9, 2, rng)),
                    ("warehouse-57-33", warehouse(57, 33))):
        write(out / f"{name}.map", g)
        print(f"wrote {out / name}.map ({len(g[0])} x {len(g)} cells)")


if __name__ == "__main__":
    main()
