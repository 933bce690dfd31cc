"""Tests of the ``warehouse-xl`` built-in suite: the committed scene files and manifest, the
generator's determinism and brief, and that the benchmark does not impose the paper's
segment limit on it."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
import shapely

from lamp.bench.jobs import enumerate_jobs, load_suite
from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.planners.config import PAPER_MAX_SEGMENTS
from lamp.scene.model import Circle
from lamp.suites import checks as C
from lamp.suites import warehouse_xl as XL
from lamp.suites.build import family_entry
from lamp.suites.registry import (
    SUITES,
    scene_yaml,
    suite_files,
    suite_info,
    suite_manifest,
    suite_scenes,
)


@pytest.fixture(scope="module")
def scenes():
    return suite_scenes(XL.NAME)


@pytest.fixture(scope="module")
def manifest():
    return suite_manifest(XL.NAME)


def test_suite_is_registered_beyond_the_paper():
    assert suite_info(XL.NAME).n_scenes == XL.N_SCENES == 25
    assert not suite_info(XL.NAME).paper
    assert [n for n, s in SUITES.items() if s.paper] == [
        "random", "maze", "tilt", "warehouse", "iros"
    ]


def test_committed_scenes_match_the_brief(scenes):
    assert len(scenes) == 25
    assert [sc.name for sc in scenes] == [XL.scene_name(k) for k in range(25)]
    for k, sc in enumerate(scenes):
        W, H = sc.workspace
        assert 20.0 <= W <= 50.0 and 20.0 <= H <= 50.0, sc.name
        assert len(sc.objects) == 1 and len(sc.robot_starts_array) == 3
        assert sc.robot_radius == 0.05
        obj = sc.objects[0]
        if k % 2:
            assert isinstance(obj.shape, Circle) and 0.10 <= obj.shape.radius <= 0.30
        else:
            assert all(0.15 <= v <= 0.50 for v in obj.shape.size)
        assert math.dist(obj.start[:2], obj.goal[:2]) >= XL.MIN_SPAN
        # robots start near the object and clear of every obstacle (Shapely reference)
        body = to_shapely(obj.shape, obj.start)
        geoms = [obstacle_geometry(o) for o in sc.obstacles]
        for p in sc.robot_starts_array:
            pt = shapely.Point(*p)
            assert body.distance(pt) <= 1.0
            assert min(g.distance(pt) for g in geoms) >= sc.robot_radius + 0.03 - 1e-9


def test_manifest_agrees_with_files(manifest, scenes):
    assert manifest["suite"] == XL.NAME
    assert manifest["checks"]["lattice_resolution"] == XL.RESOLUTION
    files = {p.name: p for p in suite_files(XL.NAME)}
    assert [s["file"] for s in manifest["scenes"]] == sorted(files)
    for entry, sc in zip(manifest["scenes"], scenes, strict=True):
        assert entry["sha256"] == hashlib.sha256(files[entry["file"]].read_bytes()).hexdigest()
        o = entry["objects"][0]
        assert o["start"] == list(sc.objects[0].start)
        assert XL.ROUTE_RANGE[0] <= o["free_route"]["length"] <= XL.ROUTE_RANGE[1]
        assert o["free_route"]["min_clearance"] >= C.FREE_CLEARANCE - 1e-4
        assert o["robot_route"]["min_clearance"] >= C.ROBOT_ROOM - 1e-4
        assert o["robots"]["all_reach"] and o["robots"]["ring_reachable_fraction"] >= 0.5


@pytest.mark.parametrize("index", [3, 18])
def test_committed_free_route_is_free(scenes, manifest, index):
    """The manifest's free route, re-checked by Shapely on poses sampled every 5 cm and
    5 cm-rad, and (on the smallest map, 20.5 m x 25.7 m) by the independent ObjectSpace
    checker."""
    sc = scenes[index]
    poses = np.array(manifest["scenes"][index]["objects"][0]["free_route"]["poses"])
    if index == 3:
        ok, _ = C.verify_route(sc, 0, poses, C.FREE_CLEARANCE)
        assert ok
    union = shapely.union_all([obstacle_geometry(o) for o in sc.obstacles])
    W, H = sc.workspace
    hall = shapely.box(0, 0, W, H)
    for a, b in zip(poses[:-1], poses[1:], strict=True):
        n = max(1, math.ceil(math.dist(a[:2], b[:2]) / 0.05 + abs(b[2] - a[2]) / 0.05))
        for t in np.linspace(0.0, 1.0, n + 1):
            body = to_shapely(sc.objects[0].shape, a + t * (b - a))
            assert body.distance(union) >= C.FREE_CLEARANCE - 1e-4
            assert hall.contains(body)


@pytest.mark.parametrize("index", [3, 18])
def test_generator_reproduces_committed_scene(index):
    gen = XL.generate_scene(index, full_checks=False)
    text = scene_yaml(gen.scene_dict)
    assert text == suite_files(XL.NAME)[index].read_text(encoding="utf-8")
    entry = family_entry(gen, text)
    assert entry["sha256"] == suite_manifest(XL.NAME)["scenes"][index]["sha256"]


def test_aisles_leave_room_for_object_and_two_robots():
    """Every aisle and cross-aisle is at least the object's width plus two robot diameters
    wide, and a disk of that diameter fits at every aisle crossing (pallets stand in the
    bays between crossings, cargo only in the dock band)."""
    rng = np.random.default_rng(7)
    for k in range(4):
        obj = XL.sample_object(rng, k)
        lay = XL.layout_xl(rng, obj)
        need = obj.width + XL.AISLE_MIN_EXTRA
        assert len(lay.aisle_widths) == lay.info["shelf_rows"] + lay.info["cross_aisles"]
        assert min(lay.aisle_widths) >= need
        world = C.build_world(lay.workspace, XL.obstacles_of(lay.obstacles))
        aisle_sites = lay.sites[lay.info["cross_aisles"]:, :2]
        assert np.all(C.point_clearance(world, aisle_sites) >= 0.5 * need - 2e-3)


def test_generator_rejects_bad_index():
    for bad in (-1, 25, 1.0):
        with pytest.raises(ValueError, match="index"):
            XL.generate_scene(bad)


def test_bench_uses_the_scaled_segment_limit_on_warehouse_xl():
    jobs = enumerate_jobs([load_suite(XL.NAME), load_suite("maze")], ["lazy"], [0],
                          scenes_per_suite=1)
    assert [(j.suite, j.max_segments) for j in jobs] == [
        (XL.NAME, None), ("maze", PAPER_MAX_SEGMENTS)
    ]


def test_environments_resolve_warehouse_xl_scene_names():
    from lamp.env.core import resolve_scene

    assert resolve_scene("warehouse-xl-07").name == "warehouse-xl-07"
    assert resolve_scene("maze-07").name == "maze-07"
