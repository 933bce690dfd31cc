"""What the ``lamp`` command costs before and around planning.

Run: ``python benchmarks/investigations/bench_cli.py [--cold]``. Prints medians over repeated runs of:
- ``lamp --help`` and ``lamp --version`` in a fresh process (start-up of the command);
- ``lamp validate`` on the 25 maze scenes (per file);
- the Numba warm-up of ``lamp.solve`` with a warm disk cache, in a fresh process each time,
  after the imports (what every process pays once before its planning clock starts: the
  kernels load from the cache and a tiny scene is planned);
- with ``--cold``: the same warm-up in an empty Numba cache (the one-off compilation).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"),
                                                     os.environ.get("PYTHONPATH", "")])}
# imports first (every run pays them anyway), then the warm-up alone
WARM = ("import time; import lamp.pipeline.run, lamp.sim; from lamp.pipeline.warmup import warm_up; "
        "t = time.perf_counter(); r = warm_up(); "
        "print(time.perf_counter() - t, r.compiled, r.compile_s)")


def timed(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, str]:
    t0 = time.perf_counter()
    res = subprocess.run(cmd, env=env or ENV, capture_output=True, text=True, check=True)
    return time.perf_counter() - t0, res.stdout


def median_of(cmd: list[str], n: int) -> float:
    return statistics.median(timed(cmd)[0] for _ in range(n))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cold", action="store_true", help="also time a cold compilation")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    lamp = [sys.executable, "-m", "lamp.cli"]
    n = args.repeats
    print(f"lamp --help:    median {median_of([*lamp, '--help'], n):.2f} s ({n} runs)")
    print(f"lamp --version: median {median_of([*lamp, '--version'], n):.2f} s ({n} runs)")
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([*lamp, "suite", "export", "maze", f"{tmp}/maze"], env=ENV, check=True,
                       capture_output=True)
        files = sorted(Path(tmp, "maze").glob("*.yaml"))
        t = median_of([*lamp, "validate", *map(str, files)], n)
        print(f"lamp validate ({len(files)} maze scenes): median {t:.2f} s, "
              f"{t / len(files) * 1000:.0f} ms per file incl. start-up")
    timed([sys.executable, "-c", WARM])  # make sure the cache is warm
    warm = [float(timed([sys.executable, "-c", WARM])[1].split()[0]) for _ in range(n)]
    print(f"warm-up, warm cache: median {statistics.median(warm):.2f} s ({n} fresh processes)")
    if args.cold:
        with tempfile.TemporaryDirectory() as cache:
            out = timed([sys.executable, "-c", WARM], {**ENV, "NUMBA_CACHE_DIR": cache})[1]
            seconds, compiled, compile_s = out.split()
            print(f"warm-up, empty cache: {float(seconds):.1f} s, {compiled} compilations "
                  f"taking {float(compile_s):.1f} s (one run)")


if __name__ == "__main__":
    main()
