"""Draw ``bench_scale.py --json`` sweeps: planning time per metre and peak memory.

Each JSON file is one sweep; its x axis is the parameter that varies across its points
(map side, robots, objects or pillar density). One column per file: planning time per
metre of route on top (the median, with the range of the repeated runs as a bar), peak
resident memory below. Failed points are drawn hollow.

Run: ``python benchmarks/plot_scale.py SIZES.json [ROBOTS.json ...] --out docs/images/scale.png``
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

#: the parameters a sweep may vary, with their axis labels
AXES = {"size_m": "map side (m)", "robots": "robots", "objects": "objects",
        "density": "pillars per m²"}


def fail(message: str) -> None:
    """Bad input: the message on stderr, exit status 2, nothing written."""
    print(f"error: {message}", file=sys.stderr)
    raise SystemExit(2)


def swept(rows: list[dict], path: Path) -> str:
    """The one parameter that varies across ``rows``."""
    varying = [k for k in AXES if len({r.get(k) for r in rows}) > 1]
    if len(varying) != 1:
        fail(f"{path}: expected one varying parameter of {list(AXES)}, "
             f"got {varying or 'none'}")
    return varying[0]


def fixed_label(rows: list[dict], key: str) -> str:
    r = rows[0]
    parts = {"size_m": f"{r['size_m']:g} m", "robots": f"{r['robots']} robots",
             "objects": f"{r['objects']} obj.", "density": f"{r.get('density', 0.15):g}/m²"}
    return ", ".join(v for k, v in parts.items() if k != key)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sweeps", nargs="+", type=Path, help="bench_scale.py --json files")
    ap.add_argument("--out", type=Path, required=True, help="image file (PNG)")
    args = ap.parse_args()
    data = []
    for path in args.sweeps:
        try:
            rows = json.loads(path.read_text())
        except (OSError, ValueError) as exc:
            fail(f"{path}: {exc}")
        if not isinstance(rows, list) or not rows:
            fail(f"{path}: expected a non-empty list of bench_scale.py points")
        key = swept(rows, path)
        data.append((path, key, sorted(rows, key=lambda r: r[key])))
    fig, axes = plt.subplots(2, len(data), figsize=(3.6 * len(data), 5.4), squeeze=False)
    for col, (_, key, rows) in enumerate(data):
        x = [r[key] for r in rows]
        for row, (field, label) in enumerate((("s_per_m", "planning per metre (s)"),
                                              ("peak_gb", "peak memory (GB)"))):
            ax = axes[row, col]
            y = [r[field] for r in rows]
            runs = [[run[field] for run in r.get("runs", [r])] for r in rows]
            lo = [yi - min(rs) for yi, rs in zip(y, runs, strict=True)]
            hi = [max(rs) - yi for yi, rs in zip(y, runs, strict=True)]
            ax.errorbar(x, y, yerr=[lo, hi], marker="o", capsize=3, color="C0")
            bad = [(xi, yi) for xi, yi, r in zip(x, y, rows, strict=True) if not r["success"]]
            if bad:
                ax.plot(*zip(*bad, strict=True), "o", mfc="white", color="C3", label="failed")
                ax.legend(fontsize=7)
            ax.set_ylim(bottom=0)
            ax.grid(alpha=0.3)
            if col == 0:
                ax.set_ylabel(label)
            if row == 1:
                ax.set_xlabel(AXES[key])
            else:
                ax.set_title(fixed_label(rows, key), fontsize=9)
    fig.suptitle("LAMP-Lazy on pillar maps (bench_scale.py)", fontsize=10)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_name(args.out.name + ".tmp.png")
    fig.savefig(tmp, dpi=110)
    tmp.replace(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
