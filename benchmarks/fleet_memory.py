"""Where a fleet run's memory goes: the process's resident memory beside the NumPy arrays
that the project's objects hold, by the class that holds them, at the run's peak.

Runs ``lamp run SCENE --schedule concurrent`` in this process; every ``--every`` events of
the fleet schedule it reads the resident set (``/proc/self/statm``) and, when that is the
highest so far by 5 %, takes an inventory: every live object of a ``lamp`` class, and each
NumPy array reachable from its attributes (directly, or inside a dict, list or tuple held
there) counted once, for the first class found holding it: an array of 128 kB or more
by its pages resident in memory (``mincore(2)``: a zero-filled array mapped on its own,
or ``distance_tiles.lazy_zeros``, costs only the pages written so far), a smaller one (on
the malloc heap) by its size. Dicts and lists of more than 64 items held by those objects are
counted by ``sys.getsizeof`` of the container and its items (the lattices' successor lists,
the searches' tables and queues). Beside it, the objects the garbage collector tracks,
by type (what no class inventory reaches shows there). What no inventory finds is
the rest: Python objects not reached this way, the libraries (PyTorch, MuJoCo, Numba,
GEOS) and the allocator's slack.

Printed: the resident set before the inventory taken at the highest reading, the segments
running and waiting then, and that inventory, largest first, with each class's largest
instances (an array shared by several counts for the first found holding it; taking an
inventory costs memory itself: read the process's peak with ``/usr/bin/time -v lamp
run`` instead).

Run: ``python benchmarks/fleet_memory.py SCENE.yaml [--every 100] [-o OUT]``
(the run's own files go to ``OUT``, a temporary folder by default).
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import gc
import mmap
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np

from lamp.fleet.turns import MMAP_THRESHOLD as HEAP_BELOW  # smaller blocks: on the heap

PAGE = mmap.PAGESIZE


def resident_bytes() -> int:
    """The process's resident set now."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * PAGE


def _root(a: np.ndarray) -> object:
    """The object owning ``a``'s memory (its outermost base)."""
    while isinstance(a, np.ndarray) and a.base is not None:
        a = a.base
    return a


_LIBC = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
_LIBC.mincore.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p]


def resident_in(address: int, size: int) -> int:
    """Bytes of the pages of ``[address, address + size)`` that are resident now
    (``mincore(2)``: nothing is read, so nothing is faulted in)."""
    if size <= 0:
        return 0
    start = address - address % PAGE
    pages = -(-(address + size - start) // PAGE)
    vec = (ctypes.c_ubyte * pages)()
    if _LIBC.mincore(ctypes.c_void_p(start), ctypes.c_size_t(pages * PAGE), vec) != 0:
        raise OSError(ctypes.get_errno(), "mincore failed")
    return int(np.count_nonzero(np.frombuffer(vec, dtype=np.uint8) & 1)) * PAGE


def _array_bytes(a: np.ndarray) -> int:
    """The resident bytes of the memory ``a`` lives in (its outermost owner's)."""
    owner = _root(a)
    if isinstance(owner, mmap.mmap):
        owner = np.frombuffer(owner, dtype=np.uint8)
    if not isinstance(owner, np.ndarray):
        owner = a
    if owner.nbytes < HEAP_BELOW:  # on the malloc heap: resident
        return int(owner.nbytes)
    return resident_in(owner.ctypes.data, owner.nbytes)


def _item_bytes(x: object) -> int:
    """``x``'s own size, and its items' when it is a list or tuple."""
    size = sys.getsizeof(x)
    if isinstance(x, list | tuple):
        size += sum(sys.getsizeof(y) for y in x)
    return size


def _dict_bytes(d: dict) -> int:
    return sys.getsizeof(d) + sum(sys.getsizeof(k) + _item_bytes(v) for k, v in d.items())


def _list_bytes(items: list) -> int:
    return sys.getsizeof(items) + sum(_item_bytes(x) for x in items)


def tracked_types(top: int = 12) -> list[tuple[str, int, int]]:
    """The ``top`` types of the objects the garbage collector tracks (containers:
    tuples, lists, dicts, class instances; not floats nor ints), by their own bytes
    (``sys.getsizeof``): (type, count, bytes)."""
    count: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    for obj in gc.get_objects():
        row = count[type(obj).__qualname__]
        row[0] += 1
        row[1] += sys.getsizeof(obj)
    return sorted(((k, n, b) for k, (n, b) in count.items()), key=lambda r: -r[2])[:top]


def inventory(each: dict[str, list[int]] | None = None) -> dict[str, tuple[int, int, int]]:
    """{class: (array bytes, dict bytes, instances)} over every live ``lamp`` object;
    with ``each``, also every instance's bytes, by class."""
    seen: set[int] = set()
    out: dict[str, list[int]] = defaultdict(lambda: [0, 0, 0])
    for obj in gc.get_objects():
        cls = type(obj)
        module = getattr(cls, "__module__", None)
        if not isinstance(module, str) or not module.startswith("lamp.") or not isinstance(
                getattr(obj, "__dict__", None), dict):
            continue
        name = f"{module}.{cls.__qualname__}"
        row = out[name]
        row[2] += 1
        before = row[0] + row[1]
        for value in vars(obj).values():
            items = (list(value.values()) if isinstance(value, dict) else
                     list(value) if isinstance(value, list | tuple) else [value])
            if isinstance(value, dict) and len(value) > 64:
                row[1] += _dict_bytes(value)
            elif isinstance(value, list) and len(value) > 64:
                row[1] += _list_bytes(value)
            for a in items:
                if isinstance(a, np.ndarray):
                    key = id(_root(a))
                    if key not in seen:
                        seen.add(key)
                        row[0] += _array_bytes(a)
        if each is not None:
            each.setdefault(name, []).append(row[0] + row[1] - before)
    return {k: (v[0], v[1], v[2]) for k, v in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--every", type=int, default=100, help="events between RSS reads")
    ap.add_argument("-o", "--out", default=None, help="the run's output folder")
    args = ap.parse_args()

    from lamp.cli import app
    from lamp.fleet import coordinator

    peak: dict = {"rss": 0, "at": 0.0, "inv": {}, "each": {}, "moving": 0, "waiting": 0,
                  "types": []}
    advance = coordinator.Fleet._advance

    def watched(self):
        advance(self)
        if self.events % args.every == 0:
            rss = resident_bytes()
            if rss > 1.05 * peak["rss"]:
                each: dict[str, list[int]] = {}
                peak.update(rss=rss, at=self.clock, inv=inventory(each), each=each,
                            types=tracked_types(),
                            moving=sum(o.running is not None for o in self.objects),
                            waiting=sum(o.request is not None for o in self.objects))
    coordinator.Fleet._advance = watched

    out = args.out or tempfile.mkdtemp(prefix="fleet-memory-")
    sys.argv = ["lamp", "run", args.scene, "--schedule", "concurrent", "-o", out, "-q"]
    try:
        app()
    except SystemExit as e:
        if e.code not in (0, None):
            raise
    mb = 2**20
    inv = peak["inv"]
    total = sum(a + d for a, d, _ in inv.values())
    print(f"{Path(args.scene).name}: inventory at {peak['at']:.0f} s simulated, resident "
          f"{peak['rss'] / mb:.0f} MB; arrays and dicts found {total / mb:.0f} MB; segments "
          f"running {peak['moving']}, waiting for admission {peak['waiting']}")
    print("| class | instances | arrays MB | dicts, lists MB | largest instances (MB) |")
    print("|---|---|---|---|---|")
    for name, (a, d, n) in sorted(inv.items(), key=lambda kv: -(kv[1][0] + kv[1][1])):
        if a + d >= mb:
            top = sorted(peak["each"].get(name, []), reverse=True)[:5]
            print(f"| {name} | {n} | {a / mb:.0f} | {d / mb:.0f} | "
                  f"{', '.join(f'{b / mb:.1f}' for b in top)} |")
    print("\n| tracked type | objects | own MB |\n|---|---|---|")
    for name, n, b in peak["types"]:
        print(f"| {name} | {n} | {b / mb:.0f} |")


if __name__ == "__main__":
    main()
