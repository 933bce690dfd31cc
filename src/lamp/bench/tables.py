"""The numbers of the benchmark report, computed from ``DIR/results.jsonl`` alone: loading
and the pure table functions (:func:`success_table`, :func:`full_horizon_table`,
:func:`median_planning_time_table`, :func:`path_cost_comparison`, :func:`iros_summary` ...)
that the tests check against hand-computed values. Definitions: :mod:`lamp.bench.report`.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lamp.bench.jobs import RESULTS_FILE, JobKey, latest_by_key, read_records, record_key
from lamp.bench.presentation import rank, table_ii_planners, table_order

#: The paper's four map families, in its column order.
FAMILY_ORDER = ("random", "maze", "tilt", "warehouse")
#: The suite reported as the long-horizon case study rather than as a family.
IROS_SUITE = "iros"
REFERENCE_PLANNER = "lazy"

# Per-planner facts (row order, labels, colours, markers, the paper's Table I and II
# figures, the rows of Table II) come from ``lamp.bench.presentation``. The paper's
# MAPush row counts MAPush's own criterion (:data:`MAPUSH_CRITERION`), every other row the
# strict one.
#: The MAPush baseline's own success criterion (paper, footnote to Sec. V-A), recorded per
#: run as ``stats.mapush_success`` by ``lamp.baselines.mapush``.
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


def _ordered(names: Iterable[str], order: Sequence[str]) -> list[str]:
    names = set(names)
    return [n for n in order if n in names] + sorted(names - set(order))


def families(records: Iterable[dict[str, Any]]) -> list[str]:
    """Suites of ``records`` other than IROS, in the paper's order then by name."""
    return _ordered((r["suite"] for r in records if r["suite"] != IROS_SUITE), FAMILY_ORDER)


def planners(records: Iterable[dict[str, Any]]) -> list[str]:
    return _ordered((r["planner"] for r in records), table_order())


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
    return _rate_table(records, run_full_horizon, only=table_ii_planners())


def median_planning_time_table(records: Sequence[dict[str, Any]]
                               ) -> dict[str, dict[str, tuple[float | None, int]]]:
    """Median planning time per segment: planner -> family -> (median, n runs).

    The median over the *solved* runs of a cell of each run's planning time per segment
    (:func:`scenario_planning_time`), the statistic the paper quotes for LAMP-Lazy
    ("median approximately 2-3 s per segment"). Failed runs are left out here (the
    violin figure shows them at the failure line).
    """
    return _median_table(records, lambda r: (v[0] if (v := scenario_planning_time(r, math.inf))
                                             is not None else None))


def makespan_bound_table(records: Sequence[dict[str, Any]]
                         ) -> dict[str, dict[str, tuple[float | None, int]]]:
    """Median makespan over its lower bound (``makespan_over_bound``, result.json; the bound
    is ``lamp.scene.bounds``'): planner -> family -> (median, n solved runs with one)."""
    return _median_table(records, lambda r: r.get("makespan_over_bound"))


def audit_table(records: Sequence[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """The recorded runs re-checked (``audit``, ``lamp check``'s verdict) per planner: how
    many, how many failed, their collisions, the largest judged push lead and the checks
    that could not run; empty when no run was recorded."""
    out: dict[str, dict[str, Any]] = {}
    for r in latest_by_key(records).values():
        a = r.get("audit")
        if not a:
            continue
        row = out.setdefault(r["planner"], {"runs": 0, "failed": 0, "collisions": 0,
                                            "lead": None, "errors": 0})
        row["runs"] += 1
        if "error" in a:
            row["errors"] += 1
            continue
        row["failed"] += not a["ok"]
        row["collisions"] += a["collisions"]
        if a["push_lead_judged"] and a["push_lead_m"] is not None:
            row["lead"] = max(a["push_lead_m"], row["lead"] if row["lead"] is not None
                              else -math.inf)
    return out


def lifelong_tables(records: Sequence[dict[str, Any]]
                    ) -> dict[str, dict[str, dict[str, tuple[float | None, int]]]]:
    """A lifelong run's figures (``result.json``'s ``lifelong``): figure -> planner ->
    family -> (median over the solved runs, their number), for the throughput per hour
    and the median service time; empty when no run has tasks."""
    if not any(r.get("lifelong") for r in records):
        return {}
    return {name: _median_table(records, lambda r, k=key: (r.get("lifelong") or {}).get(k))
            for name, key in (("tasks done per hour", "throughput_per_hour"),
                              ("median service time (s)", "service_median_s"))}


def _median_table(records: Sequence[dict[str, Any]], value: Callable[[dict[str, Any]], Any]
                  ) -> dict[str, dict[str, tuple[float | None, int]]]:
    """planner -> family (and ``"all"``) -> (median of ``value`` over the solved runs where
    it is not None, their number)."""
    recs = family_records(records)
    fams = families(recs)
    out: dict[str, dict[str, tuple[float | None, int]]] = {}
    for p in planners(recs):
        mine = [r for r in recs if r["planner"] == p and r.get("success")]
        row = {}
        for fam in [*fams, "all"]:
            vals = [float(v) for r in mine if fam in ("all", r["suite"])
                    if (v := value(r)) is not None]
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
    runs.sort(key=lambda x: (rank(x.planner), x.planner, x.seed))
    return runs


def failure_line(config: dict[str, Any], records: Sequence[dict[str, Any]]) -> float:
    """Where failed runs are drawn: the run's planning limit, else its largest time cap."""
    for key in ("planning_limit_s",):
        v = config.get(key)
        if isinstance(v, int | float) and v > 0:
            return float(v)
    caps = [float(r["time_cap_s"]) for r in records if r.get("time_cap_s")]
    return max(caps) if caps else PAPER_PLANNING_LIMIT_S

