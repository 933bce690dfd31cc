"""Build the suites' scene files and manifests (driven by ``scripts/generate_suites.py``).

``build_suite(name)`` returns the exact bytes of every file of ``data/<name>/``: the
scene files (``registry.scene_yaml``) and ``manifest.json`` (sorted keys, 1-space
indent, trailing newline). Everything is a pure function of the code, so running the
script again reproduces the committed files byte for byte.
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Callable
from typing import Any

from lamp.suites import checks as C
from lamp.suites import corridor as CO
from lamp.suites import fleet as FLEET
from lamp.suites import generators as G
from lamp.suites import iros
from lamp.suites import lifelong as LIFE
from lamp.suites import warehouse_xl as XL
from lamp.suites.registry import SUITES, scene_yaml

log = logging.getLogger(__name__)

MANIFEST_FORMAT = "lamp-suite-manifest/1"


def _object_summary(d: dict[str, Any]) -> dict[str, Any]:
    keys = ("type", "size", "radius", "points", "start", "goal")
    return {k: d[k] for k in keys if k in d}


def _check_settings() -> dict[str, Any]:
    return {
        "free_clearance": C.FREE_CLEARANCE,
        "robot_room": C.ROBOT_ROOM,
        "clearance_ladder": list(C.CLEARANCE_LADDER),
        "lattice_resolution": C.RESOLUTION,
        "headings_per_period": C.N_HEADINGS,
        "tight_min_extra": C.TIGHT_MIN_EXTRA,
        "tight_min_ratio": C.TIGHT_MIN_RATIO,
        "end_clearance": G.END_CLEARANCE,
        "tight_slack": list(G.TIGHT_SLACK),
    }


def manifest_json(manifest: dict[str, Any]) -> str:
    return json.dumps(manifest, indent=1, sort_keys=True) + "\n"


def _xl_check_settings() -> dict[str, Any]:
    return {
        **_check_settings(),
        "lattice_resolution": XL.RESOLUTION,
        "headings_per_period": XL.N_HEADINGS,
        "reach_resolution": XL.REACH_RESOLUTION,
        "route_length_range": list(XL.ROUTE_RANGE),
        "min_start_goal_distance": XL.MIN_SPAN,
        "aisle_min_extra": XL.AISLE_MIN_EXTRA,
    }


def _corridor_check_settings() -> dict[str, Any]:
    return {
        "witness_step": CO.WITNESS_STEP,
        "witness_rotation_step": CO.WITNESS_ROT_STEP,
        "witness_min_clearance": CO.WITNESS_MIN_CLEARANCE,
        "clearance_range": list(CO.CLEARANCE_RANGE),
        "leg_length_range": list(CO.LEG_RANGE),
        "turns_range": list(CO.TURNS_RANGE),
        "turn_angle_range": [round(v, 6) for v in CO.TURN_RANGE],
        "min_heading_bin_offset": round(CO.MIN_BIN_OFFSET, 6),
        "heading_bin": round(CO.HEADING_BIN, 6),
        "min_grid_offset": CO.MIN_GRID_OFFSET,
        "grid": CO.GRID,
        "bay_margin": CO.BAY_MARGIN,
        "robot_room": C.ROBOT_ROOM,
        "reach_resolution": CO.REACH_RESOLUTION,
        "reach_ring_width": CO.REACH_RING_WIDTH,
    }


def family_entry(
    gen: G.Generated | XL.GeneratedXL | CO.GeneratedCorridor, text: str
) -> dict[str, Any]:
    """Manifest entry of one generated family scene."""
    obj = {**_object_summary(gen.scene_dict["objects"][0]), **gen.report.to_dict()}
    return {
        "name": gen.scene_dict["name"],
        "file": f"{gen.scene_dict['name']}.yaml",
        "sha256": hashlib.sha256(text.encode()).hexdigest(),
        "n_obstacles": len(gen.scene_dict["obstacles"]),
        **({"aimed_tight": gen.want_tight} if isinstance(gen, G.Generated) else {}),
        "attempts": gen.attempts,
        "layout": gen.layout_info,
        "objects": [obj],
    }


#: What one suite's builder returns: (files, manifest entries, generator record, checks).
_Built = tuple[dict[str, str], list[dict[str, Any]], dict[str, Any], dict[str, Any]]


def _build_xl(progress: Callable[[str], None] | None) -> _Built:
    """The ``warehouse-xl`` suite's scene files, entries, generator record and checks."""
    files: dict[str, str] = {}
    entries = []
    for k in range(XL.N_SCENES):
        xg = XL.generate_scene(k)
        text = scene_yaml(xg.scene_dict)
        files[f"{xg.scene_dict['name']}.yaml"] = text
        entries.append(family_entry(xg, text))
        if progress is not None:
            rep = xg.report.to_dict()
            progress(
                f"{xg.scene_dict['name']}: {xg.layout_info['workspace']} m, attempts "
                f"{xg.attempts}, free route {rep['free_route']['length']:.2f} m, "
                f"robot-room route {rep['robot_route']['length']:.2f} m"
            )
    generator = {
        "module": "lamp.suites.warehouse_xl",
        "seed": G.SUITE_SEED,
        "rng": f"numpy.random.default_rng([{G.SUITE_SEED}, {XL.STREAM}, index])",
    }
    return files, entries, generator, _xl_check_settings()


def _build_corridor(progress: Callable[[str], None] | None) -> _Built:
    """The corridor suite's scene files, entries, generator record and checks."""
    files: dict[str, str] = {}
    entries = []
    for k in range(CO.N_SCENES):
        cg = CO.generate_scene(k)
        text = scene_yaml(cg.scene_dict)
        files[f"{cg.scene_dict['name']}.yaml"] = text
        entries.append(family_entry(cg, text))
        if progress is not None:
            w = cg.report.witness
            progress(
                f"{cg.scene_dict['name']}: {cg.layout_info['workspace']} m, "
                f"{cg.layout_info['turns']} turn(s), attempts {cg.attempts}, witness "
                f"{w.length:.2f} m, min clearance {w.min_clearance:.4f} m"
            )
    generator = {
        "module": "lamp.suites.corridor",
        "seed": G.SUITE_SEED,
        "rng": f"numpy.random.default_rng([{G.SUITE_SEED}, {CO.STREAM}, index])",
    }
    return files, entries, generator, _corridor_check_settings()


def _build_fleet(progress: Callable[[str], None] | None) -> _Built:
    """The fleet suite's scene files, entries, generator record and checks."""
    files: dict[str, str] = {}
    entries = []
    for k in range(FLEET.N_SCENES):
        fg = FLEET.generate_scene(k)
        text = scene_yaml(fg.scene_dict)
        files[f"{fg.scene_dict['name']}.yaml"] = text
        entries.append(FLEET.manifest_entry(fg, text))
        if progress is not None:
            progress(
                f"{fg.scene_dict['name']}: {fg.kind}, {fg.layout_info['workspace']} m, "
                f"{len(fg.reports)} objects, {fg.scene.n_robots} robots, attempts "
                f"{fg.attempts}"
            )
    generator = {
        "module": "lamp.suites.fleet",
        "seed": G.SUITE_SEED,
        "rng": f"numpy.random.default_rng([{G.SUITE_SEED}, {FLEET.STREAM}, index])",
    }
    return files, entries, generator, FLEET.check_settings()


def _build_iros() -> _Built:
    """The ``iros`` suite (one scene); RuntimeError when the scene fails its checks."""
    d, scene, steps = iros.build()
    bad = [s.piece for s in steps if not s.ok]
    if bad or not iros.goal_footprints_disjoint(scene):
        raise RuntimeError(f"iros-01 fails its checks: {bad or 'goal footprints overlap'}")
    text = scene_yaml(d)
    entry = {
        "name": "iros-01",
        "file": "iros-01.yaml",
        "sha256": hashlib.sha256(text.encode()).hexdigest(),
        "n_obstacles": len(d["obstacles"]),
        "approach_distance": iros.APPROACH,
        "objects": [
            {**_object_summary(o), **s.to_dict()}
            for o, s in zip(d["objects"], steps, strict=True)
        ],
    }
    return {"iros-01.yaml": text}, [entry], {"module": "lamp.suites.iros"}, _check_settings()


def _build_family(name: str, progress: Callable[[str], None] | None) -> _Built:
    """A generated map family's (``lamp.suites.generators``) files, entries, generator
    record and checks."""
    files: dict[str, str] = {}
    entries = []
    for k in range(G.SCENES_PER_FAMILY):
        gen = G.generate_scene(name, k)
        text = scene_yaml(gen.scene_dict)
        files[f"{gen.scene_dict['name']}.yaml"] = text
        entries.append(family_entry(gen, text))
        if progress is not None:
            rep = gen.report.to_dict()
            progress(
                f"{gen.scene_dict['name']}: attempts {gen.attempts}, too-tight shortest "
                f"route {rep['tight_shortest_route']}, free route "
                f"{rep['free_route']['length']:.2f} m, robot-room route "
                f"{rep['robot_route']['length']:.2f} m"
            )
    generator = {
        "module": "lamp.suites.generators",
        "seed": G.SUITE_SEED,
        "rng": f"numpy.random.default_rng([{G.SUITE_SEED}, {G.FAMILIES.index(name)}, index])",
        "tight_share": G.TIGHT_SHARE,
    }
    return files, entries, generator, _check_settings()


def _build_lifelong(progress: Callable[[str], None] | None) -> _Built:
    """The lifelong suite's scene files, entries, generator record and checks (the
    fleet scenes' own: its maps are theirs)."""
    files: dict[str, str] = {}
    entries = []
    for k in range(LIFE.N_SCENES):
        d = LIFE.generate_scene(k)
        text = scene_yaml(d)
        files[f"{d['name']}.yaml"] = text
        entries.append({"name": d["name"], "file": f"{d['name']}.yaml",
                        "sha256": hashlib.sha256(text.encode()).hexdigest(),
                        "base": LIFE.BASES[k], "n_objects": len(d["objects"]),
                        "n_robots": len(d["robots"]["starts"]), "n_tasks": len(d["tasks"]),
                        "last_release_s": d["tasks"][-1]["release_s"]})
        if progress is not None:
            progress(f"{d['name']}: {LIFE.BASES[k]}, {len(d['tasks'])} tasks until "
                     f"{d['tasks'][-1]['release_s']:.0f} s")
    generator = {
        "module": "lamp.suites.lifelong",
        "seed": G.SUITE_SEED,
        "rng": f"numpy.random.default_rng([{G.SUITE_SEED}, {LIFE.STREAM}, index])",
        "tasks": LIFE.N_TASKS, "mean_gap_s": LIFE.MEAN_GAP_S,
    }
    return files, entries, generator, FLEET.check_settings()


def build_suite(name: str, progress: Callable[[str], None] | None = None) -> dict[str, str]:
    """File name -> file text for every file of suite ``name``."""
    if name not in SUITES:
        raise ValueError(f"unknown suite {name!r}; valid names: {', '.join(SUITES)}")
    if name == XL.NAME:
        files, entries, generator, checks = _build_xl(progress)
    elif name == CO.NAME:
        files, entries, generator, checks = _build_corridor(progress)
    elif name == FLEET.NAME:
        files, entries, generator, checks = _build_fleet(progress)
    elif name == "iros":
        files, entries, generator, checks = _build_iros()
    elif name == LIFE.NAME:
        files, entries, generator, checks = _build_lifelong(progress)
    else:
        files, entries, generator, checks = _build_family(name, progress)
    manifest = {
        "format": MANIFEST_FORMAT,
        "suite": name,
        "description": SUITES[name].description,
        "generator": {"script": "scripts/generate_suites.py", **generator},
        "checks": checks,
        "scenes": entries,
    }
    files["manifest.json"] = manifest_json(manifest)
    return files
