"""Accuracy of the proposers on large objects, and of the learned model's scaling bound.

Run: ``python benchmarks/bench_large_objects.py [--cases 100] [--proposals 4]
[--extents 0.5 0.6 0.8]``.

The held-out large-object set of ``lamp.manip.evaluate`` (bars 1.0-1.5 m, L and T shapes
0.8-1.2 m across; every proposal executed in MuJoCo in open space, as ``lamp model eval``
does) for: the learned model as shipped (objects wider than the training data scaled
down to its bound, ``lamp.manip.scaling.trained_extent``: 0.5 m for polygons), the same model scaled down to each bound of ``--extents`` instead
(``flow@E``), the model without scaling (``flow-noscale``: the object clipped to the 1 m
window) and the geometric proposer. Prints the evaluation tables and the wall time.
"""

from __future__ import annotations

import argparse
import math
import os
import time


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cases", type=int, default=100, help="cases per budget")
    ap.add_argument("--proposals", type=int, default=4, help="proposals executed per case")
    ap.add_argument("--seed", type=int, default=12345)
    ap.add_argument("--extents", type=float, nargs="*", default=[],
                    help="other scaling bounds (m) to compare")
    args = ap.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    from lamp.manip import GeometricProposer, load_model
    from lamp.manip.evaluate import evaluate, format_report
    from lamp.manip.network import FlowProposer

    flow = load_model(threads=1)

    def variant(extent: float) -> FlowProposer:
        return FlowProposer(flow.net, flow.traj_scale, flow.sampler, flow.meta,
                            max_extent=extent)

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
