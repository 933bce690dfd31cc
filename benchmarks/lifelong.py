"""The lifelong table: the fleet against first come, first served on the ``lifelong`` family.

Reads two ``lamp bench`` result folders of the family, the fleet's (``--schedule
concurrent``) and the baseline's (``--schedule sequential``: one task at a time by the
whole team, in release order), and prints a markdown table per scene (robots, objects,
tasks done, throughput per simulated hour, service time median and p95, makespan and its
chain lower bound, collisions the independent safety check finds in the recordings), then
the summary the lifelong targets are stated in: every task done, the median over scenes of
the throughput ratio fleet / baseline and of the median-service-time ratio.

    lamp bench --suites lifelong --planners lazy --schedule concurrent --record --out CON
    lamp bench --suites lifelong --planners lazy --schedule sequential --record --out FCFS
    python benchmarks/lifelong.py CON FCFS [--out results/lifelong/table.md]
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

from fleet_schedule import collisions, records_by_scene


def _f(x: float | None, fmt: str = ".0f") -> str:
    return "-" if x is None else format(x, fmt)


def _row(rec: dict, hits: int | None) -> list[str]:
    life = rec.get("lifelong") or {}
    return [f"{life.get('done', 0)}/{life.get('tasks', '-')}",
            _f(life.get("throughput_per_hour"), ".1f"), _f(life.get("service_median_s")),
            _f(life.get("service_p95_s")), _f(rec.get("makespan_s")),
            _f(rec.get("makespan_lower_bound_s")), _f(hits, "d")]


def table(con: Path, fcfs: Path) -> str:
    """The markdown table and summary of the module docstring."""
    a, b = records_by_scene(con), records_by_scene(fcfs)
    lines = [
        "| scene | robots | objects | fleet: done | per hour | service median (s) | p95 (s) "
        "| makespan (s) | bound (s) | collisions | FCFS: done | per hour | service median "
        "(s) | p95 (s) | makespan (s) | bound (s) | collisions | throughput ratio "
        "| service ratio |",
        "|" + "---|" * 19,
    ]
    thr, svc, done, hits_all = [], [], [], []
    for name in sorted(set(a) | set(b)):
        ra, rb = a.get(name), b.get(name)
        if ra is None or rb is None:
            continue
        ha, hb = collisions(con, ra), collisions(fcfs, rb)
        la, lb = ra.get("lifelong") or {}, rb.get("lifelong") or {}
        t = (la["throughput_per_hour"] / lb["throughput_per_hour"]
             if la.get("throughput_per_hour") and lb.get("throughput_per_hour") else None)
        s = (la["service_median_s"] / lb["service_median_s"]
             if la.get("service_median_s") and lb.get("service_median_s") else None)
        thr += [t] if t is not None else []
        svc += [s] if s is not None else []
        done.append((la.get("done") == la.get("tasks"), lb.get("done") == lb.get("tasks")))
        hits_all += [h for h in (ha, hb) if h is not None]
        from lamp.suites.registry import resolve_scene

        scene = resolve_scene(name)
        n_obj, n_rob = len(scene.objects), scene.n_robots
        lines.append(f"| {name} | {n_rob} | {n_obj} | " + " | ".join(_row(ra, ha)) + " | "
                     + " | ".join(_row(rb, hb)) + f" | {_f(t, '.2f')} | {_f(s, '.2f')} |")
    lines += [
        "",
        f"- every task done: fleet {sum(d[0] for d in done)}/{len(done)} scenes, "
        f"first come first served {sum(d[1] for d in done)}/{len(done)}",
        f"- throughput fleet / FCFS, median over scenes: "
        f"{_f(statistics.median(thr) if thr else None, '.2f')} "
        f"(range {_f(min(thr) if thr else None, '.2f')}-{_f(max(thr) if thr else None, '.2f')})",
        f"- median service time fleet / FCFS, median over scenes: "
        f"{_f(statistics.median(svc) if svc else None, '.2f')} "
        f"(range {_f(min(svc) if svc else None, '.2f')}-{_f(max(svc) if svc else None, '.2f')})",
        f"- collisions in the recordings (independent check): {sum(hits_all)} in "
        f"{len(hits_all)} recordings",
    ]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("con", type=Path, help="lamp bench folder, --schedule concurrent")
    ap.add_argument("fcfs", type=Path, help="lamp bench folder, --schedule sequential")
    ap.add_argument("--out", type=Path, help="also write the table to this file")
    args = ap.parse_args()
    text = table(args.con, args.fcfs)
    print(text, end="")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
