"""LAMP-A* planning benchmark: how often and how fast one full-horizon plan is found.

Run: ``python benchmarks/bench_lamp_astar.py [--scenes 4] [--limit 20] [--weight 4] [--cap 2]``

For the first ``--scenes`` scenes of each suite family, LAMP-A* (Alg. 1) plans the whole
push sequence for the scene's object from its start, with the shipped learned model, and
stops at ``--limit`` seconds (the planning limit of ``lamp bench``). Nothing is executed:
this isolates the search from drift. Prints, per scene, whether a plan was found, the
time, the Verify calls and the plan's length and robot-time cost, then per family the
plan rate and the median time. ``--weight`` and ``--cap`` override the heuristic weight and
the robot states kept per object node (``--cap 0``: unbounded), to compare settings.
Single-threaded.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from lamp.manip.models import load_proposer  # noqa: E402
from lamp.pipeline.registry import get as planner_spec  # noqa: E402
from lamp.planners.lamp_astar import LampAStar, edge_cost  # noqa: E402
from lamp.planners.task import ManipulationTask  # noqa: E402
from lamp.suites.registry import suite_scenes  # noqa: E402

FAMILIES = ("random", "maze", "tilt", "warehouse")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=4, help="first N scenes per family")
    parser.add_argument("--limit", type=float, default=20.0, help="planning limit (s)")
    parser.add_argument("--weight", type=float, default=None, help="heuristic weight")
    parser.add_argument("--cap", type=int, default=None, help="robot states per node (0: none)")
    args = parser.parse_args()

    import torch

    torch.set_num_threads(1)
    # the planning limit sets the expansion budget as in lamp bench (astar_expansions)
    cfg = dataclasses.replace(planner_spec("astar").default_config(), planning_time_limit=args.limit)
    if args.weight is not None:
        cfg = dataclasses.replace(cfg, astar_heuristic_weight=args.weight)
    if args.cap is not None:
        cfg = dataclasses.replace(cfg, astar_states_per_node=args.cap or None)
    print(f"weight {cfg.astar_heuristic_weight}, states per node {cfg.astar_states_per_node}, "
          f"limit {args.limit} s, {cfg.astar_expansions} expansions")
    model = load_proposer("learned")
    summary = []
    for family in FAMILIES:
        found, times = 0, []
        for scene in suite_scenes(family)[: args.scenes]:
            poses = scene.object_starts()
            t0 = time.perf_counter()
            task = ManipulationTask(scene, 0, poses, model, cfg, seed=0)
            plan = LampAStar.from_task(task).plan(poses[0], scene.robot_starts_array, deadline=t0 + args.limit)
            dt = time.perf_counter() - t0
            times.append(dt)
            found += plan.solved
            what = (f"{len(plan.transitions):3d} pushes, cost {sum(map(edge_cost, plan.transitions)):6.2f} m"
                    if plan.solved else f"no plan ({plan.status.value})")
            print(f"{scene.name:14s} {dt:6.1f} s  {task.stats.verify_calls:6d} verify  {what}", flush=True)
        summary.append(f"{family:10s} planned {found}/{len(times)}   median time {np.median(times):5.1f} s")
    print("\n".join(summary))


if __name__ == "__main__":
    main()
