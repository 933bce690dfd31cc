"""Held-out fleet scenes: the ``fleet`` generator run on past the family's 25 indices
(``lamp.suites.fleet.generate_scene(index, held_out=True)``), scenes no default was tuned
on, moved one object after another and concurrently by LAMP-Lazy; prints the fleet table
(``fleet_schedule.py``: success, makespans and their ratio, collisions found by the
independent safety check in the concurrent recordings).

    python benchmarks/fleet_heldout.py [--first 25] [--count 15] [--out DIR]

Runs ``lamp bench`` (``-j 2``) on ``DIR/scenes`` into ``DIR/sequential`` and
``DIR/concurrent``; an interrupted run resumes (``--resume``: finished jobs are kept).
About 8 minutes for the 15 default scenes on 2 cores.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from pathlib import Path

from fleet_schedule import table

from lamp.scene.save import save_scene
from lamp.suites.fleet import N_SCENES, generate_scene


def write_scenes(folder: Path, first: int, count: int) -> list[Path]:
    """The held-out scenes ``first`` .. ``first + count - 1`` as files in ``folder``
    (kept when already there: generation is deterministic)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for index in range(first, first + count):
        path = folder / f"fleet-heldout-{index:02d}.yaml"
        if not path.exists():
            save_scene(generate_scene(index, held_out=True).scene, path)
        paths.append(path)
    return paths


def bench(scenes: Path, schedule: str, out: Path) -> None:
    """``lamp bench`` of LAMP-Lazy on the folder ``scenes`` with ``schedule`` into ``out``."""
    lamp = shutil.which("lamp", path=str(Path(sys.executable).parent)) or "lamp"
    cmd = [lamp, "bench", "--suites", str(scenes), "--planners", "lazy", "--schedule",
           schedule, "--time-cap", "400", "-j", "2", "--out", str(out), "--resume"]
    if schedule == "concurrent":
        cmd.append("--record")
    subprocess.run(cmd, check=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--first", type=int, default=N_SCENES, help="first held-out index")
    ap.add_argument("--count", type=int, default=15, help="how many scenes")
    ap.add_argument("--out", type=Path, default=Path("fleet-heldout"), help="output folder")
    args = ap.parse_args()
    scenes = args.out / "scenes"
    write_scenes(scenes, args.first, args.count)
    for schedule in ("sequential", "concurrent"):
        bench(scenes, schedule, args.out / schedule)
    print(table(args.out / "sequential", args.out / "concurrent", None), end="")


if __name__ == "__main__":
    main()
