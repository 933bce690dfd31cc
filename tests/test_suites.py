"""Tests of the built-in benchmark suites (``lamp.suites``): the committed scene files and
manifests, the route/reachability checks (against Shapely and ObjectSpace as independent
oracles), the generator's determinism and the ``lamp suite`` commands."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
import shapely
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import lamp
from lamp.cli.suite import suite_app
from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.scene import scene_from_dict
from lamp.scene.model import Circle, Obstacle, Rectangle
from lamp.suites import checks as C
from lamp.suites import generators as G
from lamp.suites import iros
from lamp.suites.registry import (
    export_suite,
    list_suites,
    scene_yaml,
    suite_dir,
    suite_files,
    suite_manifest,
    suite_scenes,
)

FAMILIES = ("random", "maze", "tilt", "warehouse")


# --------------------------------------------------------------------------- helpers
def _exact_clearance(scene, k: int, pose, object_poses=None) -> float:
    """Shapely reference: distance of object k at pose to obstacles, other objects, border
    (circles handled analytically, so the reference is exact)."""
    obj = scene.objects[k]
    poses = scene.object_starts() if object_poses is None else np.asarray(object_poses)
    obstacles = list(scene.obstacles) + [
        Obstacle(o.shape, tuple(p))
        for i, (o, p) in enumerate(zip(scene.objects, poses, strict=True))
        if i != k
    ]
    return _ref_clearance(obj.shape, pose, obstacles, scene.workspace)


def _ref_clearance(shape, pose, obstacles, workspace) -> float:
    """Distance from the shape at pose to the obstacles and the border (Shapely; disks as
    points plus radius, so exact); -1 for an overlap."""
    W, H = workspace
    x, y, _ = (float(v) for v in pose)
    if isinstance(shape, Circle):
        me, pad = shapely.Point(x, y), shape.radius
        best = min(x, W - x, y, H - y) - pad
    else:
        me, pad = to_shapely(shape, pose), 0.0
        xs, ys = np.asarray(me.exterior.coords).T
        best = float(min(xs.min(), W - xs.max(), ys.min(), H - ys.max()))
    for ob in obstacles:
        if isinstance(ob.shape, Circle):
            d = me.distance(shapely.Point(ob.pose[0], ob.pose[1])) - ob.shape.radius - pad
        else:
            g = obstacle_geometry(ob)
            d = -1.0 if g.intersects(me) else g.distance(me) - pad
        best = min(best, d)
    return best


def _densify(poses: np.ndarray, step: float) -> np.ndarray:
    out = [poses[:1]]
    for a, b in zip(poses[:-1], poses[1:], strict=True):
        n = max(1, math.ceil((math.hypot(*(b[:2] - a[:2])) + 0.4 * abs(b[2] - a[2])) / step))
        out.append(a + (np.arange(1, n + 1) / n)[:, None] * (b - a))
    return np.concatenate(out)


# --------------------------------------------------------------------------- committed files
def test_suite_names_and_counts():
    assert list_suites() == [
        "random", "maze", "tilt", "warehouse", "iros", "warehouse-xl", "corridor", "fleet",
        "lifelong",
    ]
    for fam in FAMILIES:
        names = [p.name for p in suite_files(fam)]
        assert names == [f"{fam}-{k:02d}.yaml" for k in range(1, 26)]
    assert [p.name for p in suite_files("iros")] == ["iros-01.yaml"]


@pytest.mark.parametrize("family", FAMILIES)
def test_family_scenes_load_and_match_the_brief(family):
    scenes = suite_scenes(family)  # lamp.load_scene: full validation
    assert len(scenes) == 25
    types = set()
    for sc in scenes:
        assert sc.n_robots == 3 and sc.robot_radius == 0.05
        assert 3.0 <= sc.workspace[0] <= 6.0 and 3.0 <= sc.workspace[1] <= 6.0
        assert len(sc.objects) == 1
        shape = sc.objects[0].shape
        types.add(type(shape))
        if isinstance(shape, Circle):
            assert 0.10 <= shape.radius <= 0.30
        else:
            assert isinstance(shape, Rectangle)
            assert all(0.15 <= v <= 0.50 for v in shape.size)
        assert len(sc.obstacles) >= 3
    assert types == {Circle, Rectangle}


def test_iros_scene():
    (sc,) = suite_scenes("iros")
    assert len(sc.objects) == 9 and sc.n_robots == 3
    assert max(sc.workspace) <= 6.0
    assert {type(o.shape) for o in sc.objects} == {Circle, Rectangle}
    goals = [to_shapely(o.shape, o.goal) for o in sc.objects]
    for i in range(9):
        for j in range(i + 1, 9):
            assert goals[i].distance(goals[j]) >= 0.03 - 1e-9, (i, j)


@pytest.mark.parametrize("name", ["random", "maze", "tilt", "warehouse", "iros"])
def test_manifest_agrees_with_files(name):
    man = suite_manifest(name)
    assert man["suite"] == name
    files = {p.name: p for p in suite_files(name)}
    assert [s["file"] for s in man["scenes"]] == sorted(files)
    for entry, sc in zip(man["scenes"], suite_scenes(name), strict=True):
        path = files[entry["file"]]
        assert entry["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
        assert entry["name"] == sc.name and entry["n_obstacles"] == len(sc.obstacles)
        assert len(entry["objects"]) == len(sc.objects)
        for k, (o, obj) in enumerate(zip(entry["objects"], sc.objects, strict=True)):
            assert o["start"] == list(obj.start) and o["goal"] == list(obj.goal)
            assert o["type"] == obj.shape.to_dict()["type"]
            free = np.array(o["free_route"]["poses"])
            assert np.allclose(free[0], obj.start, atol=1e-4)
            # the route ends at the goal footprint (theta modulo the shape's symmetry)
            assert np.allclose(free[-1, :2], obj.goal[:2], atol=1e-4)
            period = C.footprint_of(obj.shape).period
            if period:
                d = (free[-1, 2] - obj.goal[2]) % period
                assert min(d, period - d) < 1e-3, k
            if name != "iros":
                assert o["free_route"]["min_clearance"] >= C.FREE_CLEARANCE - 1e-4
                assert o["robot_route"]["min_clearance"] >= C.ROBOT_ROOM - 1e-4
                assert o["free_route"]["length"] <= o["robot_route"]["length"] + 0.05
                lf, lr = o["free_route"]["length"], o["robot_route"]["length"]
                tight = lr - lf >= C.TIGHT_MIN_EXTRA and lr >= C.TIGHT_MIN_RATIO * lf
                assert o["tight_shortest_route"] == tight
                assert o["robots"]["all_reach"] and o["robots"]["ring_reachable_fraction"] >= 0.5
                assert min(o["start_clearance"], o["goal_clearance"]) >= G.END_CLEARANCE - 1e-9
            else:
                assert o["final_push_ok"] and o["robots"]["all_reach"] and o["robots_can_leave"]
                assert o["approach_route"]["min_clearance"] >= C.ROBOT_ROOM - 1e-4


def test_cluttered_families_have_many_too_tight_shortest_routes():
    counts = {
        fam: sum(s["objects"][0]["tight_shortest_route"] for s in suite_manifest(fam)["scenes"])
        for fam in FAMILIES
    }
    for fam in ("maze", "tilt", "warehouse"):
        assert counts[fam] >= 15, counts
    assert counts["random"] < counts["maze"]
    # some passages are only slightly wider than the object: the shortest route of those
    # scenes is markedly longer when keeping 5 cm
    for fam in ("maze", "tilt", "warehouse"):
        objs = [s["objects"][0] for s in suite_manifest(fam)["scenes"]]
        narrow = [
            o
            for o in objs
            if o["route_length_by_clearance"]["0.05"] > o["free_route"]["length"] + 0.3
        ]
        assert len(narrow) >= 10, fam


# --------------------------------------------------------------------------- routes re-verified
SAMPLE = [("random", 2), ("maze", 6), ("tilt", 11), ("warehouse", 18)]


@pytest.mark.parametrize(("family", "index"), SAMPLE)
def test_sample_routes_reverified_by_shapely_and_objectspace(family, index):
    sc = suite_scenes(family)[index]
    o = suite_manifest(family)["scenes"][index]["objects"][0]
    for key, tau in (("free_route", C.FREE_CLEARANCE), ("robot_route", C.ROBOT_ROOM)):
        poses = np.array(o[key]["poses"])
        ok, _ = C.verify_route(sc, 0, poses, tau)
        assert ok, key
        dense = _densify(poses, 0.02)[::3]
        ref = np.array([_exact_clearance(sc, 0, p) for p in dense])
        assert ref.min() >= tau - 1e-6, key
        assert o[key]["min_clearance"] <= ref.min() + 1e-6  # recorded min is sampled finer


@pytest.mark.parametrize(("family", "index"), [("maze", 3), ("tilt", 0)])
def test_route_search_reproduces_manifest(family, index):
    sc = suite_scenes(family)[index]
    o = suite_manifest(family)["scenes"][index]["objects"][0]
    free = C.find_route(sc, 0, C.FREE_CLEARANCE)
    roomy = C.find_route(sc, 0, C.ROBOT_ROOM)
    assert free is not None and roomy is not None
    assert round(free.length, 4) == o["free_route"]["length"]
    assert round(roomy.length, 4) == o["robot_route"]["length"]
    assert np.allclose(np.round(free.poses, 4), o["free_route"]["poses"])


def test_iros_sequence_checks_pass():
    (sc,) = suite_scenes("iros")
    steps = iros.check_sequence(sc)
    assert [s.piece for s in steps] == [p[0] for p in iros.PIECES]
    assert all(s.ok for s in steps), [s.to_dict() for s in steps if not s.ok]
    # the order matters: placing the S's bottom bar before its posts blocks the posts'
    # straight push from below
    swapped = scene_from_dict(
        {
            **sc.to_dict(),
            "objects": [
                o.to_dict() for o in (*sc.objects[:6], sc.objects[8], sc.objects[7], sc.objects[6])
            ],
        }
    )
    poses = iros.state_poses(swapped, 8)  # S-upper moved last: bottom bar already placed
    world = C.object_world(swapped, 8, poses)
    obj = swapped.objects[8]
    approach = np.array([obj.goal[0], obj.goal[1] - iros.APPROACH, obj.goal[2]])
    assert C.clearance(obj.shape, world, approach) < C.FREE_CLEARANCE


# --------------------------------------------------------------------------- generator
@pytest.mark.parametrize("family", FAMILIES)
def test_generator_is_deterministic(family):
    man = suite_manifest(family)["scenes"]
    k = min(range(len(man)), key=lambda i: (man[i]["attempts"], i))  # cheapest to regenerate
    a = G.generate_scene(family, k, full_checks=False)
    text = (suite_dir(family) / f"{G.scene_name(family, k)}.yaml").read_text(encoding="utf-8")
    assert a.scene_dict == yaml.safe_load(text)
    assert scene_yaml(a.scene_dict) == text
    assert a.attempts == man[k]["attempts"]


def test_generator_rejects_bad_arguments():
    with pytest.raises(ValueError, match="family"):
        G.generate_scene("forest", 0)
    with pytest.raises(ValueError, match="index"):
        G.generate_scene("maze", 25)


def test_scene_yaml_round_trips():
    d = {
        "format": "lamp-scene/1",
        "name": "t",
        "workspace": [4.0, 4.0],
        "robots": {"radius": 0.05, "starts": [[0.3, 0.3]]},
        "obstacles": [
            G.rect(1.0, 1.0, 0.2, 0.4, 0.3),
            G.circle(2.0, 2.0, 0.1234),
            G.polygon(np.array([[3, 3], [3.5, 3], [3.2, 3.6]])),
        ],
        "objects": [
            {
                "type": "rectangle",
                "size": [0.2, 0.3],
                "start": [0.5, 2.0, -0.0],
                "goal": [3.0, 1.0, 1e-5],
            }
        ],
    }
    back = yaml.safe_load(scene_yaml(d))
    assert back["objects"][0]["goal"][2] == 1e-5 and back["objects"][0]["start"][2] == 0.0
    assert scene_from_dict(back) == scene_from_dict(d)


# --------------------------------------------------------------------------- checks vs oracles
_obstacle = st.one_of(
    st.builds(
        lambda x, y, r: Obstacle(Circle(r), (x, y, 0.0)),
        st.floats(0.3, 2.7),
        st.floats(0.3, 2.7),
        st.floats(0.05, 0.4),
    ),
    st.builds(
        lambda x, y, a, b, t: Obstacle(Rectangle((a, b)), (x, y, t)),
        st.floats(0.3, 2.7),
        st.floats(0.3, 2.7),
        st.floats(0.05, 0.8),
        st.floats(0.05, 0.8),
        st.floats(-3.2, 3.2),
    ),
)
_shape = st.one_of(
    st.builds(Circle, st.floats(0.05, 0.4)),
    st.builds(lambda a, b: Rectangle((a, b)), st.floats(0.05, 0.6), st.floats(0.05, 0.6)),
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    shape=_shape,
    obstacles=st.lists(_obstacle, min_size=0, max_size=5),
    pose=st.tuples(st.floats(0.0, 3.0), st.floats(0.0, 3.0), st.floats(-3.2, 3.2)),
)
def test_clearance_matches_shapely(shape, obstacles, pose):
    world = C.build_world((3.0, 3.0), obstacles)
    got = float(C.clearance(shape, world, pose))
    ref = _ref_clearance(shape, pose, obstacles, (3.0, 3.0))
    if ref > 1e-7:
        assert got == pytest.approx(ref, abs=1e-9)
    elif ref < -1e-7:
        assert got < 0.0


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    shape=_shape,
    obstacles=st.lists(_obstacle, min_size=1, max_size=6),
    ends=st.tuples(*[st.floats(0.3, 2.7)] * 4, st.floats(-3.2, 3.2), st.floats(-3.2, 3.2)),
    tau=st.sampled_from([0.0, 0.02, 0.11]),
)
def test_found_routes_keep_their_clearance(shape, obstacles, ends, tau):
    """Whatever the scene, a returned route is free with clearance >= tau everywhere
    (checked against Shapely every 2 mm of motion), starts at the start and ends at the
    goal footprint."""
    world = C.build_world((3.0, 3.0), obstacles)
    x0, y0, x1, y1, t0, t1 = ends
    start, goal = np.array([x0, y0, t0]), np.array([x1, y1, t1])
    route = C.RouteFinder(shape, world, resolution=0.05, n_headings=8).find(start, goal, tau)
    if route is None:
        return
    assert np.allclose(route.poses[0], start) and np.allclose(route.poses[-1, :2], goal[:2])
    dense = _densify(route.poses, 0.002)
    ref = min(_ref_clearance(shape, p, obstacles, (3.0, 3.0)) for p in dense[::2])
    assert ref >= tau - 1e-9
    assert route.min_clearance >= tau - 1e-9
    lengths = np.hypot(*np.diff(route.poses[:, :2], axis=0).T)
    assert route.length == pytest.approx(lengths.sum())


def _wall_scene(gap: float, shape: dict, roomy_side: float = 0.0) -> object:
    """A wall across y = 2 with a door of width ``gap`` centred at x = 2, and optionally a
    roomy opening of width ``roomy_side`` at the left border."""
    x0 = roomy_side
    obstacles = [
        G.rect(0.5 * (x0 + 2 - gap / 2), 2.0, 2 - gap / 2 - x0, 0.2),
        G.rect(0.5 * (2 + gap / 2 + 4), 2.0, 4 - 2 - gap / 2, 0.2),
    ]
    return scene_from_dict(
        {
            "format": "lamp-scene/1",
            "name": "wall",
            "workspace": [4.0, 4.0],
            "robots": {"radius": 0.05, "starts": [[3.5, 0.3], [3.7, 0.3], [3.5, 0.5]]},
            "obstacles": obstacles,
            "objects": [{**shape, "start": [2.0, 1.0, 0.4], "goal": [2.0, 3.0, -0.3]}],
        }
    )


@pytest.mark.parametrize(
    "shape", [{"type": "circle", "radius": 0.15}, {"type": "rectangle", "size": [0.2, 0.45]}]
)
def test_route_through_a_door_exists_exactly_when_it_fits(shape):
    w = 0.3 if shape["type"] == "circle" else 0.2
    # clearly wider than the object plus 2 tau (lattice offset <= 1.25 cm): found and certified
    sc = _wall_scene(w + 2 * C.FREE_CLEARANCE + 0.04, shape)
    route = C.find_route(sc, 0, C.FREE_CLEARANCE)
    assert route is not None
    dense = _densify(route.poses, 0.005)
    assert min(_exact_clearance(sc, 0, p) for p in dense) >= C.FREE_CLEARANCE - 1e-9
    assert C.find_route(sc, 0, C.ROBOT_ROOM) is None  # no room for robots beside it
    # narrower than object + 2 tau: impossible, whatever the lattice
    assert (
        C.find_route(_wall_scene(w + 2 * C.FREE_CLEARANCE - 0.005, shape), 0, C.FREE_CLEARANCE)
        is None
    )
    assert C.find_route(_wall_scene(w - 0.01, shape), 0, 0.0) is None


def test_fig1_situation_is_flagged():
    shape = {"type": "rectangle", "size": [0.2, 0.4]}
    sc = _wall_scene(0.28, shape, roomy_side=0.5)
    rep = C.check_object(sc, 0, ladder=(C.FREE_CLEARANCE, C.ROBOT_ROOM))
    assert rep.free_route is not None and rep.robot_route is not None
    assert rep.tight_shortest_route
    assert rep.robot_route.length > rep.free_route.length + 1.0
    assert rep.robot_route.poses[:, 0].min() < 0.5  # the detour through the roomy opening
    # with a roomy door the shortest route is not too tight
    roomy = C.check_object(_wall_scene(0.7, shape, roomy_side=0.5), 0, ladder=())
    assert not roomy.tight_shortest_route


def test_robot_reach_detects_an_enclosure():
    base = {
        "format": "lamp-scene/1",
        "name": "box",
        "workspace": [4.0, 4.0],
        "robots": {"radius": 0.05, "starts": [[0.5, 0.5], [0.7, 0.5], [3.5, 3.5]]},
        "objects": [
            {"type": "circle", "radius": 0.2, "start": [2.0, 2.0, 0.0], "goal": [2.0, 3.0, 0.0]}
        ],
    }
    box = [G.rect(1.0, 0.5, 0.1, 1.0), G.rect(0.5, 1.0, 1.0, 0.1)]  # fences robots 0, 1 in a corner
    closed = C.robot_reach(scene_from_dict({**base, "obstacles": box}))
    assert closed.reaches == (False, False, True)
    opened = C.robot_reach(scene_from_dict({**base, "obstacles": box[:1]}))
    assert opened.all_reach and opened.ring_fraction > 0.95


# --------------------------------------------------------------------------- CLI
def test_cli_list():
    res = CliRunner().invoke(suite_app, ["list"])
    assert res.exit_code == 0, res.output
    lines = res.output.strip().splitlines()
    assert [ln.split()[0] for ln in lines] == list_suites()
    counts = {ln.split()[0]: ln.split()[1] for ln in lines}
    assert counts["maze"] == "25" and counts["iros"] == "1" and counts["warehouse-xl"] == "25"
    assert counts["corridor"] == "25"


def test_cli_export(tmp_path):
    res = CliRunner().invoke(suite_app, ["export", "tilt", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    written = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert written == sorted([p.name for p in suite_files("tilt")] + ["manifest.json"])
    for p in suite_files("tilt"):
        assert (tmp_path / "out" / p.name).read_bytes() == p.read_bytes()
    assert lamp.load_scene(tmp_path / "out" / "tilt-07.yaml").name == "tilt-07"


def test_cli_export_unknown_suite(tmp_path):
    res = CliRunner().invoke(suite_app, ["export", "forest", str(tmp_path)])
    assert res.exit_code == 2
    assert "forest" in res.output and "random, maze, tilt, warehouse, iros" in res.output
    assert not any(tmp_path.iterdir())


def test_export_suite_api(tmp_path):
    paths = export_suite("iros", tmp_path)
    assert [p.name for p in paths] == ["iros-01.yaml", "manifest.json"]
    with pytest.raises(ValueError, match="valid names"):
        export_suite("nope", tmp_path)
