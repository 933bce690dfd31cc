"""Per-family statistics of the suites, computed from their manifests (``STATS.md``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from lamp.suites.registry import SUITES, suite_manifest


def _mmm(values: list[float], fmt: str = "{:.2f}") -> str:
    if not values:
        return "-"
    a = np.asarray(values, dtype=float)
    return " / ".join(fmt.format(v) for v in (a.min(), float(np.median(a)), a.max()))


def family_stats(manifest: dict[str, Any]) -> dict[str, Any]:
    """Summary numbers of a single-object suite's manifest."""
    objs = [s["objects"][0] for s in manifest["scenes"]]
    circles = [o for o in objs if o["type"] == "circle"]
    rects = [o for o in objs if o["type"] == "rectangle"]
    free = [o["free_route"] for o in objs]
    roomy = [o["robot_route"] for o in objs]
    return {
        "scenes": len(objs),
        "circles": len(circles),
        "rectangles": len(rects),
        "circle_radius": [o["radius"] for o in circles],
        "rect_sides": [v for o in rects for v in o["size"]],
        "obstacles": [s["n_obstacles"] for s in manifest["scenes"]],
        "free_length": [r["length"] for r in free],
        "free_clearance": [r["min_clearance"] for r in free],
        "robot_length": [r["length"] for r in roomy],
        "robot_clearance": [r["min_clearance"] for r in roomy],
        "ratio": [o["length_ratio"] for o in objs],
        "tight": sum(bool(o["tight_shortest_route"]) for o in objs),
        "ring": [o["robots"]["ring_reachable_fraction"] for o in objs],
        "l05": [o["route_length_by_clearance"]["0.05"] for o in objs],
        "l08": [o["route_length_by_clearance"]["0.08"] for o in objs],
        "start_clearance": [min(o["start_clearance"], o["goal_clearance"]) for o in objs],
        # the shortest route passes somewhere with < 5 cm per side: keeping 5 cm makes it
        # longer by >= 0.3 m (or impossible)
        "narrow": sum(
            o["route_length_by_clearance"]["0.05"] is None
            or o["route_length_by_clearance"]["0.05"] >= o["free_route"]["length"] + 0.3
            for o in objs
        ),
    }


#: suites with a table of their own (not the route-search tables)
_OWN_TABLES = ("iros", "corridor", "fleet", "lifelong")


def corridor_lines(manifest: dict[str, Any]) -> list[str]:
    """The ``corridor`` suite's table: its routes are certified witnesses, not searches."""
    scenes = manifest["scenes"]
    lay = [sc["layout"] for sc in scenes]
    wit = [sc["objects"][0]["witness"] for sc in scenes]
    kinds = [la["object_kind"] for la in lay]
    turns = [la["turns"] for la in lay]
    return [
        "",
        f"## corridor ({len(scenes)} scenes: {kinds.count('bar')} bars, "
        f"{kinds.count('rectangle')} rectangles, {kinds.count('circle')} circles)",
        "",
        "One corridor per map; *clearance*: corridor width minus the object's extent across "
        "it (both sides together); the *witness* is the generator's certified route "
        "(exact clearance, sampled every "
        f"{manifest['checks']['witness_step']} m and "
        f"{manifest['checks']['witness_rotation_step']} rad).",
        "",
        "| map side (m) | turns (1 / 2 / 3 / 4) | leg length | clearance | corridor width "
        "| object across | object along | obstacles | witness length | witness rotation (rad) "
        "| witness min clearance | contact ring reachable by robots |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
        f"| {_mmm([v for la in lay for v in la['workspace']])} | "
        + " / ".join(str(turns.count(n)) for n in (1, 2, 3, 4))
        + f" | {_mmm([leg['length'] for la in lay for leg in la['legs']])}"
        f" | {_mmm([la['clearance'] for la in lay], '{:.3f}')}"
        f" | {_mmm([la['corridor_width'] for la in lay], '{:.3f}')}"
        f" | {_mmm([la['object_across'] for la in lay])}"
        f" | {_mmm([la['object_along'] for la in lay])}"
        f" | {_mmm([sc['n_obstacles'] for sc in scenes], '{:.0f}')}"
        f" | {_mmm([w['length'] for w in wit])} | {_mmm([w['rotation'] for w in wit])}"
        f" | {_mmm([w['min_clearance'] for w in wit], '{:.4f}')}"
        f" | {_mmm([sc['objects'][0]['robots']['ring_reachable_fraction'] for sc in scenes])} |",
    ]


def lifelong_lines(manifest: dict[str, Any]) -> list[str]:
    """The ``lifelong`` suite's table: the stream of each scene."""
    g = manifest["generator"]
    lines = [
        "",
        f"## lifelong ({len(manifest['scenes'])} scenes, tasks released while the robots "
        "work)",
        "",
        f"{g['tasks']} tasks per scene beyond the objects' own goals, released by a Poisson "
        f"process (mean gap {g['mean_gap_s']:g} s), each sending an object drawn uniformly "
        "back or forth between its start and its goal.",
        "",
        "| scene | base | objects | robots | tasks | last release (s) |",
        "|---|---|---|---|---|---|",
    ]
    lines += [f"| {sc['name']} | {sc['base']} | {sc['n_objects']} | {sc['n_robots']} | "
              f"{sc['n_tasks']} | {sc['last_release_s']:.0f} |" for sc in manifest["scenes"]]
    return lines


def fleet_lines(manifest: dict[str, Any]) -> list[str]:
    """The ``fleet`` suite's table: one row per kind of map."""
    scenes = manifest["scenes"]
    lines = [
        "",
        f"## fleet ({len(scenes)} scenes, concurrent schedule)",
        "",
        "Every object has a certified route keeping "
        f"{manifest['checks']['robot_room']} m of clearance with the other objects standing "
        "where the schedule may have left them; *waits*: objects with an `after` list "
        "(each checked to be blocked until its blockers are placed).",
        "",
        "| kind | scenes | map side (m) | objects | robots | robots per object "
        "| obstacles | route length | waits |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for kind in dict.fromkeys(sc["kind"] for sc in scenes):
        sel = [sc for sc in scenes if sc["kind"] == kind]
        routes = [o["robot_route"]["length"] for sc in sel for o in sc["objects"]]
        lines.append(
            f"| {kind} | {len(sel)} | "
            f"{_mmm([v for sc in sel for v in sc['layout']['workspace']], '{:.1f}')} | "
            f"{_mmm([sc['n_objects'] for sc in sel], '{:.0f}')} | "
            f"{_mmm([sc['n_robots'] for sc in sel], '{:.0f}')} | "
            f"{_mmm([sc['n_robots'] / sc['n_objects'] for sc in sel], '{:.1f}')} | "
            f"{_mmm([sc['n_obstacles'] for sc in sel], '{:.0f}')} | {_mmm(routes)} | "
            f"{sum(bool(o['after']) for sc in sel for o in sc['objects'])} |"
        )
    return lines


def stats_markdown(manifests: dict[str, dict[str, Any]] | None = None) -> str:
    """The text of ``data/STATS.md`` (from the committed manifests unless given)."""
    if manifests is None:
        manifests = {name: suite_manifest(name) for name in SUITES}
    chk = manifests["random"]["checks"]
    # the single-object families, in suite order (the IROS scene has its own table)
    families = {
        name: family_stats(manifests[name])
        for name in SUITES
        if name not in _OWN_TABLES and name in manifests
    }
    lines = [
        "# Benchmark suite statistics",
        "",
        "Generated by `scripts/generate_suites.py` from the manifests; do not edit.",
        "Triples are min / median / max. Lengths are paths of the object's centre (m).",
        "",
        "- *free route*: shortest route keeping clearance >= "
        f"{chk['free_clearance']} m from obstacles and border;",
        "- *robot-room route*: shortest route keeping clearance >= "
        f"{chk['robot_room']} m (a robot fits beside the object everywhere);",
        "- *too-tight shortest route*: the robot-room route is longer than the free route by >= "
        f"{chk['tight_min_extra']} m and by a factor >= "
        f"{chk['tight_min_ratio']} (the LAMP paper's Fig. 1 situation);",
        "- *min clearance*: exact minimum along the route, sampled every 5 mm of motion.",
    ]
    xl = manifests.get("warehouse-xl")
    if xl is not None:
        xc = xl["checks"]
        lines.append(
            f"- warehouse-xl's routes are searched on a {xc['lattice_resolution']} m lattice "
            f"with {xc['headings_per_period']} headings per period (the others: "
            f"{chk['lattice_resolution']} m, {chk['headings_per_period']}) and robot reach "
            f"on a {xc['reach_resolution']} m grid; its lengths are upper bounds. Its maps "
            "measure "
            + _mmm([v for sc in xl["scenes"] for v in sc["layout"]["workspace"]], "{:.1f}")
            + " m a side."
        )
    lines += [
        "",
        "| family | scenes | circles (radius) | rectangles (sides) | obstacles "
        "| free route length | free route min clearance | robot-room route length "
        "| robot-room min clearance | length ratio | too-tight shortest route |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, s in families.items():
        lines.append(
            f"| {name} | {s['scenes']} | {s['circles']} ({_mmm(s['circle_radius'])}) | "
            f"{s['rectangles']} ({_mmm(s['rect_sides'])}) | {_mmm(s['obstacles'], '{:.0f}')} | "
            f"{_mmm(s['free_length'])} | {_mmm(s['free_clearance'], '{:.3f}')} | "
            f"{_mmm(s['robot_length'])} | {_mmm(s['robot_clearance'], '{:.3f}')} | "
            f"{_mmm(s['ratio'])} | {s['tight']} / {s['scenes']} |"
        )
    lines += [
        "",
        "Route length when keeping larger clearances (medians, m), and reachability:",
        "",
        "| family | 0.02 m | 0.05 m | 0.08 m | 0.11 m | shortest route through a passage "
        "< 5 cm per side | object start/goal clearance | contact ring reachable by robots |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, s in families.items():
        med = [float(np.median(s[k])) for k in ("free_length", "l05", "l08", "robot_length")]
        lines.append(
            f"| {name} | "
            + " | ".join(f"{v:.2f}" for v in med)
            + f" | {s['narrow']} / {s['scenes']}"
            + f" | {_mmm(s['start_clearance'], '{:.3f}')} | {_mmm(s['ring'])} |"
        )
    if "corridor" in manifests:
        lines += corridor_lines(manifests["corridor"])
    if "fleet" in manifests:
        lines += fleet_lines(manifests["fleet"])
    if "lifelong" in manifests:
        lines += lifelong_lines(manifests["lifelong"])
    if "iros" in manifests:
        lines += _iros_lines(manifests["iros"]["scenes"][0])
    return "\n".join(lines) + "\n"


def _iros_lines(sc: dict[str, Any]) -> list[str]:
    """The IROS scene's own table: one row per object, in the order they are moved."""
    lines = [
        "",
        f"## iros ({sc['name']}: {len(sc['objects'])} objects, moved in this order)",
        "",
        "| # | piece | shape | free route length | approach route length (robot room) | "
        "approach min clearance | final push free |",
        "|---|---|---|---|---|---|---|",
    ]
    for o in sc["objects"]:
        shape = (
            f"circle r={o['radius']}"
            if o["type"] == "circle"
            else f"rectangle {o['size'][0]} x {o['size'][1]}"
        )
        app = o["approach_route"]
        lines.append(
            f"| {o['index']} | {o['piece']} | {shape} | {o['free_route']['length']:.2f} | "
            f"{app['length']:.2f} | {app['min_clearance']:.3f} | {o['final_push_ok']} |"
        )
    return lines
