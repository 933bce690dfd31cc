"""The robustness table and figure from a sweep of ``lamp bench --disturb PRESET`` runs.

    lamp bench --suites random,maze,tilt,warehouse --scenes 5 --planners lazy,gco-var \
        --disturb noise-high --out runs/noise-high      # one folder per preset
    python benchmarks/robustness.py runs/none runs/noise-low runs/noise-high \
        runs/one-robot-fails --out results/robustness

Per preset and planner: how many runs the disturbance happened in, the success rate over
those runs only (a run it missed, a failure that never fired, counts as not disturbed,
never as survived), mean executed segments, segments against the same scene's undisturbed
run (on scenes both solved; needs the ``none`` folder), median makespan in simulated
seconds, and median planning time per segment. Writes ``report.md`` and ``robustness.png``
into ``--out`` and prints the table.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

from lamp.bench.jobs import read_records

LABELS = {"lazy": "LAMP-Lazy", "gco-var": "GCo_var", "astar-replan": "LAMP-A*_replan",
          "astar": "LAMP-A*_ori", "gco-ori": "GCo_ori"}


def load(folder: Path) -> tuple[str, list[dict]]:
    config = json.loads((folder / "config.json").read_text())
    latest: dict[tuple, dict] = {}
    for r in read_records(folder / "results.jsonl"):
        latest[(r["suite"], r["scene"], r["planner"], r["seed"])] = r
    return config.get("disturb", "none"), list(latest.values())


def disturbed(record: dict) -> bool:
    """Whether the run's disturbance happened: a robot failure fired (a run without one
    was not disturbed by it); noise and knocks act in every run that moved at all."""
    d = record.get("disturbances") or {}
    if d.get("robot_failures"):
        return bool(d.get("robot_failures_fired"))
    return True


def rows(runs: dict[str, list[dict]]) -> list[dict]:
    base = {(r["suite"], r["scene"], r["planner"], r["seed"]): r for r in runs.get("none", [])}
    out = []
    for preset, records in runs.items():
        for planner in sorted({r["planner"] for r in records}):
            every = [r for r in records if r["planner"] == planner]
            mine = [r for r in every if disturbed(r)]
            ok = [r for r in mine if r.get("success")]
            ratios = []
            for r in ok:
                b = base.get((r["suite"], r["scene"], r["planner"], r["seed"]))
                if b is not None and b.get("success") and b["segments"]:
                    ratios.append(r["segments"] / b["segments"])
            per_seg = [r["planning_time_per_segment_s"] for r in mine
                       if r.get("planning_time_per_segment_s") is not None]
            out.append({
                "preset": preset, "planner": planner, "runs": len(every),
                "disturbed": len(mine),
                "success": 100.0 * len(ok) / len(mine) if mine else 0.0,
                "segments": statistics.fmean(r["segments"] for r in mine) if mine else 0.0,
                "segment_ratio": statistics.median(ratios) if ratios else None,
                "makespan_s": (statistics.median(r["makespan_s"] for r in ok)
                               if ok and all("makespan_s" in r for r in ok) else None),
                "planning_per_segment_s": statistics.median(per_seg) if per_seg else None,
            })
    return out


def markdown(table: list[dict]) -> str:
    head = ("| disturbance | planner | runs | disturbed | success (of disturbed) | segments "
            "(mean) | segments / undisturbed (median, both solved) | makespan (median, s) | "
            "planning per segment (median, s) |\n|---|---|---|---|---|---|---|---|---|\n")

    def f(v, fmt):
        return "-" if v is None else format(v, fmt)

    return head + "".join(
        f"| {r['preset']} | {LABELS.get(r['planner'], r['planner'])} | {r['runs']} | "
        f"{r['disturbed']} | "
        f"{r['success']:.0f}% | {r['segments']:.1f} | {f(r['segment_ratio'], '.2f')} | "
        f"{f(r['makespan_s'], '.1f')} | {f(r['planning_per_segment_s'], '.3f')} |\n"
        for r in table)


def figure(table: list[dict], presets: list[str], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
    for planner in sorted({r["planner"] for r in table}):
        mine = {r["preset"]: r for r in table if r["planner"] == planner}
        xs = [p for p in presets if p in mine]
        axes[0].plot(xs, [mine[p]["success"] for p in xs], marker="o",
                     label=LABELS.get(planner, planner))
        axes[1].plot(xs, [mine[p]["segments"] for p in xs], marker="o")
    axes[0].set_ylabel("success (%)")
    axes[0].set_ylim(0, 105)
    axes[1].set_ylabel("executed segments (mean)")
    for ax in axes:
        ax.tick_params(axis="x", rotation=20)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Disturbances: success and segments per preset")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", type=Path, nargs="+")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    runs = dict(load(f) for f in args.folders)
    table = rows(runs)
    text = markdown(table)
    print(text)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "report.md").write_text(
            "# Robustness sweep\n\nCommand: `python benchmarks/robustness.py "
            + " ".join(str(f) for f in args.folders) + "`\n\n" + text)
        figure(table, list(runs), args.out / "robustness.png")
        print(f"wrote {args.out / 'report.md'} and {args.out / 'robustness.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
