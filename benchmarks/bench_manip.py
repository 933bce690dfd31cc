"""Speed of the manipulation proposers: median / p95 ``propose`` time for k = 16 and 64.

Run: ``python benchmarks/bench_manip.py [--threads 1] [--repeats 60]``.
Targets (issue #4): learned model, median k=16 <= 50 ms and k=64 <= 150 ms on 2 cores.
Calls cycle over a few shapes (so the per-shape image cache is warm, as in a planner that
asks about the same object many times) and random motions; the first call per shape (cold
cache: rasterise + CNN) is timed separately. The last lines time a 1.5 m bar and a 1.2 m L
(beyond the training sizes: the learned model proposes for them scaled down).
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np


def _stats(ts: list[float]) -> str:
    a = 1e3 * np.asarray(ts)
    return f"median {np.median(a):7.1f} ms   p95 {np.percentile(a, 95):7.1f} ms   n={len(a)}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=60)
    ap.add_argument("--model", default=None, help="checkpoint (default: the shipped one)")
    args = ap.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", str(args.threads))
    import torch

    from lamp.manip import GeometricProposer, load_model

    model = load_model(args.model, threads=args.threads)
    geo = GeometricProposer()
    shapes = [
        {"type": "rectangle", "size": [0.4, 0.3]},
        {"type": "circle", "radius": 0.2},
        {"type": "rectangle", "size": [0.25, 0.45]},
        {"type": "polygon", "points": [[0.0, 0.25], [-0.2, -0.1], [0.2, -0.1]]},
    ]
    rng = np.random.default_rng(0)
    print(f"python {platform.python_version()}, torch {torch.__version__}, "
          f"threads {torch.get_num_threads()}, cpus {os.cpu_count()}")
    cold = []
    for s in shapes:
        t0 = time.perf_counter()
        model.propose(s, (0.1, 0.0, 0.0), 3, k=16, seed=0)
        cold.append(time.perf_counter() - t0)
    print(f"flow      first call per shape (cold cache) k=16: {_stats(cold)}")
    for name, prop in (("flow", model), ("geometric", geo)):
        for k in (16, 64):
            ts = []
            for i in range(args.repeats):
                s = shapes[i % len(shapes)]
                m = rng.uniform([-0.2, -0.2, -0.5], [0.2, 0.2, 0.5])
                b = 1 + i % 3
                t0 = time.perf_counter()
                props = prop.propose(s, m, b, k=k, seed=i)
                ts.append(time.perf_counter() - t0)
                assert len(props) == k
            print(f"{name:<9} propose k={k:<3} budgets 1-3: {_stats(ts)}")
    # several motions of one shape in one pass (e.g. all primitives of a search expansion)
    motions = rng.uniform([-0.2, -0.2, -0.5], [0.2, 0.2, 0.5], size=(8, 3))
    ts = []
    for i in range(max(5, args.repeats // 4)):
        t0 = time.perf_counter()
        model.propose_batch(shapes[0], motions, 3, k=16, seed=i)
        ts.append(time.perf_counter() - t0)
    print(f"flow      propose_batch 8 motions x k=16: {_stats(ts)}")
    # objects beyond the training sizes, which the learned model proposes for scaled down
    large = [
        {"type": "rectangle", "size": [1.5, 0.12]},
        {"type": "polygon", "points": [[-0.6, -0.45], [0.6, -0.45], [0.6, -0.25],
                                       [-0.4, -0.25], [-0.4, 0.45], [-0.6, 0.45]]},
    ]
    for s in large:
        model.propose(s, (0.1, 0.0, 0.0), 3, k=16, seed=0)
    for name, prop in (("flow", model), ("geometric", geo)):
        ts = []
        for i in range(args.repeats):
            m = rng.uniform([-0.2, -0.2, -0.5], [0.2, 0.2, 0.5])
            t0 = time.perf_counter()
            prop.propose(large[i % len(large)], m, 1 + i % 3, k=16, seed=i)
            ts.append(time.perf_counter() - t0)
        print(f"{name:<9} propose k=16  1.5 m bar / 1.2 m L: {_stats(ts)}")


if __name__ == "__main__":
    main()
