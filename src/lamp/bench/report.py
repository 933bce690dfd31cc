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

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from lamp.bench.jobs import RESULTS_FILE
from lamp.bench.presentation import label, paper_full_horizon, paper_success, rank
from lamp.bench.scene_bounds import with_scene_bounds
from lamp.bench.tables import (  # noqa: F401 - re-exported: the report's numbers
    FAMILY_ORDER,
    IROS_SUITE,
    MAPUSH_CRITERION,
    MAPUSH_PLANNER,
    PAPER_IROS_MEAN_S,
    PAPER_LAZY_MEDIAN_S,
    PAPER_PLANNING_LIMIT_S,
    REFERENCE_PLANNER,
    IrosRun,
    PathCost,
    Rate,
    audit_table,
    failure_line,
    failure_reasons,
    families,
    family_records,
    full_horizon_table,
    iros_summary,
    lifelong_tables,
    load_config,
    load_results,
    makespan_bound_table,
    mapush_criteria_table,
    mapush_success,
    median_planning_time_table,
    path_cost_comparison,
    planners,
    planning_time_points,
    record_runs,
    run_full_horizon,
    scenario_planning_time,
    status_counts,
    success_table,
)


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
        paper = paper_success(MAPUSH_PLANNER)
        rows.append(["MAPush (paper only, not run)"]
                    + [(f"[paper {paper[f]:.0f}%]" if f in FAMILY_ORDER else "-")
                       for f in fams] + ["-"])
    for p, row in table.items():
        # the paper's MAPush row counts MAPush's criterion: it is beside that one instead
        ref = {} if p == MAPUSH_PLANNER else paper_success(p)
        method = label(p) + (" (strict criterion)" if p == MAPUSH_PLANNER else "")
        rows.append([method] + [row[f].cell() + _paper(ref.get(f)) for f in fams]
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
        rows.append([label(p)] + [row[f].cell() + _paper(ref.get(f)) for f in fams]
                    + [row["all"].cell()])
    return _table(["method", *fams, "all"], rows)


def median_markdown(table: dict[str, dict[str, tuple[float | None, int]]],
                    fams: Sequence[str], fmt: str | None = None) -> str:
    def cell(v: float | None) -> str:
        return _fmt_s(v) if fmt is None or v is None else format(v, fmt)

    rows = [[label(p)] + [f"{cell(row[f][0])} (n={row[f][1]})" for f in [*fams, "all"]]
            for p, row in table.items()]
    return _table(["method", *fams, "all"], rows)


def path_cost_markdown(costs: dict[str, PathCost]) -> str:
    rows = []
    for base, pc in costs.items():
        rows.append([
            f"LAMP-Lazy vs {label(base)}", str(pc.n),
            "-" if pc.mean_ratio is None else f"{pc.mean_ratio:.3f}",
            "-" if pc.median_ratio is None else f"{pc.median_ratio:.3f}",
            str(pc.dnf_baseline), str(pc.dnf_reference), str(pc.both_failed)])
    return _table(["comparison", "n (both solved)", "mean cost ratio", "median cost ratio",
                   "DNF baseline only", "DNF LAMP-Lazy only", "both failed"], rows)


def audit_markdown(audits: dict[str, dict[str, Any]]) -> str:
    """The re-checked recordings, a row per planner."""
    rows = [[label(p), str(a["runs"]), str(a["failed"]), str(a["collisions"]),
             "-" if a["lead"] is None else f"{a['lead']:.3f}", str(a["errors"])]
            for p, a in sorted(audits.items(), key=lambda kv: rank(kv[0]))]
    return _table(["method", "runs", "failed a check", "collisions", "largest judged push "
                   "lead (m)", "checks that could not run"], rows)


def _audit_section(records: Sequence[dict[str, Any]]) -> list[str]:
    """The report's lines on the re-checked recordings (none when nothing was recorded)."""
    audits = audit_table(records)
    if not audits:
        return []
    return ["## Recordings re-checked", "",
            "Every recorded run (`--record`) re-checked without the planner, as `lamp check` "
            "does: collisions between robots, objects, obstacles and the border beyond "
            "contact tolerance, and, for concurrent runs without noise or knocks, pushed "
            "objects ahead of their pushers by more than the reach admission assumes.", "",
            audit_markdown(audits), ""]


def iros_markdown(runs: Sequence[IrosRun], run_dir: Path) -> str:
    if not runs:
        return ("No IROS runs in this folder (run `lamp bench --suite iros ...` to add the "
                "case study).")
    parts = []
    rows = []
    for run in runs:
        n_ok = sum(bool(o.get("success")) for o in run.objects)
        rows.append([label(run.planner), str(run.seed), "yes" if run.success else "no",
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
        parts.append(f"**{label(run.planner)}, seed {run.seed}**: per object\n\n"
                     + _table(["object", "success", "segments", "planning time (s)",
                               "per segment (s)", "full-horizon plan", "failure reason"],
                              orow))
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
    for p, c in sorted(by_run.items(), key=lambda kv: rank(kv[0])):
        parts = []
        for rid, n in sorted(c.items(), key=lambda kv: (kv[0] is None, kv[0] or 0)):
            if rid is None:
                parts.append(f"{n} written before lines carried a run id{older}")
            else:
                s = sessions[rid] if 0 <= rid < len(sessions) else {}
                commit = (s.get("git_commit") or "unknown")[:10]
                parts.append(f"{n} from run {rid} (commit `{commit}`)")
        origin.append(f"{label(p)}: " + ", ".join(parts))
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
                         + ", ".join(f"{label(k)} {v:g} s" for k, v in other.items()))
    else:
        lines.append("- no config.json in this folder: caps and provenance unknown")
    counts = status_counts(records)
    lines.append("- runs recorded: " + ", ".join(
        f"{label(p)} {sum(c.values())}"
        + (" (" + ", ".join(f"{k} {v}" for k, v in sorted(c.items()) if k != "ok") + ")"
           if any(k != "ok" for k in c) else "")
        for p, c in sorted(counts.items(), key=lambda kv: rank(kv[0]))))
    return "\n".join(lines)


def build_report(run_dir: str | Path) -> Path:
    """Write ``run_dir/report.md`` and its figures from ``results.jsonl``; return its path."""
    from lamp.bench.figures import plot_iros, plot_path_cost, plot_planning_time

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
        bounds = makespan_bound_table(with_scene_bounds(records))
        if any(n for row in bounds.values() for _, n in row.values()):
            md += ["## Makespan over its lower bound", "",
                   "Median over the solved runs of each cell of the simulated makespan "
                   "divided by the scene's makespan lower bound, computed from each run's "
                   "scene as this report is made (`lamp.scene.bounds`: for each object, "
                   "the nearest robot's drive to touch it, straight or round the "
                   "obstacles, plus the shortest travel "
                   "of the object's inscribed disk round the obstacles to within the "
                   "success tolerance, at the robots' speed, maximised over objects; no "
                   "run can be shorter). A lifelong run keeps the bound over its tasks it "
                   "recorded.", "",
                   median_markdown(bounds, fams, ".2f"), ""]
        for name, table in lifelong_tables(records).items():
            md += [f"## Lifelong: {name}", "",
                   "Median over the solved runs with tasks (`result.json`'s `lifelong`; "
                   "`docs/lifelong.md`).", "", median_markdown(table, fams, ".1f"), ""]
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
            rows = [[label(p), "; ".join(f"{k}: {v}" for k, v in c.most_common())]
                    for p, c in sorted(reasons.items(), key=lambda kv: rank(kv[0]))]
            md += ["## Failure reasons", "", _table(["method", "reasons (runs)"], rows), ""]
    md += _audit_section(records)
    runs = iros_summary(records)
    n_obj = max((len(r.objects) for r in runs), default=9)
    md += [f"## IROS case study ({n_obj} objects)", "", iros_markdown(runs, run_dir), ""]
    if runs and plot_iros(runs, run_dir / "iros_planning_time.png"):
        md += ["![IROS planning time](iros_planning_time.png)", ""]
    out = run_dir / "report.md"
    from lamp.io import write_text_atomic

    write_text_atomic(out, "\n".join(md))
    return out
