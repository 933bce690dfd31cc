"""The benchmark report's figures (matplotlib, imported only when a report is drawn):
planning time per segment as violins, path cost against LAMP-Lazy, IROS planning time."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from lamp.bench.presentation import color, label, marker
from lamp.bench.tables import (
    IrosRun,
    PathCost,
    families,
    family_records,
    planning_time_points,
)

FAMILY_COLORS = {"random": "#1f77b4", "maze": "#ff7f0e", "tilt": "#2ca02c",
                 "warehouse": "#d62728"}



def _violin_axes(ax, points: dict[str, list[tuple[str, float, bool]]], fail_value: float,
                 title: str) -> None:
    """Violins of log10(planning time per segment) with jittered dots and a failure line."""
    rng = np.random.default_rng(0)  # jitter only; fixed so the figure is reproducible
    names = list(points)
    floor = 1e-3
    for i, p in enumerate(names):
        vals = np.log10(np.maximum([v for _, v, _ in points[p]], floor))
        if vals.size >= 2 and np.ptp(vals) > 0:
            parts = ax.violinplot([vals], positions=[i], widths=0.8, showextrema=False)
            for body in parts["bodies"]:
                body.set_facecolor(color(p))
                body.set_alpha(0.3)
        if vals.size:
            ax.boxplot([vals], positions=[i], widths=0.12, showfliers=False,
                       medianprops={"color": "black"}, manage_ticks=False)
            x = i + rng.uniform(-0.18, 0.18, vals.size)
            fam_colors = [FAMILY_COLORS.get(f, "#7f7f7f") for f, _, _ in points[p]]
            failed = np.array([bad for _, _, bad in points[p]])
            ax.scatter(x[~failed], vals[~failed], s=10, c=np.array(fam_colors)[~failed],
                       zorder=3, alpha=0.8)
            if failed.any():
                ax.scatter(x[failed], vals[failed], s=10, c="#444444", marker="x", zorder=3,
                           alpha=0.6)
    ax.axhline(math.log10(fail_value), color="black", ls="--", lw=1)
    ax.text(len(names) - 0.5, math.log10(fail_value), f" failed ({fail_value:g} s)",
            va="bottom", ha="right", fontsize=7)
    ax.set_xticks(range(len(names)), [label(p) for p in names], rotation=20,
                  fontsize=8)
    data = [math.log10(max(v, floor)) for pts in points.values() for _, v, _ in pts]
    lo = max(math.floor(min(data, default=0.0)), -3)
    hi = math.ceil(math.log10(fail_value) + 0.3)
    ticks = list(range(lo, hi + 1))
    ax.set_yticks(ticks, [f"{10.0 ** t:g}" for t in ticks])
    ax.set_ylim(lo - 0.1, hi)
    ax.set_ylabel("planning time per segment (s)")
    ax.set_title(title, fontsize=9)


def plot_planning_time(records: Sequence[dict[str, Any]], fail_value: float, path: Path,
                       by_family: bool = False) -> Path | None:
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    recs = family_records(records)
    if not recs:
        return None
    fams = families(recs)
    if by_family:
        fig = Figure(figsize=(3.2 * len(fams), 3.4), layout="constrained")
        axes = fig.subplots(1, len(fams), sharey=True, squeeze=False)[0]
        for ax, fam in zip(axes, fams, strict=True):
            pts = planning_time_points([r for r in recs if r["suite"] == fam], fail_value)
            _violin_axes(ax, pts, fail_value, fam)
    else:
        fig = Figure(figsize=(6.5, 3.8), layout="constrained")
        ax = fig.subplots()
        n_scen = len({(r["suite"], r["scene"], r["seed"]) for r in recs})
        _violin_axes(ax, planning_time_points(recs, fail_value), fail_value,
                     f"Planning time per segment ({n_scen} scenarios)")
        handles = [Line2D([], [], ls="", marker="o", color=FAMILY_COLORS.get(f, "#7f7f7f"),
                          label=f) for f in fams]
        handles.append(Line2D([], [], ls="", marker="x", color="#444444", label="failed"))
        ax.legend(handles=handles, fontsize=7, loc="upper left")
    fig.savefig(path, dpi=130)
    return path


def plot_path_cost(costs: dict[str, PathCost], path: Path) -> Path | None:
    from matplotlib.figure import Figure

    if not any(pc.n for pc in costs.values()) and not costs:
        return None
    fig = Figure(figsize=(5.6, 5.6), layout="constrained")
    ax = fig.subplots()
    hi = 1.0
    for base, pc in costs.items():
        if pc.n:
            xs = [b for _, _, b in pc.pairs]
            ys = [r for _, r, _ in pc.pairs]
            hi = max(hi, max(xs), max(ys))
            ratio = f"{pc.mean_ratio:.2f}"
        else:
            xs, ys, ratio = [], [], "-"
        ax.scatter(xs, ys, marker=marker(base), color=color(base),
                   s=22, alpha=0.8,
                   label=f"{label(base)}: n={pc.n}, ratio={ratio}, "
                         f"DNF {pc.dnf_baseline}/{pc.dnf_reference}")
    ax.plot([0, hi * 1.05], [0, hi * 1.05], color="black", lw=0.8, ls="--")
    ax.set_xlim(0, hi * 1.05)
    ax.set_ylim(0, hi * 1.05)
    ax.set_xlabel("baseline makespan (steps)")
    ax.set_ylabel("LAMP-Lazy makespan (steps)")
    ax.set_title("Path cost on mutually solved scenes\n"
                 "(ratio = mean of LAMP-Lazy / baseline; DNF = baseline / LAMP-Lazy only)",
                 fontsize=8)
    fig.legend(fontsize=7, loc="outside lower center", ncols=2)
    fig.savefig(path, dpi=130)
    return path


def plot_iros(runs: Sequence[IrosRun], path: Path) -> Path | None:
    from matplotlib.figure import Figure

    if not runs:
        return None
    fig = Figure(figsize=(6.5, 3.4), layout="constrained")
    ax = fig.subplots()
    for run in runs:
        if not run.planning_time_s:
            continue
        ax.plot(range(1, len(run.planning_time_s) + 1), run.planning_time_s, marker=".",
                lw=0.8, color=color(run.planner),
                label=f"{label(run.planner)} (seed {run.seed})")
    ax.set_yscale("log")
    ax.set_xlabel("executed segment")
    ax.set_ylabel("planning time (s)")
    ax.set_title("IROS case study: planning time per segment", fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    fig.savefig(path, dpi=130)
    return path
