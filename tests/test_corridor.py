"""Tests of the ``corridor`` built-in suite: the committed scene files and manifest against
the brief (geometry measured on the walls themselves), independent re-checks of the
witness routes (Shapely, ObjectSpace), the generator's determinism, and properties of the
layout helpers against simple references."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.shapes import local_outline, obstacle_geometry, to_shapely
from lamp.scene.model import Circle, Polygon, Rectangle
from lamp.suites import checks as C
from lamp.suites import corridor as CO
from lamp.suites import corridor_layout as CL
from lamp.suites.build import family_entry
from lamp.suites.registry import scene_yaml, suite_files, suite_info, suite_manifest, suite_scenes

DEG = math.pi / 180.0


@pytest.fixture(scope="module")
def scenes():
    return suite_scenes(CO.NAME)


@pytest.fixture(scope="module")
def manifest():
    return suite_manifest(CO.NAME)


@pytest.fixture(scope="module")
def walls(scenes):
    """Per scene: the union of its wall polygons (Shapely)."""
    return [shapely.union_all([obstacle_geometry(o) for o in sc.obstacles]) for sc in scenes]


def _diameter(shape) -> float:
    """Twice the largest distance of the footprint from the object's origin."""
    if isinstance(shape, Circle):
        return 2.0 * shape.radius
    return 2.0 * float(np.max(np.hypot(*local_outline(shape).T)))


def _extents(shape) -> tuple[float, float]:
    """(short, long) extent of the object."""
    if isinstance(shape, Circle):
        return 2.0 * shape.radius, 2.0 * shape.radius
    pts = local_outline(shape)
    a, b = np.ptp(pts[:, 0]), np.ptp(pts[:, 1])
    return float(min(a, b)), float(max(a, b))


# --------------------------------------------------------------------------- committed files
def test_suite_is_registered_beyond_the_paper():
    info = suite_info(CO.NAME)
    assert info.n_scenes == CO.N_SCENES == 25 and not info.paper


def test_committed_scenes_match_the_brief(scenes):
    assert [sc.name for sc in scenes] == [CO.scene_name(k) for k in range(25)]
    bars = 0
    for k, sc in enumerate(scenes):
        W, H = sc.workspace
        assert 6.0 <= W <= 14.0 and 6.0 <= H <= 14.0, sc.name
        assert len(sc.objects) == 1 and sc.n_robots == 3 and sc.robot_radius == 0.05
        shape = sc.objects[0].shape
        short, long = _extents(shape)
        kind = CO.object_kind(k)
        if kind == "bar":
            assert isinstance(shape, (Polygon, Rectangle))
            assert 1.0 <= long <= 1.5 and 0.15 <= short <= 0.30, sc.name
            bars += 1
        elif kind == "circle":
            assert isinstance(shape, Circle) and 0.10 <= shape.radius <= 0.25
        else:
            assert isinstance(shape, Rectangle) and all(0.15 <= v <= 0.50 for v in shape.size)
        # walls: simple polygons inside the workspace, a reasonable number of them
        assert 3 <= len(sc.obstacles) < 200
        box = shapely.box(0, 0, W, H).buffer(1e-6)
        for ob in sc.obstacles:
            assert isinstance(ob.shape, Polygon)
            g = obstacle_geometry(ob)
            assert g.is_valid and not g.interiors and box.contains(g)
    assert bars >= 6
    kinds = {type(sc.objects[0].shape) for sc in scenes}
    assert kinds == {Circle, Rectangle, Polygon}


def test_manifest_agrees_with_files(manifest, scenes):
    assert manifest["suite"] == CO.NAME
    assert manifest["checks"]["witness_step"] == CO.WITNESS_STEP
    files = {p.name: p for p in suite_files(CO.NAME)}
    assert [s["file"] for s in manifest["scenes"]] == sorted(files)
    for entry, sc in zip(manifest["scenes"], scenes, strict=True):
        assert entry["sha256"] == hashlib.sha256(files[entry["file"]].read_bytes()).hexdigest()
        assert entry["n_obstacles"] == len(sc.obstacles)
        assert entry["layout"]["workspace"] == list(sc.workspace)
        o = entry["objects"][0]
        obj = sc.objects[0]
        assert o["start"] == list(obj.start) and o["goal"] == list(obj.goal)
        w = o["witness"]
        poses = np.array(w["poses"])
        assert list(poses[0]) == list(obj.start)
        assert list(poses[-1, :2]) == list(obj.goal[:2])
        if not isinstance(obj.shape, Circle):  # the same footprint (half-turn symmetric)
            assert math.remainder(poses[-1, 2] - obj.goal[2], math.pi) == pytest.approx(0.0)
        assert w["min_clearance"] >= CO.WITNESS_MIN_CLEARANCE
        d = np.diff(poses, axis=0)
        assert w["length"] == pytest.approx(np.sum(np.hypot(d[:, 0], d[:, 1])), abs=1e-3)
        assert o["robots"]["all_reach"] and o["robots"]["ring_reachable_fraction"] >= 0.5


def test_corridor_geometry_matches_the_brief(manifest, scenes):
    """Legs off the axes and 22.5 degree bins, vertices off the 0.1 m grid, clearance,
    turns, leg lengths and bay sizes as recorded, and consistent with each other."""
    turn_counts = set()
    for entry, sc in zip(manifest["scenes"], scenes, strict=True):
        lay = entry["layout"]
        legs, bays = lay["legs"], lay["bays"]
        assert 1 <= lay["turns"] <= 4 and len(bays) == lay["turns"] == len(legs) - 1
        turn_counts.add(lay["turns"])
        assert 0.02 <= lay["clearance"] <= 0.06
        short, long = _extents(sc.objects[0].shape)
        assert lay["object_across"] == pytest.approx(short, abs=1e-9)
        assert lay["corridor_width"] == pytest.approx(short + lay["clearance"], abs=2e-4)
        assert lay["corridor_width"] >= C.ROBOT_ROOM
        for leg in legs:
            a, b = np.array(leg["from"]), np.array(leg["to"])
            ang = math.atan2(*(b - a)[::-1])
            assert math.remainder(ang - leg["angle"], 2 * math.pi) == pytest.approx(0, abs=1e-3)
            off = min(ang % (math.pi / 8), math.pi / 8 - ang % (math.pi / 8))
            assert off >= 3.0 * DEG - 1e-3, (sc.name, leg)
            for c in (*a, *b):
                assert min(c % 0.1, 0.1 - c % 0.1) >= 0.005 - 2e-4, (sc.name, c)
            assert 1.5 - 1e-3 <= leg["length"] <= 4.0 + 1e-3
        need = _diameter(sc.objects[0].shape) + 4 * sc.robot_radius + 0.15
        for k, bay in enumerate(bays):
            assert bay["center"] == legs[k]["to"] == legs[k + 1]["from"]
            assert 30 * DEG - 1e-3 <= abs(bay["turn"]) <= 120 * DEG + 1e-3
            turn = math.remainder(legs[k + 1]["angle"] - legs[k]["angle"], 2 * math.pi)
            assert turn == pytest.approx(bay["turn"], abs=1e-3)
            assert 2 * bay["radius"] >= need - 1e-3
            # vertex distance = narrow length + the pieces' radii at its ends
        for k, leg in enumerate(legs):
            r0 = bays[k - 1]["radius"] if k > 0 else 0.0
            r1 = bays[k]["radius"] if k < len(bays) else 0.0
            span = math.dist(leg["from"], leg["to"])
            assert span == pytest.approx(r0 + leg["length"] + r1, abs=1e-3)
    assert turn_counts == {1, 2, 3, 4}


def test_witness_keeps_the_short_side_across_and_rotates_at_every_turn(manifest, scenes):
    """Along each leg the witness holds the object with its short extent across the leg;
    at every bay it turns by the bay's turn (>= 30 degrees, modulo the half-turn
    symmetry), and start and goal are 25-90 degrees off their legs' headings."""
    for entry, sc in zip(manifest["scenes"], scenes, strict=True):
        shape = sc.objects[0].shape
        if isinstance(shape, Circle):
            continue
        lay = entry["layout"]
        poses = np.array(entry["objects"][0]["witness"]["poses"])
        n = lay["turns"]
        assert len(poses) == 6 + 2 * n
        on_leg = [poses[2], *(poses[4 + 2 * k] for k in range(n))]
        for leg, p in zip(lay["legs"], on_leg, strict=True):
            outline = to_shapely(shape, p).exterior.coords
            normal = CL.unit(leg["angle"] + 0.5 * math.pi)
            across = np.ptp(np.asarray(outline) @ normal)
            assert across == pytest.approx(lay["object_across"], abs=1e-3), sc.name
        for k, bay in enumerate(lay["bays"]):
            before, after = poses[3 + 2 * k], poses[4 + 2 * k]
            assert np.allclose(before[:2], after[:2]) and np.allclose(before[:2], bay["center"])
            turned = after[2] - before[2]
            assert math.remainder(turned - bay["turn"], math.pi) == pytest.approx(0, abs=1e-3)
            assert abs(turned) >= 30 * DEG - 1e-3
        for a, b in ((poses[0], poses[1]), (poses[-2], poses[-1])):
            assert 25 * DEG - 1e-3 <= abs(b[2] - a[2]) <= 90 * DEG + 1e-3, sc.name


def test_corridor_width_measured_on_the_walls(manifest, scenes, walls):
    """Across the middle of every leg, the walls stand at half the recorded width from
    the centreline on both sides (within the 1 mm snapping of the scene files)."""
    for entry, sc, wall in zip(manifest["scenes"], scenes, walls, strict=True):
        width = entry["layout"]["corridor_width"]
        for leg in entry["layout"]["legs"]:
            a, b = np.array(leg["from"]), np.array(leg["to"])
            u = (b - a) / np.linalg.norm(b - a)
            n = np.array([-u[1], u[0]])
            for t in (0.4, 0.5, 0.6):
                m = a + t * (b - a)
                for side in (n, -n):
                    ray = shapely.LineString([m, m + side])
                    hit = ray.intersection(wall)
                    d = shapely.Point(m).distance(hit)
                    assert d == pytest.approx(0.5 * width, abs=1.5e-3), (sc.name, leg)


def test_robots_start_behind_the_object(manifest, scenes):
    for entry, sc in zip(manifest["scenes"], scenes, strict=True):
        lay = entry["layout"]
        leg0 = lay["legs"][0]
        u = CL.unit(leg0["angle"])
        n = CL.unit(leg0["angle"] + 0.5 * math.pi)
        obj = sc.objects[0]
        reach = 0.5 * _diameter(obj.shape)
        (u0, u1), (v0, v1) = lay["rooms"]["start"]["u"], lay["rooms"]["start"]["v"]
        for p in sc.robot_starts_array:
            assert (p - np.array(obj.start[:2])) @ u <= -0.5 * reach, sc.name
            du, dv = (p - np.array(leg0["from"])) @ u, (p - np.array(leg0["from"])) @ n
            assert u0 + 0.05 <= du <= u1 - 0.05 and v0 + 0.05 <= dv <= v1 - 0.05


def _samples(poses: np.ndarray, step: float, rot: float) -> np.ndarray:
    out = [poses[0]]
    for a, b in zip(poses[:-1], poses[1:], strict=True):
        n = int(max(1, np.ceil(np.hypot(*(b[:2] - a[:2])) / step), np.ceil(abs(b[2] - a[2]) / rot)))
        out.extend(a + (b - a) * (i / n) for i in range(1, n + 1))
    return np.array(out)


@pytest.mark.parametrize("index", [0, 22])
def test_witness_recertified_with_shapely(manifest, scenes, walls, index):
    """Every 1 cm / 0.01 rad of the committed witness, the object's polygon stays inside
    the workspace, off the walls by >= WITNESS_MIN_CLEARANCE, and the route really passes
    the tight corridor (its least clearance is about half the corridor's clearance)."""
    sc, wall = scenes[index], walls[index]
    o = manifest["scenes"][index]["objects"][0]
    poses = np.array(o["witness"]["poses"])
    W, H = sc.workspace
    inside = shapely.box(0, 0, W, H)
    shapely.prepare(wall)
    least = np.inf
    for p in _samples(poses, 0.01, 0.01):
        body = to_shapely(sc.objects[0].shape, p)
        assert inside.contains(body) and not wall.intersects(body)
        least = min(least, body.distance(wall))
    assert least >= CO.WITNESS_MIN_CLEARANCE - 1e-4
    half = 0.5 * manifest["scenes"][index]["layout"]["clearance"]
    assert least == pytest.approx(half, abs=2e-3)
    assert least == pytest.approx(o["witness"]["min_clearance"], abs=1e-3)


def test_witness_recertified_with_object_space(manifest, scenes):
    """ObjectSpace (a conservative grid checker, error band 13 mm) confirms the witness of
    a scene whose witness keeps more than its band plus motion margin."""
    index = 11
    o = manifest["scenes"][index]["objects"][0]
    space = ObjectSpace.from_scene(scenes[index], 0, inflation=0.0)
    assert o["witness"]["min_clearance"] > space.band + space.motion_margin
    dense = CO.sample_witness(np.array(o["witness"]["poses"]))
    assert space.pose_free(dense).all()
    assert space.motions_free(dense[:-1], dense[1:]).all()


def test_certification_rejects_a_witness_through_a_wall(scenes, manifest):
    index = 5
    sc = scenes[index]
    o = manifest["scenes"][index]["objects"][0]
    poses = np.array(o["witness"]["poses"])
    leg = manifest["scenes"][index]["layout"]["legs"][0]
    assert CO.certify_witness(sc, poses) is not None
    moved = poses.copy()
    clearance = manifest["scenes"][index]["layout"]["clearance"]
    moved[2:-2, :2] += CL.unit(leg["angle"] + 0.5 * math.pi) * (0.5 * clearance + 0.002)
    assert CO.certify_witness(sc, moved) is None


@pytest.mark.parametrize("index", [3, 20])
def test_generator_is_deterministic_and_reproduces_committed_scene(index):
    a = CO.generate_scene(index)
    b = CO.generate_scene(index)
    assert a.scene_dict == b.scene_dict and a.layout_info == b.layout_info
    assert a.report.to_dict() == b.report.to_dict()
    text = scene_yaml(a.scene_dict)
    assert text == suite_files(CO.NAME)[index].read_text(encoding="utf-8")
    assert family_entry(a, text) == suite_manifest(CO.NAME)["scenes"][index]


def test_generator_rejects_bad_index():
    for bad in (-1, 25, 1.0):
        with pytest.raises(ValueError, match="index"):
            CO.generate_scene(bad)


def test_environments_resolve_corridor_scene_names():
    from lamp.env.core import resolve_scene

    assert resolve_scene("corridor-07").name == "corridor-07"


# --------------------------------------------------------------------------- properties
@settings(max_examples=60, deadline=None)
@given(a=st.floats(-20.0, 20.0), w=st.sampled_from([math.pi / 8, 0.1, 1.0]))
def test_offsets_match_brute_force(a, w):
    near = min(abs(a - w * k) for k in range(math.floor(a / w) - 1, math.ceil(a / w) + 2))
    assert CL.angle_bin_offset(a, w) == pytest.approx(near, abs=1e-9)
    assert CL.grid_offset(a, w) == pytest.approx(near, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(width=st.floats(0.12, 0.6), turn=st.floats(30 * DEG, 120 * DEG),
       sign=st.sampled_from([-1.0, 1.0]), rot=st.floats(0.2, 1.0), phase=st.floats(-3.0, 3.0))
def test_bay_radius_leaves_the_wall_between_legs(width, turn, sign, rot, phase):
    """The narrow parts of the two legs at a bay keep >= WALL_NEAR between them (Shapely
    reference), and the bay contains the rotation disk."""
    r = CL.bay_radius(rot, width, sign * turn, CO.WALL_NEAR)
    assert r >= rot
    c = np.array([0.0, 0.0])
    a0, a1 = phase, phase + sign * turn
    b = CL.bay(c, r, a0)
    assert b.contains(shapely.Point(0, 0).buffer(rot * 0.999, quad_segs=32))
    leg0 = CL.strip(c - 3.0 * CL.unit(a0), c, width).difference(b)
    leg1 = CL.strip(c, c + 3.0 * CL.unit(a1), width).difference(b)
    assert leg0.distance(leg1) >= CO.WALL_NEAR - 1e-3


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_wall_polygons_fill_the_complement(seed):
    """Walls are simple polygons inside the workspace, off the free region, and together
    with it they cover the workspace (up to the millimetre snapping)."""
    rng = np.random.default_rng(seed)
    W, H = (float(v) for v in np.round(rng.uniform(3.0, 7.0, size=2), 2))
    pts = rng.uniform([0.8, 0.8], [W - 0.8, H - 0.8], size=(3, 2))
    free = shapely.union_all([CL.strip(pts[0], pts[1], 0.2), CL.strip(pts[1], pts[2], 0.2),
                              shapely.Point(*pts[1]).buffer(0.4)])
    polys = [shapely.Polygon(p) for p in CL.wall_polygons((W, H), free)]
    assert all(p.is_valid and not p.interiors for p in polys)
    box = shapely.box(0, 0, W, H)
    union = shapely.union_all(polys)
    assert box.buffer(1e-9).contains(union)
    assert union.intersection(free).area <= 1e-9
    assert box.difference(union).difference(free).area <= 2e-3 * free.length
    for p in polys:  # on the scene files' millimetre grid
        xy = np.asarray(p.exterior.coords)
        assert np.allclose(xy, np.round(xy, 3), atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(poses=st.lists(st.tuples(st.floats(0, 5), st.floats(0, 5), st.floats(-4, 4)),
                      min_size=2, max_size=5))
def test_witness_samples_are_dense(poses):
    arr = np.array(poses)
    d = CO.sample_witness(arr)
    step = np.diff(d, axis=0)
    assert np.all(np.hypot(step[:, 0], step[:, 1]) <= CO.WITNESS_STEP + 1e-9)
    assert np.all(np.abs(step[:, 2]) <= CO.WITNESS_ROT_STEP + 1e-9)
    for p in arr:  # every given pose is a sample
        assert np.min(np.abs(d - p).sum(axis=1)) <= 1e-9


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), direction=st.floats(-math.pi, math.pi),
       half=st.floats(0.1, 1.2))
def test_place_robots_keeps_to_its_sector(seed, direction, half):
    from lamp.suites.generators import place_robots

    world = C.build_world((4.0, 4.0), [])
    shape = Rectangle((0.4, 0.2))
    start = np.array([2.0, 2.0, 0.3])
    robots = place_robots(np.random.default_rng(seed), world, shape, start, 0.224,
                          sector=(direction, half))
    assert robots is not None and len(robots) == 3
    for p in robots:
        seen = math.atan2(p[1] - start[1], p[0] - start[0])
        # positions are rounded to the millimetre, >= 0.39 m from the centre
        assert abs(math.remainder(seen - direction, 2 * math.pi)) <= half + 0.003


def test_records_are_validated():
    with pytest.raises(ValueError, match="kind"):
        CO.CorridorObject({"type": "circle", "radius": 0.1}, "disk", 0.2, 0.2, 0.1, 0.0, 0.0)
    with pytest.raises(ValueError, match="across"):
        CO.CorridorObject({"type": "rectangle", "size": [0.2, 0.4]}, "rectangle", 0.4, 0.2,
                          0.224, 0.0, math.pi)
    with pytest.raises(ValueError, match="min_clearance"):
        CO.Witness(np.zeros((2, 3)), 0.005, 0.0, 0.0, 0.001, 2)
    with pytest.raises(ValueError, match="radii"):
        CL.Chain(np.zeros((3, 2)), (0.1, 0.2), (1.0, 1.0), ())


def test_stats_table_of_the_committed_suite(manifest):
    """STATS.md is what the committed manifests give, and its corridor table counts the
    object kinds and turns of the manifest."""
    from lamp.suites.registry import DATA_DIR
    from lamp.suites.stats import stats_markdown

    text = stats_markdown()
    assert text == (DATA_DIR / "STATS.md").read_text(encoding="utf-8")
    kinds = [sc["layout"]["object_kind"] for sc in manifest["scenes"]]
    turns = [sc["layout"]["turns"] for sc in manifest["scenes"]]
    assert (f"## corridor (25 scenes: {kinds.count('bar')} bars, "
            f"{kinds.count('rectangle')} rectangles, {kinds.count('circle')} circles)") in text
    section = text.split("## corridor")[1].split("\n## ")[0]
    header, _, row = [ln for ln in section.splitlines() if ln.startswith("|")]
    assert "turns (1 / 2 / 3 / 4)" in header
    assert " / ".join(str(turns.count(n)) for n in (1, 2, 3, 4)) in row
