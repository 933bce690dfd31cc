"""The fleet table: the ``fleet`` family moved one object after another and concurrently.

Reads ``lamp bench`` result folders of the family, one per schedule (and planner), and
prints a markdown table per scene (robots, objects, map, success, makespan of each,
the ratio concurrent / sequential, planning per segment, robot utilisation, collisions
found by the independent safety check in the recordings), then the summary the fleet
targets are stated in: success, the median makespan ratio over the family and over the
scenes with at least three sub-teams' worth of robots, and the collisions.

    lamp bench --suites fleet --planners lazy --schedule sequential --out SEQ
    lamp bench --suites fleet --planners lazy --schedule concurrent --record --out CON
    lamp bench --suites fleet --planners gco-var --schedule concurrent --record --out GCO
    python benchmarks/fleet_schedule.py SEQ CON [--peer GCO] [--out results/fleet/table.md]

``--seeds DIR`` instead summarises a folder run with several seeds (``--num-seeds 3``):
success per seed and the collisions in all its recordings.
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

from lamp.bench.scene_bounds import record_scene
from lamp.contract.model import MAX_ROBOTS
from lamp.scene.bounds import makespan_lower_bound


def records_by_scene(folder: Path) -> dict[str, dict]:
    """A ``lamp bench`` folder's records by scene (the last of a scene wins)."""
    out = {}
    for line in (folder / "results.jsonl").read_text().splitlines():
        if line.strip():
            rec = json.loads(line)
            out[rec["scene"]] = rec  # the last record of a scene wins (reruns)
    return out


def collisions(folder: Path, rec: dict) -> int | None:
    """Violations the safety check finds in the job's recording (None: not recorded)."""
    from lamp.record.safety import check_run_dir

    run = folder / "recordings" / rec["suite"] / f"{rec['scene']}-{rec['planner']}-s{rec['seed']}"
    if not (run / "recording.json").exists():
        return None
    return len(check_run_dir(run).violations)


def _f(x: float | None, fmt: str = ".1f") -> str:
    return "-" if x is None else format(x, fmt)


def _makespan(rec: dict | None) -> str:
    """A run's makespan, or "-" when it did not place every object (a failed run's
    clock stops where it gave up: no makespan to compare)."""
    return _f(rec["makespan_s"]) if rec and rec["success"] and rec.get("makespan_s") else "-"


def table(seq: Path, con: Path, peer: Path | None) -> str:
    s_recs, c_recs = records_by_scene(seq), records_by_scene(con)
    p_recs = records_by_scene(peer) if peer else {}
    rows = ["| scene | robots | objects | map (m) | lower bound (s) | seq ok | seq makespan (s) | "
            "conc ok | conc makespan (s) | conc / bound | ratio | plan/seg seq (s) | "
            "plan/seg conc (s) | working | collisions | peer ok | peer makespan (s) |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    ratios, big, over, ok, hits, checked = [], [], [], 0, 0, 0
    for name in sorted(c_recs):
        c, s, p = c_recs[name], s_recs.get(name), p_recs.get(name)
        scene = record_scene(c)
        bound = makespan_lower_bound(scene).seconds
        c_over = c["makespan_s"] / bound if c["success"] and bound else None
        if c_over is not None:
            over.append(c_over)
        ratio = None
        if s and c["success"] and s["success"]:
            ratio = c["makespan_s"] / s["makespan_s"]
            ratios.append(ratio)
            if scene.n_robots >= 3 * MAX_ROBOTS:
                big.append(ratio)
        ok += bool(c["success"])
        n_hits = collisions(con, c)
        if n_hits is not None:
            checked += 1
            hits += n_hits
        fleet = c.get("stats", {}).get("fleet", {})
        rows.append("| " + " | ".join([
            name, str(scene.n_robots), str(len(scene.objects)),
            f"{scene.workspace[0]:.0f} x {scene.workspace[1]:.0f}", _f(bound),
            "-" if s is None else ("yes" if s["success"] else "no"),
            _makespan(s), "yes" if c["success"] else "no", _makespan(c),
            _f(c_over, ".2f"),
            _f(ratio, ".2f"), _f(s and s.get("planning_time_per_segment_s"), ".3f"),
            _f(c.get("planning_time_per_segment_s"), ".3f"),
            _f(fleet.get("utilisation", {}).get("working"), ".2f"),
            "-" if n_hits is None else str(n_hits),
            "-" if p is None else ("yes" if p["success"] else "no"),
            _makespan(p)]) + " |")
    n = len(c_recs)
    seq_ok = sum(bool(r["success"]) for r in s_recs.values())
    summary = [
        "",
        f"- concurrent success: {ok}/{n} ({100 * ok / max(n, 1):.0f}%); sequential "
        f"{seq_ok}/{len(s_recs)}"
        + (f"; peer {sum(bool(r['success']) for r in p_recs.values())}/{len(p_recs)}"
           if p_recs else ""),
        f"- makespan concurrent / sequential (scenes both solved, {len(ratios)}): median "
        f"{_f(statistics.median(ratios) if ratios else None, '.2f')}; on the "
        f"{len(big)} with at least {3 * MAX_ROBOTS} robots: median "
        f"{_f(statistics.median(big) if big else None, '.2f')}",
        f"- concurrent makespan / lower bound (`lamp.scene.bounds`; {len(over)} placed every "
        f"object): median {_f(statistics.median(over) if over else None, '.2f')}",
        f"- collisions found by the safety check: {hits} in {checked} recordings",
    ]
    return "\n".join(rows + summary) + "\n"


def seeds_summary(folder: Path) -> str:
    """Success per seed and collisions over every recording of ``folder``."""
    by_seed: dict[int, list[dict]] = {}
    for line in (folder / "results.jsonl").read_text().splitlines():
        if line.strip():
            rec = json.loads(line)
            by_seed.setdefault(int(rec["seed"]), []).append(rec)
    lines = []
    hits = checked = 0
    for seed, recs in sorted(by_seed.items()):
        ok = sum(bool(r["success"]) for r in recs)
        failed = ", ".join(r["scene"] for r in recs if not r["success"]) or "none"
        lines.append(f"- seed {seed}: {ok}/{len(recs)} ({100 * ok / len(recs):.0f}%); "
                     f"failed: {failed}")
        for r in recs:
            n = collisions(folder, r)
            if n is not None:
                checked, hits = checked + 1, hits + n
    lines.append(f"- collisions found by the safety check: {hits} in {checked} recordings")
    return "\n".join(lines + _spread(by_seed)) + "\n"


def _spread(by_seed: dict[int, list[dict]]) -> list[str]:
    """Per scene, the makespan of each seed and how far apart they lie (max / min over the
    seeds that solved it)."""
    seeds = sorted(by_seed)
    spans: dict[str, dict[int, float]] = {}
    for seed, recs in by_seed.items():
        for r in recs:
            if r["success"] and r.get("makespan_s") is not None:
                spans.setdefault(r["scene"], {})[seed] = float(r["makespan_s"])
    if len(seeds) < 2 or not spans:
        return []
    rows = ["", "| scene | " + " | ".join(f"seed {s} (s)" for s in seeds) + " | max / min |",
            "|---|" + "---|" * (len(seeds) + 1)]
    ratios = {}
    for scene, got in sorted(spans.items()):
        ratios[scene] = max(got.values()) / min(got.values())
        rows.append(f"| {scene} | " + " | ".join(_f(got.get(s), ".1f") for s in seeds)
                    + f" | {ratios[scene]:.2f} |")
    worst = max(ratios, key=lambda k: ratios[k])
    rows += ["", f"- makespan max / min over the seeds, per scene: median "
             f"{statistics.median(ratios.values()):.2f}, largest {ratios[worst]:.2f} ({worst})"]
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sequential", type=Path, nargs="?")
    ap.add_argument("concurrent", type=Path, nargs="?")
    ap.add_argument("--seeds", type=Path, help="summarise this several-seed folder instead")
    ap.add_argument("--peer", type=Path, help="the peer's (GCo_var) concurrent folder")
    ap.add_argument("--out", type=Path, help="also write the table here")
    args = ap.parse_args()
    if args.seeds is not None:
        text = seeds_summary(args.seeds)
    elif args.sequential is None or args.concurrent is None:
        ap.error("give SEQUENTIAL and CONCURRENT folders, or --seeds FOLDER")
    else:
        text = table(args.sequential, args.concurrent, args.peer)
    print(text, end="")
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)


if __name__ == "__main__":
    main()
