"""The fleet schedule's admission tests, per call: whether two segments may run together
(``spacetime.compatible``) and whether a segment's bodies meet standing robots
(``admission.meets_standing``).

A waiting segment is tested again at every event of the shared clock, against every
running segment, so these run thousands of times a run (12 991 ``compatible`` calls in
the 48 x 16 aisles run of ``bench_fleet_scale.py``). Segments here are random pushes of
a 0.4 m box, 1-3 robots and 2-120 rows each, placed 0-2.5 m apart; each pair is tested
at ``--steps`` cursors, as a waiting segment is. Printed: the median time per call on
the first test of a segment (its object spaces computed) and on later ones, and per
``meets_standing`` call with 12 / 48 / 96 standing robots (first and later tests).

    python benchmarks/bench_admission.py [--pairs 300] [--steps 8]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from lamp.fleet.admission import meets_standing
from lamp.fleet.segments import Segment
from lamp.fleet.spacetime import compatible
from lamp.scene import scene_from_dict
from lamp.scene.model import Rectangle

R = 0.05
BOX = Rectangle((0.4, 0.4))


def random_segment(rng: np.random.Generator, index: int, centre: tuple[float, float]
                   ) -> Segment:
    """A random push: 1-3 robots along straight rows, the box moving up to 0.4 m and
    0.5 rad."""
    n = int(rng.integers(1, 4))
    start = np.asarray(centre) + rng.uniform(-0.6, 0.6, (n, 2))
    end = start + rng.uniform(-0.8, 0.8, (n, 2))
    t = int(rng.integers(2, 121))
    rows = start[:, None] + (end - start)[:, None] * np.linspace(0, 1, t)[None, :, None]
    q0 = np.r_[np.asarray(centre) + rng.uniform(-0.3, 0.3, 2), rng.uniform(-3, 3)]
    q1 = q0 + np.r_[rng.uniform(-0.4, 0.4, 2), rng.uniform(-0.5, 0.5)]
    poses = q0 + np.linspace(0, 1, 8)[:, None] * (q1 - q0)
    return Segment(index, list(range(n)), rows, poses, None, BOX, R)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs", type=int, default=300)
    ap.add_argument("--steps", type=int, default=8)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    first, later = [], []
    for _ in range(args.pairs):
        a = random_segment(rng, 0, (0.0, 0.0))
        b = random_segment(rng, 1, (float(rng.uniform(0.0, 2.5)), 0.3))
        for step in range(args.steps):
            a.cursor = min(step * a.rows.shape[1] // args.steps, a.rows.shape[1] - 1)
            t0 = time.perf_counter()
            compatible(a, b)
            (first if step == 0 else later).append(time.perf_counter() - t0)
    print(f"compatible: first test of a pair {1e3 * np.median(first):.3f} ms, later tests "
          f"{1e3 * np.median(later):.3f} ms (median of {len(first)} / {len(later)})")
    for n in (12, 48, 96):
        scene = scene_from_dict({
            "format": "lamp-scene/1", "name": "standing", "workspace": [40.0, 30.0],
            "robots": {"radius": R, "starts": [[1.0 + 0.2 * (i % 150), 20.0 + 0.2 * (i // 150)]
                                               for i in range(n)]},
            "obstacles": [],
            "objects": [{"type": "circle", "radius": 0.1, "start": [35.0, 1.0, 0.0],
                         "goal": [35.0, 3.0, 0.0]}]})
        cold, warm = [], []
        for _ in range(args.pairs):
            seg = random_segment(rng, 0, (0.0, 0.0))
            robots = rng.uniform(-3.0, 3.0, (n, 2))
            for times in (cold, warm):  # a segment tested again at the next event
                t0 = time.perf_counter()
                meets_standing(seg, scene, np.zeros((1, 3)), robots, [], set())
                times.append(time.perf_counter() - t0)
        print(f"meets_standing, {n} standing robots: first test of a segment "
              f"{1e3 * np.median(cold):.3f} ms, later tests {1e3 * np.median(warm):.3f} ms")


if __name__ == "__main__":
    main()
