"""The benchmark report: the paper's Tables I-II, planning-time and path-cost figures, IROS.

Everything here is computed from ``DIR/results.jsonl`` alone (plus ``DIR/config.json`` for
the caps and provenance), so ``lamp report DIR`` rebuilds ``DIR/report.md`` and its PNG
figures without rerunning anything. The numbers are produced by small pure functions
(:func:`success_table`, :func:`full_horizon_table`, :func:`median_planning_time_table`,
:func:`path_cost_comparison`, :func:`iros_summary`) that the tests check against
hand-computed values; the Markdown and the figures only format them.

Definitions (paper Sec. V-A):
- *Success* of a run: every object ends within 0.1 m / 0.1 rad of its goal and never left
  the workspace (the run's ``success`` key). A timeout, error or crash is a failure.
- *Full-horizon plan* of a run: every object had a complete plan before its first segment.
- *Planning time per segment* of a run (the dots of the paper's violin figure): its total
  planning time divided by its executed segments when it succeeded; a failed run is drawn
  at the failure line (the paper puts failures at its 500 s LAMP-A* limit; we use the
  ``--planning-limit`` of the run, recorded in ``config.json``).
- *Median planning time per segment* (table): the median of those per-run values over
  the solved runs of a cell (failed runs have no meaningful per-segment value).
- *Path cost*: the makespan (synchronised robot time steps). LAMP-Lazy is compared with
  each baseline on the (scene, seed) pairs both solved; the ratio is the mean over those
  pairs of ``makespan(LAMP-Lazy) / makespan(baseline)``; DNF counts one-sided failures.
- *MAPush criterion* (the paper's, for MAPush only): every object within 0.5 m of its goal
  position at some instant within 2 simulated minutes, orientation ignored
  (``stats.mapush_success``); the MAPush runs are shown under both criteria.
The IROS suite is reported in its own section and left out of the per-family tables.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lamp.bench.jobs import RESULTS_FILE, JobKey, latest_by_key, read_records, record_key
from lamp.planners import registry

#: The paper's four map families, in its column order.
FAMILY_ORDER = ("random", "maze", "tilt", "warehouse")
#: The suite reported as the long-horizon case study rather than as a family.
IROS_SUITE = "iros"
REFERENCE_PLANNER = "lazy"

# Per-planner facts (row order, labels, colours, markers, the paper's Table I and II
# figures, which planners are LAMP's) come from ``lamp.planners.registry``. The paper's
# MAPush row counts MAPush's own criterion (:data:`MAPUSH_CRITERION`), every other row the
# strict one.
#: The MAPush baseline's own success criterion (paper, footnote to Sec. V-A), recorded per
#: run as ``stats.mapush_success`` by ``lamp.planners.mapush``.
MAPUSH_PLANNER = "mapush"
MAPUSH_CRITERION = ("within 0.5 m of the goal position, orientation ignored, within 2 "
                    "simulated minutes")
#: Paper: LAMP-Lazy's median planning time per segment is about 2-3 s; IROS 2.07 s average.
PAPER_LAZY_MEDIAN_S = "2-3"
PAPER_IROS_MEAN_S = 2.07
#: The paper's cumulative planning limit for LAMP-A*.
PAPER_PLANNING_LIMIT_S = 500.0


@dataclass(frozen=True)
class Rate:
    """``k`` of ``n`` runs."""

    k: int
    n: int

    @property
    def value(self) -> float | None:
        return self.k / self.n if self.n else None

    def percent(self) -> str:
        return "-" if not self.n else f"{100.0 * self.k / self.n:.0f}%"

    def cell(self) -> str:
        return "-" if not self.n else f"{self.percent()} ({self.k}/{self.n})"


@dataclass
class PathCost:
    """LAMP-Lazy against one baseline on the (suite, scene, seed) pairs both ran."""

    baseline: str
    pairs: list[tuple[tuple[str, str, int], float, float]] = field(default_factory=list)
    dnf_baseline: int = 0  # LAMP-Lazy solved, the baseline did not
    dnf_reference: int = 0  # the baseline solved, LAMP-Lazy did not
    both_failed: int = 0

    @property
    def n(self) -> int:
        return len(self.pairs)

    @property
    def ratios(self) -> list[float]:
        return [ref / base for _, ref, base in self.pairs]

    @property
    def mean_ratio(self) -> float | None:
        return float(np.mean(self.ratios)) if self.pairs else None

    @property
    def median_ratio(self) -> float | None:
        return float(np.median(self.ratios)) if self.pairs else None


# ------------------------------------------------------------------------------ loading
def load_results(run_dir: str | Path) -> list[dict[str, Any]]:
    """The latest record per job of ``run_dir/results.jsonl``, in file order."""
    path = Path(run_dir) / RESULTS_FILE
    if not path.exists():
        raise FileNotFoundError(f"no {RESULTS_FILE} in {run_dir}")
    return list(latest_by_key(read_records(path)).values())


def load_config(run_dir: str | Path) -> dict[str, Any]:
    path = Path(run_dir) / "config.json"
    if not path.exists():
        return {}
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError:
        return {}


def _spec(planner: str) -> registry.PlannerSpec | None:
    """The registered planner, or None for a name recorded by a planner since removed."""
    try:
        return registry.get(planner)
    except ValueError:
        return None


def _rank(planner: str) -> int:
    """The planner's row in the paper's tables (unknown planners last)."""
    spec = _spec(planner)
    return spec.row if spec is not None else 1 << 30


def paper_success(planner: str) -> dict[str, float]:
    """Table I of the paper (success rate, %) per family for ``planner`` ({} if none)."""
    spec = _spec(planner)
    return dict(spec.paper_success) if spec is not None else {}


def paper_full_horizon(planner: str) -> dict[str, float]:
    """Table II of the paper (full-horizon plan rate, %) per family ({} if none)."""
    spec = _spec(planner)
    return dict(spec.paper_full_horizon) if spec is not None else {}


def _ordered(names: Iterable[str], order: Sequence[str]) -> list[str]:
    names = set(names)
    return [n for n in order if n in names] + sorted(names - set(order))


def families(records: Iterable[dict[str, Any]]) -> list[str]:
    """Suites of ``records`` other than IROS, in the paper's order then by name."""
    return _ordered((r["suite"] for r in records if r["suite"] != IROS_SUITE), FAMILY_ORDER)


def planners(records: Iterable[dict[str, Any]]) -> list[str]:
    return _ordered((r["planner"] for r in records), registry.table_order())


def family_records(records: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    return [r for r in records if r["suite"] != IROS_SUITE]


# ------------------------------------------------------------------------------- tables
def run_full_horizon(rec: dict[str, Any]) -> bool:
    """Whether every object of the run had a complete plan before its first segment."""
    objs = rec.get("objects") or []
    return bool(objs) and all(bool(o.get("full_horizon_plan")) for o in objs)


def _rate_table(records: Sequence[dict[str, Any]], predicate, only: Sequence[str] | None = None
                ) -> dict[str, dict[str, Rate]]:
    recs = family_records(records)
    fams = families(recs)
    table: dict[str, dict[str, Rate]] = {}
    for p in planners(recs):
        if only is not None and p not in only:
            continue
        mine = [r for r in recs if r["planner"] == p]
        row = {}
        for fam in fams:
            cell = [r for r in mine if r["suite"] == fam]
            row[fam] = Rate(sum(bool(predicate(r)) for r in cell), len(cell))
        row["all"] = Rate(sum(bool(predicate(r)) for r in mine), len(mine))
        table[p] = row
    return table


def success_table(records: Sequence[dict[str, Any]]) -> dict[str, dict[str, Rate]]:
    """Table I: success rate per planner (rows) and family (columns, plus ``"all"``)."""
    return _rate_table(records, lambda r: r.get("success"))


def mapush_success(rec: dict[str, Any]) -> bool:
    """Whether a run met MAPush's criterion (``stats.mapush_success``; absent: no)."""
    stats = rec.get("stats")
    return bool(isinstance(stats, dict) and stats.get("mapush_success"))


def mapush_criteria_table(records: Sequence[dict[str, Any]]) -> dict[str, dict[str, Rate]]:
    """The MAPush runs under both criteria: ``"mapush"`` (MAPush's) and ``"strict"``.

    Rows of :func:`success_table`'s shape (family columns plus ``"all"``), counted over
    the ``mapush`` runs only; empty when there are none. A timeout or error has no
    ``stats.mapush_success`` and counts as a failure under both.
    """
    out = {}
    for name, predicate in (("mapush", mapush_success), ("strict", lambda r: r.get("success"))):
        table = _rate_table(records, predicate, only=(MAPUSH_PLANNER,))
        if MAPUSH_PLANNER in table:
            out[name] = table[MAPUSH_PLANNER]
    return out


def full_horizon_table(records: Sequence[dict[str, Any]]) -> dict[str, dict[str, Rate]]:
    """Table II: full-horizon plan rate of the LAMP planners per family (plus ``"all"``)."""
    return _rate_table(records, run_full_horizon, only=registry.lamp_planners())


def median_planning_time_table(records: Sequence[dict[str, Any]]
                               ) -> dict[str, dict[str, tuple[float | None, int]]]:
    """Median planning time per segment: planner -> family -> (median, n runs).

    The median over the *solved* runs of a cell of each run's planning time per segment
    (:func:`scenario_planning_time`), the statistic the paper quotes for LAMP-Lazy
    ("median approximately 2-3 s per segment"). Failed runs are left out here (the
    violin figure shows them at the failure line).
    """
    recs = family_records(records)
    fams = families(recs)
    out: dict[str, dict[str, tuple[float | None, int]]] = {}
    for p in planners(recs):
        mine = [r for r in recs if r["planner"] == p and r.get("success")]
        row = {}
        for fam in [*fams, "all"]:
            vals = [v[0] for r in mine if fam in ("all", r["suite"])
                    for v in [scenario_planning_time(r, math.inf)] if v is not None]
            row[fam] = (float(np.median(vals)) if vals else None, len(vals))
        out[p] = row
    return out


def scenario_planning_time(rec: dict[str, Any], fail_value: float) -> tuple[float, bool] | None:
    """(planning time per segment, failed) of one run for the violin figure.

    A successful run gives its total planning time over its segments; a failed one
    ``fail_value``. A successful run without any segment (object already at its goal)
    gives ``None``: it has no per-segment time.
    """
    if not rec.get("success"):
        return (float(fail_value), True)
    n = int(rec.get("segments") or 0)
    if n <= 0:
        return None
    total = rec.get("total_planning_time_s")
    if total is None:
        total = sum(rec.get("planning_time_s") or [])
    return (float(total) / n, False)


def planning_time_points(records: Sequence[dict[str, Any]], fail_value: float
                         ) -> dict[str, list[tuple[str, float, bool]]]:
    """Per planner: (family, planning time per segment, failed) of every run (violin dots)."""
    out: dict[str, list[tuple[str, float, bool]]] = {}
    recs = family_records(records)
    for p in planners(recs):
        pts = []
        for r in recs:
            if r["planner"] != p:
                continue
            v = scenario_planning_time(r, fail_value)
            if v is not None:
                pts.append((r["suite"], v[0], v[1]))
        out[p] = pts
    return out


def path_cost_comparison(records: Sequence[dict[str, Any]], reference: str = REFERENCE_PLANNER
                         ) -> dict[str, PathCost]:
    """LAMP-Lazy's makespan against each baseline's on mutually solved (scene, seed) pairs."""
    recs = family_records(records)
    by_key: dict[JobKey, dict[str, Any]] = {record_key(r): r for r in recs}
    out: dict[str, PathCost] = {}
    for base in planners(recs):
        if base == reference:
            continue
        pc = PathCost(base)
        for (suite, scene, planner, seed), rb in by_key.items():
            if planner != base:
                continue
            rr = by_key.get((suite, scene, reference, seed))
            if rr is None:
                continue
            ok_r, ok_b = bool(rr.get("success")), bool(rb.get("success"))
            if ok_r and ok_b:
                if float(rb.get("makespan") or 0) > 0:
                    pc.pairs.append(((suite, scene, seed), float(rr["makespan"]),
                                     float(rb["makespan"])))
            elif ok_r:
                pc.dnf_baseline += 1
            elif ok_b:
                pc.dnf_reference += 1
            else:
                pc.both_failed += 1
        out[base] = pc
    return out


def status_counts(records: Sequence[dict[str, Any]]) -> dict[str, Counter]:
    """Per planner: how many runs ended ok / timeout / error / crashed."""
    out: dict[str, Counter] = {}
    for r in records:
        out.setdefault(r["planner"], Counter())[r.get("status", "ok")] += 1
    return out


def record_runs(records: Sequence[dict[str, Any]]) -> dict[str, Counter]:
    """Per planner: how many of its (latest) records each invocation wrote.

    Keyed by the line's ``run_id`` (the index of the invocation in ``config.json``'s
    ``sessions``); ``None`` counts lines written before results carried one.
    """
    out: dict[str, Counter] = {}
    for r in records:
        rid = r.get("run_id")
        out.setdefault(r["planner"], Counter())[rid if isinstance(rid, int) else None] += 1
    return out


def failure_reasons(records: Sequence[dict[str, Any]]) -> dict[str, Counter]:
    """Per planner: failure reasons of the failed runs (first failed object's reason)."""
    out: dict[str, Counter] = {}
    for r in records:
        if r.get("success"):
            continue
        reason = r.get("failure_reason") or "failed"
        out.setdefault(r["planner"], Counter())[reason.split("\n")[0][:80]] += 1
    return out


@dataclass
class IrosRun:
    """One planner on the IROS case study."""

    planner: str
    seed: int
    success: bool
    status: str
    objects: list[dict[str, Any]]
    segments: int
    total_planning_time_s: float
    mean_planning_time_s: float | None  # total planning time / executed segments
    planning_time_s: list[float]
    makespan: int


def iros_summary(records: Sequence[dict[str, Any]]) -> list[IrosRun]:
    """The IROS runs, one per (planner, seed), with per-object outcomes."""
    runs = []
    for r in records:
        if r["suite"] != IROS_SUITE:
            continue
        times = [float(t) for t in (r.get("planning_time_s") or [])]
        seg = len(times)
        # objects carry all planning time, also the part spent before no segment at all
        obj_times = [o.get("planning_time_s") for o in (r.get("objects") or [])]
        total = (sum(float(t) for t in obj_times) if obj_times and None not in obj_times
                 else float(sum(times)))
        runs.append(IrosRun(
            planner=r["planner"], seed=int(r["seed"]), success=bool(r.get("success")),
            status=r.get("status", "ok"), objects=list(r.get("objects") or []), segments=seg,
            total_planning_time_s=total,
            # one definition of "per segment" everywhere: all planning over executed segments
            mean_planning_time_s=(total / seg) if seg else None, planning_time_s=times,
            makespan=int(r.get("makespan") or 0)))
    runs.sort(key=lambda x: (_rank(x.planner), x.planner, x.seed))
    return runs


def failure_line(config: dict[str, Any], records: Sequence[dict[str, Any]]) -> float:
    """Where failed runs are drawn: the run's planning limit, else its largest time cap."""
    for key in ("planning_limit_s",):
        v = config.get(key)
        if isinstance(v, int | float) and v > 0:
            return float(v)
    caps = [float(r["time_cap_s"]) for r in records if r.get("time_cap_s")]
    return max(caps) if caps else PAPER_PLANNING_LIMIT_S


# ------------------------------------------------------------------------------ figures
FAMILY_COLORS = {"random": "#1f77b4", "maze": "#ff7f0e", "tilt": "#2ca02c",
                 "warehouse": "#d62728"}


def _label(p: str) -> str:
    spec = _spec(p)
    return spec.label if spec is not None else p


def _color(p: str) -> str:
    spec = _spec(p)
    return spec.color if spec is not None else registry.DEFAULT_COLOR


def _marker(p: str) -> str:
    spec = _spec(p)
    return spec.marker if spec is not None else "o"


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
                body.set_facecolor(_color(p))
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
    ax.set_xticks(range(len(names)), [_label(p) for p in names], rotation=20, fontsize=8)
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
        ax.scatter(xs, ys, marker=_marker(base), color=_color(base),
                   s=22, alpha=0.8,
                   label=f"{_label(base)}: n={pc.n}, ratio={ratio}, "
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
                lw=0.8, color=_color(run.planner),
                label=f"{_label(run.planner)} (seed {run.seed})")
    ax.set_yscale("log")
    ax.set_xlabel("executed segment")
    ax.set_ylabel("planning time (s)")
    ax.set_title("IROS case study: planning time per segment", fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    fig.savefig(path, dpi=130)
    return path


# ----------------------------------------------------------------------------- markdown
def _fmt_s(v: float | None) -> str:
    if v is None:
        return "-"
    return f"{v:.3g}" if v < 100 else f"{v:.0f}"


def _table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def _paper(value: float | None) -> str:
    return "" if value is None else f" [paper {value:.0f}%]"


def success_markdown(table: dict[str, dict[str, Rate]], fams: Sequence[str]) -> str:
    rows = []
    if any(f in FAMILY_ORDER for f in fams) and "mapush" not in table:
        rows.append(["MAPush (paper only, not run)"]
                    + [(f"[paper {paper_success('mapush')[f]:.0f}%]" if f in FAMILY_ORDER
                        else "-") for f in fams] + ["-"])
    for p, row in table.items():
        # the paper's MAPush row counts MAPush's criterion: it is beside that one instead
        ref = {} if p == MAPUSH_PLANNER else paper_success(p)
        label = _label(p) + (" (strict criterion)" if p == MAPUSH_PLANNER else "")
        rows.append([label] + [row[f].cell() + _paper(ref.get(f)) for f in fams]
                    + [row["all"].cell()])
    return _table(["method", *fams, "all"], rows)


def mapush_criteria_markdown(table: dict[str, dict[str, Rate]], fams: Sequence[str]) -> str:
    """Both criteria of the MAPush runs; the paper's MAPush figures beside MAPush's one."""
    ref = paper_success(MAPUSH_PLANNER)
    labels = {"mapush": "MAPush criterion (0.5 m, position only, 120 s)",
              "strict": "strict criterion (0.1 m and 0.1 rad, as Table I)"}
    rows = [[labels[name]] + [row[f].cell() + (_paper(ref.get(f)) if name == "mapush" else "")
                              for f in fams] + [row["all"].cell()]
            for name, row in table.items()]
    return _table(["MAPush runs", *fams, "all"], rows)


def full_horizon_markdown(table: dict[str, dict[str, Rate]], fams: Sequence[str]) -> str:
    rows = []
    for p, row in table.items():
        ref = paper_full_horizon(p)
        rows.append([_label(p)] + [row[f].cell() + _paper(ref.get(f)) for f in fams]
                    + [row["all"].cell()])
    return _table(["method", *fams, "all"], rows)


def median_markdown(table: dict[str, dict[str, tuple[float | None, int]]],
                    fams: Sequence[str]) -> str:
    rows = [[_label(p)] + [f"{_fmt_s(row[f][0])} (n={row[f][1]})" for f in [*fams, "all"]]
            for p, row in table.items()]
    return _table(["method", *fams, "all"], rows)


def path_cost_markdown(costs: dict[str, PathCost]) -> str:
    rows = []
    for base, pc in costs.items():
        rows.append([
            f"LAMP-Lazy vs {_label(base)}", str(pc.n),
            "-" if pc.mean_ratio is None else f"{pc.mean_ratio:.3f}",
            "-" if pc.median_ratio is None else f"{pc.median_ratio:.3f}",
            str(pc.dnf_baseline), str(pc.dnf_reference), str(pc.both_failed)])
    return _table(["comparison", "n (both solved)", "mean cost ratio", "median cost ratio",
                   "DNF baseline only", "DNF LAMP-Lazy only", "both failed"], rows)


def iros_markdown(runs: Sequence[IrosRun], run_dir: Path) -> str:
    if not runs:
        return ("No IROS runs in this folder (run `lamp bench --suite iros ...` to add the "
                "case study).")
    parts = []
    rows = []
    for run in runs:
        n_ok = sum(bool(o.get("success")) for o in run.objects)
        rows.append([_label(run.planner), str(run.seed), "yes" if run.success else "no",
                     f"{n_ok}/{len(run.objects)}", str(run.segments),
                     _fmt_s(run.mean_planning_time_s), _fmt_s(run.total_planning_time_s),
                     str(run.makespan), run.status])
    parts.append(_table(["method", "seed", "all objects", "objects placed", "segments",
                         "planning time / segment (s)", "total planning time (s)",
                         "makespan (steps)", "status"], rows))
    parts.append(f"Paper: LAMP-Lazy placed all 9 objects with {PAPER_IROS_MEAN_S} s of "
                 "planning per segment on average; the other methods failed part-way. "
                 "Objects are moved one after another; a failed object stays where it "
                 "stopped and the next one is attempted.")
    for run in runs:
        orow = []
        for i, o in enumerate(run.objects):
            seg = int(o.get("segments") or 0)
            pt = o.get("planning_time_s")
            per = (float(pt) / seg) if (pt is not None and seg) else None
            orow.append([str(i + 1), "yes" if o.get("success") else "no", str(seg),
                         _fmt_s(None if pt is None else float(pt)), _fmt_s(per),
                         "yes" if o.get("full_horizon_plan") else "no",
                         (o.get("failure_reason") or "").replace("|", "/")])
        parts.append(f"**{_label(run.planner)}, seed {run.seed}**: per object\n\n" + _table(
            ["object", "success", "segments", "planning time (s)", "per segment (s)",
             "full-horizon plan", "failure reason"], orow))
    gif = run_dir / "iros.gif"
    if gif.exists():
        parts.append("Animation of the LAMP-Lazy assembly: [iros.gif](iros.gif)\n\n"
                     "![IROS assembly](iros.gif)")
    else:
        parts.append("No animation yet (`lamp bench --suite iros --planners lazy "
                     "--render-iros --resume --out DIR` writes `DIR/iros.gif`).")
    return "\n\n".join(parts)


def _config_markdown(config: dict[str, Any], records: Sequence[dict[str, Any]]) -> str:
    lines = []
    sessions = config.get("sessions") or []
    for i, s in enumerate(sessions):
        lines.append(f"- run {i}: `{s.get('command', '?')}` on {s.get('date', '?')}, commit "
                     f"`{s.get('git_commit') or 'unknown'}`"
                     + (" (uncommitted changes)" if s.get("git_dirty") else "")
                     + (f", on {s['machine'].get('cpu', '?')}"
                        if isinstance(s.get("machine"), dict) else ""))
    origin = []
    by_run = record_runs(records)
    # lines without a run id are older than the first line with one
    first = min((rid for c in by_run.values() for rid in c if rid is not None), default=None)
    older = ("" if not first else " (run 0)" if first == 1 else f" (runs 0-{first - 1})")
    for p, c in sorted(by_run.items(), key=lambda kv: _rank(kv[0])):
        parts = []
        for rid, n in sorted(c.items(), key=lambda kv: (kv[0] is None, kv[0] or 0)):
            if rid is None:
                parts.append(f"{n} written before lines carried a run id{older}")
            else:
                s = sessions[rid] if 0 <= rid < len(sessions) else {}
                commit = (s.get("git_commit") or "unknown")[:10]
                parts.append(f"{n} from run {rid} (commit `{commit}`)")
        origin.append(f"{_label(p)}: " + ", ".join(parts))
    if origin:
        lines.append("- the records counted (the newest per job): " + "; ".join(origin))
    if config:
        m = config.get("machine", {})
        lines.append(f"- machine: {m.get('cpu', '?')}, {m.get('cpu_count', '?')} CPUs, "
                     f"{m.get('memory_gb', '?')} GB, {m.get('platform', '?')}, "
                     f"Python {m.get('python', '?')}")
        lines.append(f"- backend {config.get('backend', '?')}, {config.get('workers', '?')} "
                     f"workers; model `{config.get('model', '?')}`; seeds "
                     f"{config.get('seeds', '?')}")
        lim = config.get("planning_limit_s")
        line = f"- wall-clock cap per job: {config.get('time_cap_s', '?')} s per object of the scene"
        if any(p in (config.get("planners") or []) for p in ("astar", "astar-replan")):
            line += f"; LAMP-A* cumulative planning limit per object: {lim} s" + (
                f" (**the paper uses {PAPER_PLANNING_LIMIT_S:g} s**; lowered so the full run "
                "fits the time budget)" if lim != PAPER_PLANNING_LIMIT_S else "")
        lines.append(line)
        other = config.get("planner_planning_limits_s")
        if other:
            lines.append("- planning limits per object used by each planner: "
                         + ", ".join(f"{_label(k)} {v:g} s" for k, v in other.items()))
    else:
        lines.append("- no config.json in this folder: caps and provenance unknown")
    counts = status_counts(records)
    lines.append("- runs recorded: " + ", ".join(
        f"{_label(p)} {sum(c.values())}"
        + (" (" + ", ".join(f"{k} {v}" for k, v in sorted(c.items()) if k != "ok") + ")"
           if any(k != "ok" for k in c) else "")
        for p, c in sorted(counts.items(), key=lambda kv: _rank(kv[0]))))
    return "\n".join(lines)


def build_report(run_dir: str | Path) -> Path:
    """Write ``run_dir/report.md`` and its figures from ``results.jsonl``; return its path."""
    run_dir = Path(run_dir)
    records = load_results(run_dir)
    config = load_config(run_dir)
    fams = families(records)
    fail_value = failure_line(config, records)
    md = ["# LAMP benchmark report", "",
          f"Rebuilt from `{RESULTS_FILE}` by `lamp report {run_dir}`; the paper's published "
          "numbers are shown in brackets beside ours.", "", "## Run", "",
          _config_markdown(config, records), ""]

    main = family_records(records)
    if main:
        st = success_table(records)
        md += ["## Table I: success rate", "",
               "Success: every object within 0.1 m and 0.1 rad of its goal, inside the map "
               "throughout; timeouts and errors count as failures.", "",
               success_markdown(st, fams), ""]
        crit = mapush_criteria_table(records)
        if crit:
            md += ["### MAPush criterion", "",
                   f"The paper counts MAPush as successful {MAPUSH_CRITERION} (its own "
                   "criterion, recorded per run as `stats.mapush_success`); its MAPush "
                   "figures are shown beside that row. Table I above counts the strict "
                   "criterion for every method, MAPush included.", "",
                   mapush_criteria_markdown(crit, fams), ""]
        fh = full_horizon_table(records)
        if fh:
            md += ["## Table II: full-horizon plan rate (LAMP planners)", "",
                   "A complete plan to the goal found before the first segment was executed "
                   "(the paper's single LAMP-A* row is shown beside both variants).", "",
                   full_horizon_markdown(fh, fams), ""]
        md += ["## Median planning time per segment (s)", "",
               "Median over the solved runs of each cell of the run's total planning time "
               "(all planning, also a final search that executed nothing) divided by its "
               "executed segments (n = solved runs); the paper reports about "
               f"{PAPER_LAZY_MEDIAN_S} s for LAMP-Lazy.", "",
               median_markdown(median_planning_time_table(records), fams), ""]
        figs = []
        if plot_planning_time(records, fail_value, run_dir / "planning_time.png"):
            figs.append("![planning time per segment](planning_time.png)")
        if plot_planning_time(records, fail_value, run_dir / "planning_time_by_family.png",
                              by_family=True):
            figs.append("![planning time per segment by family](planning_time_by_family.png)")
        md += ["## Planning time per segment", "",
               "One dot per run: its total planning time (all planning) divided by its "
               "executed segments; "
               f"failed runs are drawn at the dashed line ({fail_value:g} s), as in the "
               "paper's figure (log scale; boxes show the median and quartiles).", "",
               *figs, ""]
        costs = path_cost_comparison(records)
        if costs:
            md += ["## Path cost (makespan)", "",
                   "LAMP-Lazy against each baseline on the scenes both solved; ratio = "
                   "LAMP-Lazy makespan / baseline makespan, averaged over those scenes. DNF: "
                   "one-sided failures, excluded from the ratios.", "",
                   path_cost_markdown(costs), ""]
            if plot_path_cost(costs, run_dir / "path_cost.png"):
                md += ["![path cost](path_cost.png)", ""]
        reasons = failure_reasons(main)
        if reasons:
            rows = [[_label(p), "; ".join(f"{k}: {v}" for k, v in c.most_common())]
                    for p, c in sorted(reasons.items(), key=lambda kv: _rank(kv[0]))]
            md += ["## Failure reasons", "", _table(["method", "reasons (runs)"], rows), ""]
    runs = iros_summary(records)
    n_obj = max((len(r.objects) for r in runs), default=9)
    md += [f"## IROS case study ({n_obj} objects)", "", iros_markdown(runs, run_dir), ""]
    if runs and plot_iros(runs, run_dir / "iros_planning_time.png"):
        md += ["![IROS planning time](iros_planning_time.png)", ""]
    out = run_dir / "report.md"
    from lamp.io import write_text_atomic

    write_text_atomic(out, "\n".join(md))
    return out
