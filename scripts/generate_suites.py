"""Generate the built-in benchmark suites into ``src/lamp/suites/data`` (seeded).

    python scripts/generate_suites.py                # all suites
    python scripts/generate_suites.py maze tilt      # some suites
    python scripts/generate_suites.py --check        # regenerate in memory, compare with
                                                     # the committed files (exit 1 on a diff)

Every scene is a pure function of (family, index) (see ``lamp.suites.generators``), so
running this again reproduces the committed files byte for byte. It also rewrites
``data/STATS.md`` (per-family statistics; suites not rebuilt contribute their committed
manifests). Takes a few
minutes on one core.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

from lamp.suites.build import build_suite  # noqa: E402
from lamp.suites.registry import DATA_DIR, SUITES, suite_manifest  # noqa: E402
from lamp.suites.stats import stats_markdown  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "suites", nargs="*", help=f"suites to build (default: all of {', '.join(SUITES)})"
    )
    parser.add_argument(
        "--check", action="store_true", help="compare with the committed files instead of writing"
    )
    parser.add_argument("-q", "--quiet", action="store_true")
    args = parser.parse_args(argv)
    names = args.suites or list(SUITES)
    unknown = [n for n in names if n not in SUITES]
    if unknown:
        parser.error(f"unknown suite(s) {', '.join(unknown)}; valid: {', '.join(SUITES)}")
    say = (lambda s: None) if args.quiet else (lambda s: print(s, flush=True))
    differ = []
    manifests = {}
    for name in names:
        t0 = time.perf_counter()
        files = build_suite(name, progress=say)
        folder = DATA_DIR / name
        manifests[name] = json.loads(files["manifest.json"])
        if args.check:
            present = {p.name for p in folder.glob("*")} if folder.exists() else set()
            for fname, text in files.items():
                path = folder / fname
                if not path.exists() or path.read_text(encoding="utf-8") != text:
                    differ.append(f"{name}/{fname}")
            differ += [f"{name}/{f} (extra)" for f in sorted(present - set(files))]
        else:
            folder.mkdir(parents=True, exist_ok=True)
            for old in folder.glob("*"):
                if old.name not in files:
                    old.unlink()
            for fname, text in files.items():
                (folder / fname).write_text(text, encoding="utf-8")
        say(f"{name}: {len(files) - 1} scene(s) in {time.perf_counter() - t0:.1f} s")
    if not args.check or set(names) == set(SUITES):
        # suites not rebuilt here contribute their committed manifests
        for other in SUITES:
            if other not in manifests and (DATA_DIR / other / "manifest.json").exists():
                manifests[other] = suite_manifest(other)
        stats = stats_markdown(manifests)
        path = DATA_DIR / "STATS.md"
        if args.check:
            if not path.exists() or path.read_text(encoding="utf-8") != stats:
                differ.append("STATS.md")
        else:
            path.write_text(stats, encoding="utf-8")
    if differ:
        print("differs from the committed files: " + ", ".join(differ), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
