"""Long-haul depot scenes, drawn apart from the ``fleet`` family's generator.

A hall of ``W x H`` m: robots start parked in a home band along the south wall; shelving
rows run west-east through the middle (1 m deep, 2 m aisles, a 2 m cross-aisle every
8-10 m); pallets (rectangles, sides 0.3-0.6 m) stand in the aisles of the western part of
the shelving and go to a dispatch band along the east wall, on a grid of drop spots. So a
load's haul runs most of the hall's length, and its first robot drives from the south.
Every scene is a pure function of its arguments (``numpy.random.default_rng(seed)``) and
is checked by the scene loader before it is written (exit 2 naming the failure).

    python benchmarks/depot_scene.py OUT.yaml --size 30 20 --robots 36 --loads 12 --seed 0
    lamp run OUT.yaml --schedule concurrent -o RUN && python benchmarks/fleet_gap.py RUN
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import yaml

from lamp.errors import InputError
from lamp.scene.loader import scene_from_dict

#: Layout (m): home band depth, shelf depth, aisle width, west and east band widths.
HOME, SHELF, AISLE, WEST, EAST = 2.6, 1.0, 2.0, 4.0, 5.0
#: Pallet sides (m), robot radius (m) and spacing of robot parking spots and drop spots.
PALLET = (0.3, 0.6)
ROBOT_RADIUS = 0.05
PARK_PITCH, DROP_PITCH = 0.35, 1.2


def _rect(x0: float, y0: float, x1: float, y1: float) -> dict:
    x0, y0, x1, y1 = (float(v) for v in (x0, y0, x1, y1))
    return {"type": "rectangle", "center": [round((x0 + x1) / 2, 4), round((y0 + y1) / 2, 4)],
            "size": [round(x1 - x0, 4), round(y1 - y0, 4)], "angle": 0.0}


def _shelves(rng: np.random.Generator, W: float, H: float) -> tuple[list[dict], list[float]]:
    """Shelf rectangles and the aisles' centre lines (y)."""
    obstacles, aisles = [], []
    x_lo, x_hi = WEST, W - EAST
    cuts, x = [], x_lo + rng.uniform(8.0, 10.0)
    while x < x_hi - 3.0:  # cross-aisles
        cuts.append(x)
        x += rng.uniform(8.0, 10.0)
    y = HOME + 0.4
    while y + SHELF <= H - 1.5:
        edges = [x_lo, *[c for cut in cuts for c in (cut - 1.0, cut + 1.0)], x_hi]
        for a, b in zip(edges[0::2], edges[1::2], strict=True):
            obstacles.append(_rect(a, y, b, y + SHELF))
        if y + SHELF + AISLE + SHELF <= H - 1.5:
            aisles.append(float(y + SHELF + AISLE / 2))
        y += SHELF + AISLE
    return obstacles, aisles


def depot(W: float, H: float, robots: int, loads: int, seed: int) -> dict:
    """The scene dict (module docstring); ValueError when the hall cannot hold them."""
    rng = np.random.default_rng(seed)
    obstacles, aisles = _shelves(rng, W, H)
    if not aisles:
        raise ValueError(f"a {W} x {H} m hall holds no aisle: make it taller")
    # pick spots: the western 45% of each aisle, 1.4 m apart
    span = (WEST + 0.8, WEST + 0.45 * (W - WEST - EAST))
    spots = [(float(x), y) for y in aisles for x in np.arange(span[0], span[1], 1.4)]
    drops = [(float(x), float(y)) for x in np.arange(W - EAST + 1.0, W - 0.7, DROP_PITCH)
             for y in np.arange(HOME + 1.0, H - 0.8, DROP_PITCH)]
    parks = [(float(x), float(y)) for y in np.arange(0.35, HOME - 0.3, PARK_PITCH)
             for x in np.arange(0.5, W - 0.4, PARK_PITCH)]
    for what, have, need in (("pick spots", spots, loads), ("drop spots", drops, loads),
                             ("parking spots", parks, robots)):
        if len(have) < need:
            raise ValueError(f"a {W} x {H} m hall has {len(have)} {what}, {need} needed")
    objects = []
    for s, g in zip(rng.choice(len(spots), loads, replace=False),
                    rng.choice(len(drops), loads, replace=False), strict=True):
        size = [round(float(v), 3) for v in rng.uniform(*PALLET, 2)]
        objects.append({"type": "rectangle", "size": size,
                        "start": [round(spots[s][0], 3), round(spots[s][1], 3), 0.0],
                        "goal": [round(drops[g][0], 3), round(drops[g][1], 3), 0.0]})
    starts = [[round(parks[i][0], 3), round(parks[i][1], 3)]
              for i in np.sort(rng.choice(len(parks), robots, replace=False))]
    return {"format": "lamp-scene/1", "name": f"depot-{W:g}x{H:g}-{robots}r{loads}o-s{seed}",
            "workspace": [W, H], "robots": {"radius": ROBOT_RADIUS, "starts": starts},
            "obstacles": obstacles, "objects": objects, "schedule": "concurrent"}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--size", type=float, nargs=2, default=(30.0, 20.0), metavar=("W", "H"))
    ap.add_argument("--robots", type=int, default=36)
    ap.add_argument("--loads", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    try:
        scene = depot(*a.size, a.robots, a.loads, a.seed)
        scene_from_dict(scene)
    except (ValueError, InputError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    a.out.write_text(yaml.safe_dump(scene, sort_keys=False))
    print(f"wrote {a.out}: {scene['name']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
