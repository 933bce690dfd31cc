"""Object-level search benchmark: ObjectSpace throughput, D* Lite plan/replan times.

Run: ``python benchmarks/bench_search.py [--seed 0] [--pairs 10]``

On a deterministic 4 x 4 m cluttered map (random rectangles and disks, about 20% of the
area occupied) with a 0.4 x 0.3 m box (and a 0.2 m radius disk for the pose checks):

* ObjectSpace construction time (rasterisation + distance transform, 4 mm cells);
* pose checks per second (one batch of 100k random poses);
* edge checks per second (lattice primitives from random free nodes, 20k per batch);
* D* Lite on the goal-anchored lattice (0.1 m, 16 headings) for random start/goal pairs:
  the initial plan (lazy collision checks included), then replans after penalising an
  edge of the current path by 1e4 (LAMP-Lazy's UpdateChange), each time from a start that
  has moved one node along the path, and a weighted A* (w = 1) from scratch for scale.

Prints medians and 95th percentiles. Single-threaded.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import shapely  # noqa: E402

from lamp.geometry.object_space import ObjectSpace  # noqa: E402
from lamp.geometry.shapes import obstacle_geometry  # noqa: E402
from lamp.scene.model import Circle, Obstacle, Rectangle  # noqa: E402
from lamp.search.astar import weighted_astar  # noqa: E402
from lamp.search.dstar_lite import DStarLite  # noqa: E402
from lamp.search.lattice import PRIMITIVES, ObjectLattice  # noqa: E402

W = H = 4.0
BOX = Rectangle((0.4, 0.3))
DISK = Circle(0.2)


def cluttered_map(rng: np.random.Generator, n: int = 28) -> list[Obstacle]:
    """Random rectangles and disks, kept away from two free corridors' worth of space."""
    obs: list[Obstacle] = []
    for _ in range(n):
        x, y = rng.uniform(0.3, 3.7, 2)
        if rng.random() < 0.65:
            size = (float(rng.uniform(0.1, 0.7)), float(rng.uniform(0.08, 0.4)))
            obs.append(Obstacle(Rectangle(size), (float(x), float(y), float(rng.uniform(-3, 3)))))
        else:
            obs.append(Obstacle(Circle(float(rng.uniform(0.05, 0.25))), (float(x), float(y), 0.0)))
    return obs


def occupied(obstacles: list[Obstacle]) -> float:
    """The fraction of the W x H map the obstacles cover."""
    cover = shapely.union_all([obstacle_geometry(o) for o in obstacles])
    return float(cover.intersection(shapely.box(0.0, 0.0, W, H)).area) / (W * H)


def stats(xs: list[float]) -> str:
    a = np.asarray(xs, dtype=float)
    return f"median {np.median(a) * 1e3:8.2f} ms   p95 {np.percentile(a, 95) * 1e3:8.2f} ms   (n={len(a)})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--pairs", type=int, default=10, help="start/goal pairs for D* Lite")
    parser.add_argument("--replans", type=int, default=8, help="penalty replans per pair")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    obstacles = cluttered_map(rng)

    # warm up the compiled kernels on a throw-away space
    warm = ObjectSpace(BOX, (1.0, 1.0), [])
    warm.pose_free(np.zeros((1, 3)))
    warm.motions_free(np.zeros((1, 3)), np.zeros((1, 3)))

    build = []
    for _ in range(5):
        t0 = time.perf_counter()
        space = ObjectSpace(BOX, (W, H), obstacles)
        build.append(time.perf_counter() - t0)
    print(
        f"seed {args.seed}; map: {len(obstacles)} obstacles, occupied {occupied(obstacles):.1%}"
    )
    print(f"ObjectSpace build (4x4 m, {space.resolution * 1e3:.0f} mm cells): {stats(build)}")
    print(
        f"  clearance band {space.band * 1e3:.1f} mm, motion margin {space.motion_margin * 1e3:.1f} mm"
    )

    poses = rng.uniform([0, 0, -np.pi], [W, H, np.pi], size=(100_000, 3))
    for name, shape in (("box 0.4x0.3", BOX), ("disk r=0.2", DISK)):
        sp = space if shape is BOX else ObjectSpace(shape, (W, H), obstacles)
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            free = sp.pose_free(poses)
            times.append(time.perf_counter() - t0)
        rate = len(poses) / np.median(times)
        print(
            f"pose checks, {name}: {rate:,.0f} poses/s (batch of {len(poses):,}, {free.mean():.0%} free)"
        )

    lat = ObjectLattice(space, (3.5, 3.5, 0.0))
    valid = np.nonzero(lat.validate_all_nodes())[0]
    starts = lat.poses(rng.choice(valid, 20_000))
    prim = np.array(PRIMITIVES, dtype=float)[rng.integers(len(PRIMITIVES), size=len(starts))]
    ends = starts + prim * np.array([lat.step, lat.step, lat.dtheta])
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        ok = space.motions_free(starts, ends)
        times.append(time.perf_counter() - t0)
    print(
        f"edge checks (lattice primitives from free nodes): {len(starts) / np.median(times):,.0f} "
        f"edges/s ({ok.mean():.0%} free)"
    )

    # D* Lite: initial plans and replans after penalties
    free_poses = poses[space.pose_free(poses)]
    init_t, init_cached_t, replan_t, astar_t = [], [], [], []
    init_exp, replan_exp, astar_exp, lengths = [], [], [], []
    pairs = 0
    attempts = 0
    while pairs < args.pairs and attempts < 50 * args.pairs:
        attempts += 1
        i, j = rng.choice(len(free_poses), 2, replace=False)
        start, goal = free_poses[i], free_poses[j]
        if np.hypot(*(start[:2] - goal[:2])) < 2.0:
            continue
        start = tuple(float(v) for v in start)
        lattice = ObjectLattice(space, goal)
        dstar = DStarLite(lattice)
        dstar.initialize(lattice.goal_node)
        t0 = time.perf_counter()
        edges = lattice.start_connections(start)
        path = dstar.plan_shortest_path(start, edges)
        t_init = time.perf_counter() - t0
        if not path:
            continue
        pairs += 1
        init_t.append(t_init)
        init_exp.append(dstar.stats.last_expansions)
        lengths.append(len(path))
        # the same query on a lattice whose collision checks are all cached
        dstar2 = DStarLite(lattice)
        dstar2.initialize(lattice.goal_node)
        t0 = time.perf_counter()
        dstar2.plan_shortest_path(start, lattice.start_connections(start))
        init_cached_t.append(time.perf_counter() - t0)
        res = weighted_astar(lattice, path[1], lattice.goal_node, weight=1.0)
        astar_t.append(res.time_s)
        astar_exp.append(res.expansions)
        # replans: the start moves one node along the path, an edge ahead is penalised
        cur = path
        for _ in range(args.replans):
            if len(cur) < 4:
                break
            new_start = cur[1]
            k = min(len(cur) - 2, 1 + int(rng.integers(1, max(2, len(cur) - 2))))
            dstar.penalize(cur[k], cur[k + 1], 1e4)
            t0 = time.perf_counter()
            cur = dstar.plan_shortest_path(new_start)
            replan_t.append(time.perf_counter() - t0)
            replan_exp.append(dstar.stats.last_expansions)
            if not cur:
                break
    print(
        f"D* Lite on the 0.1 m / 16-heading lattice ({lat.n_nodes:,} nodes), {pairs} start/goal "
        f"pairs >= 2 m apart, paths of median {np.median(lengths):.0f} nodes:"
    )
    print(
        f"  initial plan (lazy collision checks): {stats(init_t)}  expansions median {np.median(init_exp):.0f}"
    )
    print(f"  initial plan (checks cached):         {stats(init_cached_t)}")
    print(
        f"  replan after penalty + start move:    {stats(replan_t)}  expansions median {np.median(replan_exp):.0f}"
    )
    print(
        f"  A* from scratch (checks cached):      {stats(astar_t)}  expansions median {np.median(astar_exp):.0f}"
    )


if __name__ == "__main__":
    main()
