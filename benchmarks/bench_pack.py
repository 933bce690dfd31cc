"""D* Lite's packed tables (``lamp.search.dstar_tables``): what packing and unpacking a
large search costs, and what the arrays hold.

A synthetic search the size of the largest on the 144-robot depot: 345,000 vertices with
an ``rhs`` (random node ids below 4,000,000, one virtual start among them), 5,000 with a
``g`` of their own and 72,000 queued. Prints the medians of ``--repeats`` packs and unpacks
and the arrays' size; every unpack is checked equal to what was packed. Single-threaded.

    python benchmarks/bench_pack.py [--vertices 345000] [--queued 72000] [--repeats 5]
"""

from __future__ import annotations

import argparse
import itertools
import random
import statistics
import time

from lamp.search.dstar_tables import PackedTables


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vertices", type=int, default=345_000)
    ap.add_argument("--queued", type=int, default=72_000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    rng = random.Random(0)
    keys = rng.sample(range(4_000_000), args.vertices)
    virtual = (1.0, 2.0, 0.5)
    rhs = {k: rng.random() * 50 for k in keys}
    rhs[virtual] = 3.0
    g = {k: float("inf") for k in keys[:5000]}
    seq = itertools.count()
    queued = {k: (rhs[k] + 1.0, rhs[k], next(seq), k) for k in keys[-args.queued:]}
    queued[virtual] = (4.0, 3.0, next(seq), virtual)
    packs, unpacks = [], []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        packed = PackedTables.of(rhs, g, queued)
        t1 = time.perf_counter()
        back = packed.tables()
        unpacks.append(time.perf_counter() - t1)
        packs.append(t1 - t0)
        if back[0] != rhs or back[1] != g or back[2] != queued:
            raise SystemExit("unpacked tables differ from those packed")
    print(f"{len(rhs)} vertices, {len(queued)} queued: pack {1e3 * statistics.median(packs):.0f}"
          f" ms, unpack {1e3 * statistics.median(unpacks):.0f} ms (medians of {args.repeats});"
          f" arrays {packed.nbytes / 2**20:.1f} MB")


if __name__ == "__main__":
    main()
