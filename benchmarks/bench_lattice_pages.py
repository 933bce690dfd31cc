"""Memory pages an object lattice's validity states hold after a long haul's D* Lite plan.

For every ``--every``-th object of a scene (a depot from ``benchmarks/depot_scene.py``):
its goal-anchored lattice (0.1 m, 16 headings, landmark at its start) over the scene's
obstacles and the other objects, one D* Lite plan from its start, and then the pages of
the lattice's zero-filled state arrays that hold a state (a page never written costs no
memory). Prints, per object, the path's nodes, the expansions and the running total of
such pages, by array. The arrays are found by type (every NumPy array the lattice holds
of 1 MB or more), so the same script measures other layouts of the states.

Run: ``python benchmarks/bench_lattice_pages.py SCENE.yaml [--every 3]``
"""

from __future__ import annotations

import argparse

import numpy as np

from lamp.geometry.object_space import ObjectSpace
from lamp.scene import load_scene
from lamp.search.dstar_lite import DStarLite
from lamp.search.lattice import ObjectLattice

PAGE = 4096


def written_pages(a: np.ndarray) -> int:
    """Pages of ``a`` holding a byte that is not zero."""
    b = a.reshape(-1).view(np.uint8)
    n = len(b) // PAGE
    full = int(np.count_nonzero(b[: n * PAGE].reshape(n, PAGE).any(axis=1)))
    return full + int(bool(b[n * PAGE:].any()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("--every", type=int, default=3, help="plan every N-th object")
    args = parser.parse_args()
    scene = load_scene(args.scene)
    total: dict[str, int] = {}
    for k in range(0, len(scene.objects), max(1, args.every)):
        obj = scene.objects[k]
        lattice = ObjectLattice(ObjectSpace.from_scene(scene, k), obj.goal,
                                landmark=np.asarray(obj.start)[:2])
        search = DStarLite(lattice)
        search.initialize(lattice.goal_node)
        start = tuple(float(v) for v in obj.start)
        path = search.plan_shortest_path(start, lattice.start_connections(start))
        for name, value in vars(lattice).items():
            if isinstance(value, np.ndarray) and value.nbytes >= 2**20:
                total[name] = total.get(name, 0) + written_pages(value) * PAGE
        held = ", ".join(f"{n} {v / 2**20:.1f} MB" for n, v in total.items())
        print(f"object {k}: path {len(path)} nodes, {search.stats.last_expansions} "
              f"expansions; pages holding states so far: {held}", flush=True)


if __name__ == "__main__":
    main()
