"""Accuracy of the proposers on large objects, and of the learned model's scaling bound.

Run: ``python benchmarks/bench_large_objects.py [--cases 100] [--proposals 4]
[--extents 0.5 0.6 0.8]``.

The held-out large-object set of ``lamp.manip.evaluate`` (bars 1.0-1.5 m, L and T shapes
0.8-1.2 m across; every proposal executed in MuJoCo in open space, as ``lamp model eval``
does) for: the learned model as shipped (objects wider than the training data scaled
down to its bound, ``lamp.manip.scaling.trained_extent``: 0.5 m for polygons), the same model scaled down to each bound of ``--extents`` instead
(``flow@E``), the model without scaling (``flow-noscale``: the object clipped to the 1 m
window) and the geometric proposer. Prints the evaluation tables and the wall time.

``--e2e N``: instead, N open 4 m scenes with one large object (``large_shape``, start
near the centre, goal 0.8-1.2 m away turned by up to 0.5 rad; 3 and 6 robots) planned and
executed by LAMP-Lazy with each model: success, segments, replans and planning time.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np


def e2e(n: int, seed: int, noscale) -> None:
    import lamp
    from lamp.manip.evaluate import large_shape

    rng = np.random.default_rng([seed, 4242])
    scenes = []
    while len(scenes) < 2 * n:  # draws that leave the workspace or hit a robot are redrawn
        shape = large_shape(rng)
        start = np.array([*rng.uniform(1.6, 2.4, 2), rng.uniform(-np.pi, np.pi)])
        a, d = rng.uniform(-np.pi, np.pi), rng.uniform(0.8, 1.2)
        goal = start + [d * np.cos(a), d * np.sin(a), rng.uniform(-0.5, 0.5)]
        try:
            pair = [lamp.scene_from_dict({
                "format": "lamp-scene/1", "name": f"large-{len(scenes) // 2:02d}-r{robots}",
                "workspace": [4.0, 4.0],
                "robots": {"starts": [[0.3 + 0.3 * j, 0.25] for j in range(robots)]},
                "objects": [{**shape.to_dict(), "start": start.tolist(),
                             "goal": goal.tolist()}]}) for robots in (3, 6)]
        except lamp.SceneError:
            continue
        scenes += pair
    print(f"LAMP-Lazy (planner seed 0), {n} large-object scenes (seed {seed}) x (3, 6 robots), "
          "open 4 m map")
    print(f"{'model':<15} {'robots':>6} {'success':>8} {'segments':>9} {'replans':>8} "
          f"{'plan s':>7}  (medians over scenes)")
    for model in ("learned", "learned-noscale", "geometric"):
        for robots in (3, 6):
            m = noscale if model == "learned-noscale" else model
            rows = [lamp.solve(sc, planner="lazy", seed=0, model=m).to_dict()
                    for sc in scenes if sc.n_robots == robots]
            ok = sum(r["success"] for r in rows)
            print(f"{model:<15} {robots:>6} {ok:>5}/{len(rows):<2} "
                  f"{np.median([r['segments'] for r in rows]):>9.0f} "
                  f"{np.median([r['replans'] for r in rows]):>8.0f} "
                  f"{np.median([r['total_planning_time_s'] for r in rows]):>7.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cases", type=int, default=100, help="cases per budget")
    ap.add_argument("--proposals", type=int, default=4, help="proposals executed per case")
    ap.add_argument("--seed", type=int, default=12345)
    ap.add_argument("--extents", type=float, nargs="*", default=[],
                    help="other scaling bounds (m) to compare")
    ap.add_argument("--e2e", type=int, default=0, metavar="N",
                    help="run N end-to-end scenes with LAMP-Lazy instead")
    args = ap.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    from lamp.manip import GeometricProposer, load_model
    from lamp.manip.evaluate import evaluate, format_report
    from lamp.manip.network import FlowProposer

    flow = load_model(threads=1)

    def variant(extent: float) -> FlowProposer:
        return FlowProposer(flow.net, flow.traj_scale, flow.sampler, flow.meta,
                            max_extent=extent)

    if args.e2e:
        e2e(args.e2e, args.seed, variant(math.inf))
        return
    proposers = {"flow": flow}
    proposers.update({f"flow@{e:g}": variant(e) for e in args.extents})
    proposers["flow-noscale"] = variant(math.inf)
    proposers["geometric"] = GeometricProposer()
    t0 = time.perf_counter()
    report = evaluate(proposers, cases_per_budget=args.cases, k=args.proposals,
                      seed=args.seed, large=True, progress=False)
    print("flow: scaled down to the training data's bound (trained_extent)")
    print(format_report(report))
    print(f"wall time {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
