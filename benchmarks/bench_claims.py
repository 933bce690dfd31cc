"""The fleet's claims (``lamp.fleet.regions.claims``), per announced segment.

Every segment a loop announces renews its object's claim: the footprints along the rest of
its plan, grown by a robot diameter. A long haul announces about one segment per lattice
edge, so one plan's claim is rebuilt from each suffix in turn. Here each plan is a random
lattice-like path (steps of 0.10 m and up to 0.3 rad) of ``--steps`` edges for a box, a
circle and a triangle; a segment is each edge in turn, announced with the rest of the
plan. Printed: the median time per announcement without and with ``ClaimBlocks`` (the
fleet's default), their ratio, and the blocks' memory.

    python benchmarks/bench_claims.py [--steps 150] [--plans 3]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import shapely

from lamp.fleet import regions
from lamp.geometry.primitives import Circle, Polygon
from lamp.geometry.se2 import interpolate
from lamp.scene.model import Rectangle

R = 0.05
SHAPES = {"box": Rectangle((0.6, 0.4)), "circle": Circle(0.25),
          "triangle": Polygon(((-0.3, -0.2), (0.3, -0.2), (0.0, 0.35)))}


def plan(rng: np.random.Generator, steps: int) -> np.ndarray:
    """(steps + 1, 3): a path of lattice-like edges from (2, 2, 0)."""
    q = [np.array([2.0, 2.0, 0.0])]
    for _ in range(steps):
        th = q[-1][2] + rng.choice([-0.3, 0.0, 0.0, 0.3])
        q.append(q[-1] + [0.1 * np.cos(th), 0.1 * np.sin(th), th - q[-1][2]])
    return np.array(q)


def announcements(poses: np.ndarray) -> list[np.ndarray]:
    """The poses each announcement claims: its segment (the edge, 8 poses) and the rest."""
    out = []
    for i in range(len(poses) - 1):
        seg = interpolate(poses[i], poses[i + 1], np.linspace(0.0, 1.0, 8))
        out.append(np.concatenate([seg, poses[i + 2:]]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=150, help="edges per plan")
    ap.add_argument("--plans", type=int, default=3, help="plans per shape")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print(f"{'shape':<9} {'plain (ms)':>10} {'blocks (ms)':>11} {'ratio':>6} {'blocks':>7}")
    for name, shape in SHAPES.items():
        plain, blocked, held = [], [], 0
        for _ in range(args.plans):
            stream = announcements(plan(rng, args.steps))
            cache = regions.ClaimBlocks()
            for poses in stream:
                t0 = time.perf_counter()
                regions.claims(shape, poses, poses[-1], R)
                t1 = time.perf_counter()
                regions.claims(shape, poses, poses[-1], R, blocks=cache)
                t2 = time.perf_counter()
                plain.append(t1 - t0)
                blocked.append(t2 - t1)
            held = max(held, sum(shapely.get_num_coordinates(g) * 16
                                 for g in cache._blocks.values()))
        a, b = statistics.median(plain) * 1e3, statistics.median(blocked) * 1e3
        print(f"{name:<9} {a:10.2f} {b:11.2f} {b / a:6.2f} {held / 2**10:5.0f} kB")


if __name__ == "__main__":
    main()
