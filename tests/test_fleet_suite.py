"""Tests of the ``fleet`` built-in suite (multi-object scenes for the concurrent schedule):
all 25 scenes generate, reproduce the committed files, load and round-trip, meet the brief
(counts, sizes, kinds, ``after`` constraints, a door swap), and independent Shapely checks
of the clearances, the routes and the blockers agree with the generator's checks."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
import shapely
from typer.testing import CliRunner

from lamp.bench.jobs import load_suite
from lamp.bench.request import DEFAULT_SUITES
from lamp.cli.suite import suite_app
from lamp.geometry.shapes import narrowest_width, obstacle_geometry, to_shapely
from lamp.geometry.team import DEFAULT_TEAM
from lamp.planners.limits import check_scene_limits
from lamp.scene.loader import load_scene
from lamp.scene.model import Circle, Polygon, Rectangle
from lamp.scene.save import save_scene
from lamp.suites import checks as C
from lamp.suites import fleet as F
from lamp.suites import fleet_checks as FC
from lamp.suites import fleet_warehouse as FW
from lamp.suites.registry import (
    list_suites,
    scene_yaml,
    suite_files,
    suite_info,
    suite_manifest,
)


@pytest.fixture(scope="module")
def generated() -> list[F.GeneratedFleet]:
    """All 25 scenes, generated once (about 15 s)."""
    return [F.generate_scene(k) for k in range(F.N_SCENES)]


@pytest.fixture(scope="module")
def manifest():
    return suite_manifest(F.NAME)


def _extent(shape) -> float:
    """Largest extent (diameter) of an object."""
    if isinstance(shape, Circle):
        return 2.0 * shape.radius
    if isinstance(shape, Rectangle):
        return max(shape.size)
    pts = np.asarray(shape.points)
    return float(np.max(np.hypot(*(pts[:, None] - pts[None, :]).transpose(2, 0, 1))))


# --------------------------------------------------------------------------- registry
def test_registered_beyond_the_paper_and_not_a_default_suite():
    info = suite_info(F.NAME)
    assert info.n_scenes == F.N_SCENES == 25 and not info.paper
    assert list_suites()[-2:] == ["fleet", "lifelong"]
    assert "fleet" not in DEFAULT_SUITES.split(",")
    assert "lifelong" not in DEFAULT_SUITES.split(",") and not suite_info("lifelong").paper
    jobs = load_suite("fleet")  # what ``lamp bench --suites fleet`` loads
    assert len(jobs) == 25 and not any(j.builtin for j in jobs)
    assert [j.scene.name for j in jobs] == [f"fleet-{k:02d}" for k in range(25)]


def test_cli_lists_and_exports(tmp_path):
    res = CliRunner().invoke(suite_app, ["list"])
    assert res.exit_code == 0
    row = next(ln for ln in res.output.splitlines() if ln.startswith("fleet "))
    assert row.split()[1] == "25"
    res = CliRunner().invoke(suite_app, ["export", "fleet", str(tmp_path)])
    assert res.exit_code == 0, res.output
    assert len(list(tmp_path.glob("fleet-*.yaml"))) == 25
    assert (tmp_path / "manifest.json").is_file()


def test_cli_writes_a_fleet_scene_of_any_size_and_refuses_bad_input(tmp_path):
    from lamp.cli import app

    out = tmp_path / "yard.yaml"
    args = ["suite", "fleet-scene", str(out), "--kind", "yard", "--size", "9", "7",
            "--objects", "3", "--robots", "4", "--seed", "2"]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    scene = load_scene(out)
    assert scene.to_dict() == F.generate_custom("yard", (9.0, 7.0), 3, 4, seed=2).scene.to_dict()
    assert scene.schedule == "concurrent" and scene.n_robots == 4 and len(scene.objects) == 3
    for bad, what in ((["--kind", "hall"], "kind"), (["--size", "3", "7"], "workspace"),
                      (["--robots", "2"], "n_robots")):
        target = tmp_path / f"bad-{what}.yaml"
        res = CliRunner().invoke(app, ["suite", "fleet-scene", str(target), *bad,
                                       "--objects", "3"])
        assert res.exit_code == 2 and what in res.output and not target.exists(), res.output
    res = CliRunner().invoke(app, ["suite", "fleet-scene", str(tmp_path / "x.txt"),
                                   "--kind", "yard", "--size", "9", "7", "--objects", "3",
                                   "--robots", "4"])
    assert res.exit_code == 2 and "extension" in res.output


# --------------------------------------------------------------------------- generation
def test_generated_scenes_are_the_committed_files(generated, manifest):
    files = suite_files(F.NAME)
    assert [p.stem for p in files] == [F.scene_name(k) for k in range(25)]
    for g, path, entry in zip(generated, files, manifest["scenes"], strict=True):
        text = scene_yaml(g.scene_dict)
        assert text == path.read_text(encoding="utf-8"), path.name
        assert entry["sha256"] == hashlib.sha256(text.encode()).hexdigest()
        assert entry == F.manifest_entry(g, text)


def test_generation_is_deterministic(generated):
    for k in (13, 21):  # small maps: cheap to redo
        again = F.generate_scene(k)
        assert again.scene_dict == generated[k].scene_dict
        assert again.attempts == generated[k].attempts


def test_generator_rejects_bad_index():
    for bad in (-1, 25, 1.0, "3"):
        with pytest.raises(ValueError, match="index"):
            F.generate_scene(bad)  # type: ignore[arg-type]


def test_held_out_scenes_continue_the_family_under_their_own_names():
    """Held-out indices run on past the family (its kinds, levels and checks) and are
    named apart from it; family indices are refused there and held-out ones here."""
    a, b = F.generate_scene(34, held_out=True), F.generate_scene(34, held_out=True)
    assert a.scene_dict == b.scene_dict
    assert a.scene.name == "fleet-heldout-34" and a.scene.schedule == "concurrent"
    assert (a.kind, a.layout_info["level"]) == (F.scene_kind(34), F.scene_level(34))
    assert a.scene_dict["name"] not in {F.scene_name(k) for k in range(F.N_SCENES)}
    for bad in (0, 24, True, 30.0):
        with pytest.raises(ValueError, match="index"):
            F.generate_scene(bad, held_out=True)  # type: ignore[arg-type]


def test_lamp_validate_accepts_every_scene():
    from lamp.cli import app

    res = CliRunner().invoke(app, ["validate", *map(str, suite_files(F.NAME))])
    assert res.exit_code == 0, res.output
    assert "25 of 25 scene files valid" in res.output


def test_scenes_validate_and_round_trip(generated, tmp_path):
    for g, path in zip(generated, suite_files(F.NAME), strict=True):
        loaded = load_scene(path)
        assert loaded == g.scene
        check_scene_limits(loaded)
        for suffix in (".yaml", ".json"):
            out = save_scene(loaded, tmp_path / f"{loaded.name}{suffix}")
            assert load_scene(out) == loaded


# --------------------------------------------------------------------------- the brief
def test_counts_sizes_and_schedule(generated):
    rich = lean = 0
    for g in generated:
        sc = g.scene
        assert sc.schedule == "concurrent", sc.name
        assert 6 <= sc.n_robots <= 24 and 2 <= len(sc.objects) <= 12, sc.name
        assert sc.robot_radius == DEFAULT_TEAM.radius
        assert all(6.0 <= v <= 50.0 for v in sc.workspace), sc.name
        lo, hi = F.LEVELS[F.scene_level(g.index)]
        assert all(lo <= v <= hi for v in sc.workspace), sc.name
        for o in sc.objects:
            assert narrowest_width(o.shape) >= 0.2 - 1e-9 and _extent(o.shape) <= 0.6 + 1e-9
        if sc.n_robots >= 3 * len(sc.objects):
            rich += 1
        else:
            lean += 1
    assert rich >= 6 and lean >= 6
    sides = [v for g in generated for v in g.scene.workspace]
    assert min(sides) == 6.0 and max(sides) == 50.0


def test_every_kind_at_every_size(generated):
    for kind in F.KINDS:
        mine = [g for g in generated if g.kind == kind]
        assert len(mine) == 5
        assert sorted(F.scene_level(g.index) for g in mine) == [0, 1, 2, 3, 4]
    shapes = {type(o.shape) for g in generated if g.kind in ("yard", "rooms", "swap")
              for o in g.scene.objects}
    assert shapes == {Circle, Rectangle, Polygon}
    for g in generated:
        if g.kind == "aisles":  # pallets
            assert all(isinstance(o.shape, Rectangle) for o in g.scene.objects)


def test_after_constraints(generated):
    waits = [(g, k) for g in generated for k, o in enumerate(g.scene.objects) if o.after]
    assert len(waits) >= 5 and {g.kind for g, _ in waits} == {"after"}
    for g in generated:
        if g.kind == "after":
            assert any(o.after for o in g.scene.objects), g.scene.name
    for g, k in waits:
        assert all(j < k for j in g.scene.objects[k].after)  # file order is a valid order
        assert g.reports[k].blocked is True


def _disk_free(sc, k: int, rad: float, blocker: int, pose) -> shapely.Geometry:
    """Where the centre of a disk of radius ``rad`` fits among the obstacles, the border
    and the objects other than ``k`` at their starts, ``blocker`` at ``pose``."""
    geoms = [obstacle_geometry(o) for o in sc.obstacles]
    geoms += [to_shapely(o.shape, pose if j == blocker else o.start)
              for j, o in enumerate(sc.objects) if j != k]
    room = shapely.box(0, 0, *sc.workspace).buffer(-rad, join_style="mitre")
    return room.difference(shapely.union_all(geoms).buffer(rad))


def test_blockers_block_their_loads(generated):
    """Independent of the lattice: the disk inscribed in the load (it lies inside the load)
    cannot get from the load's start to its goal past the blocker at its start, and can
    once the blocker stands at its goal."""
    waits = [(g.scene, k) for g in generated for k, o in enumerate(g.scene.objects) if o.after]
    for sc, k in waits:
        load = sc.objects[k]
        rad = 0.5 * narrowest_width(load.shape)
        start, goal = shapely.Point(load.start[:2]), shapely.Point(load.goal[:2])
        (blk,) = load.after
        free = _disk_free(sc, k, rad, blk, sc.objects[blk].start)
        part = next(p for p in getattr(free, "geoms", [free]) if p.distance(start) < 1e-6)
        assert part.distance(goal) > 1e-3, (sc.name, k)
        assert _disk_free(sc, k, rad, blk, sc.objects[blk].goal).distance(goal) < 1e-6


def test_door_swap(generated):
    swaps = [g for g in generated if g.kind == "swap"]
    assert len(swaps) == 5
    for g in swaps:
        sc, info = g.scene, g.layout_info
        x, t = info["wall_x"], info["wall_thickness"]
        assert sc.n_robots >= 6
        a, b = sc.objects[0], sc.objects[1]
        assert (a.start[0] - x) * (a.goal[0] - x) < 0 and (b.start[0] - x) * (b.goal[0] - x) < 0
        assert (a.start[0] - x) * (b.start[0] - x) < 0  # they swap sides
        wall = [o for o in sc.obstacles if isinstance(o.shape, Rectangle)
                and abs(o.pose[0] - x) < 1e-3 and abs(o.shape.size[0] - t) < 2e-3]
        assert len(wall) == 2  # one door: the wall in two pieces
        span = sum(o.shape.size[1] for o in wall)
        assert span == pytest.approx(sc.workspace[1] - info["door_width"], abs=3e-3)
        assert info["door_width"] >= max(narrowest_width(o.shape) for o in sc.objects) + 0.2
        for p in sc.robot_starts_array:
            assert abs(p[0] - x) >= 0.5 * t + sc.robot_radius  # not in the doorway


def test_clearances_of_starts_goals_and_robots(generated):
    """Shapely, independently of the generator's kernels."""
    for g in generated:
        _assert_clearances(g)


def _assert_clearances(g: F.GeneratedFleet) -> None:
    """Shapely, independently of the generator's kernels."""
    sc = g.scene
    r = sc.robot_radius
    walls = shapely.union_all([obstacle_geometry(o) for o in sc.obstacles])
    feet = [to_shapely(o.shape, p) for o in sc.objects for p in (o.start, o.goal)]
    for i, f in enumerate(feet):
        assert walls.distance(f) >= F.END_CLEARANCE - 2e-3, (sc.name, i)
        for j in range(i):
            assert f.distance(feet[j]) >= F.OBJECT_GAP - 2e-3, (sc.name, i, j)
    zones = [shapely.box(*b) for b in g.keep_out]
    robots = [shapely.Point(p) for p in sc.robot_starts_array]
    for i, p in enumerate(robots):
        assert walls.distance(p) >= r + 0.03 - 1e-6
        assert min(f.distance(p) for f in feet) >= r + 0.03 - 2e-3
        assert all(z.distance(p) >= r - 1e-6 for z in zones), (sc.name, i)
        assert all(p.distance(q) >= 2 * r + 0.05 - 1e-6 for q in robots[:i])


@pytest.mark.parametrize(("kind", "size", "n_objects", "n_robots"), [
    ("aisles", (14.0, 10.0), 5, 15), ("yard", (9.0, 7.0), 3, 4), ("after", (10.0, 8.0), 4, 12)])
def test_custom_scenes_at_any_size_keep_the_guarantees(kind, size, n_objects, n_robots):
    """``generate_custom``: the counts asked for, deterministic in its arguments, every
    clearance re-checked with Shapely, every object's route certified."""
    g = F.generate_custom(kind, size, n_objects, n_robots)
    again = F.generate_custom(kind, size, n_objects, n_robots)
    assert g.scene_dict == again.scene_dict
    assert F.generate_custom(kind, size, n_objects, n_robots, seed=1).scene_dict != g.scene_dict
    sc = g.scene
    assert (sc.n_robots, len(sc.objects), sc.workspace) == (n_robots, n_objects, size)
    assert sc.schedule == "concurrent" and g.kind == kind
    assert g.scene_dict["name"] not in {F.scene_name(k) for k in range(F.N_SCENES)}
    _assert_clearances(g)
    assert len(g.reports) == n_objects
    for rep in g.reports:
        assert rep.route.min_clearance >= C.ROBOT_ROOM and rep.reach.all_reach
    if kind == "after":
        assert any(o.after for o in sc.objects)


@pytest.mark.parametrize(("args", "what"), [
    (("hall", (10, 8), 2, 6), "kind"), (("yard", (5, 8), 2, 6), "workspace"),
    (("yard", (10, 200), 2, 6), "workspace"), (("yard", (10, 8), 0, 6), "n_objects"),
    (("after", (10, 8), 1, 6), "n_objects"), (("yard", (10, 8), 4, 3), "n_robots")])
def test_custom_scenes_refuse_bad_arguments_by_name(args, what):
    with pytest.raises(ValueError, match=what):
        F.generate_custom(*args)


# A small Moving AI grid map (8 x 6 m at 0.5 m a cell): two walls with gaps, a pillar.
GRID_MAP = """type octile
height 12
width 16
map
................
................
................
.....@@@@@@.....
.....@..........
.....@..........
..........@@....
..........@@....
................
@@@@@@@@@@@@..@@
................
................
"""


def _grid_map(tmp_path, text: str = GRID_MAP):
    path = tmp_path / "hall.map"
    path.write_text(text)
    return path


def test_fleet_scenes_on_a_users_map_keep_the_guarantees(tmp_path):
    """``generate_on_map``: the map's workspace and obstacles exactly, the counts asked
    for, deterministic in its arguments and in the map, every clearance re-checked with
    Shapely, every object's route certified."""
    from lamp.scene.mapf import load_grid_map

    base = load_grid_map(_grid_map(tmp_path), 0.5).scene
    g = F.generate_on_map(base, 3, 6)
    assert g.scene_dict == F.generate_on_map(base, 3, 6).scene_dict
    assert F.generate_on_map(base, 3, 6, seed=1).scene_dict != g.scene_dict
    other = load_grid_map(_grid_map(tmp_path, GRID_MAP.replace("..@@....", "........")), 0.5)
    assert F.generate_on_map(other.scene, 3, 6).scene_dict["objects"] != g.scene_dict["objects"]
    sc = g.scene
    assert sc.obstacles == base.obstacles and sc.workspace == base.workspace == (8.0, 6.0)
    assert (sc.n_robots, len(sc.objects), sc.schedule) == (6, 3, "concurrent")
    _assert_clearances(g)
    assert len(g.reports) == 3
    for rep in g.reports:
        assert rep.route.min_clearance >= C.ROBOT_ROOM and rep.reach.all_reach


def test_fleet_scenes_on_a_scene_file_keep_its_physics_and_refuse_bad_input(tmp_path):
    from dataclasses import replace

    from lamp.scene.physics import Physics

    base = F.generate_custom("yard", (9.0, 7.0), 3, 4).scene
    base = replace(base, physics=replace(Physics(), robot_speed=0.3), name="mine")
    g = F.generate_on_map(base, 2, 4)
    assert g.scene.physics.robot_speed == 0.3 and g.scene.obstacles == base.obstacles
    assert g.scene_dict["name"].startswith("mine-fleet-")
    assert load_scene(save_scene(g.scene, tmp_path / "g.yaml")) == g.scene
    for bad, what in (((replace(base, robot_radius=0.08), 2, 4), "radius"),
                      ((base, 0, 4), "n_objects"), ((base, 3, 2), "n_robots")):
        with pytest.raises(ValueError, match=what):
            F.generate_on_map(*bad)


def test_cli_writes_a_fleet_scene_on_a_users_map_and_refuses_bad_input(tmp_path):
    from lamp.cli import app
    from lamp.scene.mapf import load_grid_map

    grid, out = _grid_map(tmp_path), tmp_path / "on-map.yaml"
    res = CliRunner().invoke(app, ["suite", "fleet-scene", str(out), "--map", str(grid),
                                   "--objects", "3", "--robots", "6"])
    assert res.exit_code == 0, res.output
    want = F.generate_on_map(load_grid_map(grid, 0.5).scene, 3, 6).scene
    assert load_scene(out).to_dict() == want.to_dict()
    for bad, what in ((["--kind", "yard"], "--kind"), (["--cell", "-1"], "cell"),
                      (["--robots", "2"], "n_robots"), (["--cell", "0.1"], "--cell")):
        target = tmp_path / f"bad{len(what)}.yaml"
        res = CliRunner().invoke(app, ["suite", "fleet-scene", str(target), "--map", str(grid),
                                       "--objects", "3", *bad])
        assert res.exit_code == 2 and what in res.output and not target.exists(), res.output
    res = CliRunner().invoke(app, ["suite", "fleet-scene", str(out), "--map",
                                   str(tmp_path / "none.map")])
    assert res.exit_code == 2 and "none.map" in res.output


def test_object_reports(generated):
    for g in generated:
        for rep in g.reports:
            assert rep.route.min_clearance >= C.ROBOT_ROOM
            assert rep.route.length > 0.5
            assert rep.reach.all_reach and rep.reach.ring_fraction >= FC.MIN_RING
            assert rep.start_clearance >= F.END_CLEARANCE - 1e-3


@pytest.mark.parametrize("index", [0, 1, 4, 5, 6, 9, 13, 14, 17, 18, 19, 21, 22, 23])
def test_routes_rechecked_with_shapely(generated, index):
    """The certified routes keep ROBOT_ROOM from everything that may stand in their way
    (Shapely on poses 1 cm apart: within 1 cm of the exact minimum)."""
    g = generated[index]
    sc = g.scene
    anc = FC.ancestry([o.after for o in sc.objects])
    W, H = sc.workspace
    for k, rep in enumerate(g.reports):
        world = shapely.union_all([obstacle_geometry(o) for o in FC.standing(sc, k, anc)])
        shape = sc.objects[k].shape
        reach = float(np.max(np.abs(shapely.get_coordinates(to_shapely(shape)))) * 1.5)
        poses = rep.route.poses
        for a, b in zip(poses[:-1], poses[1:], strict=True):
            n = max(1, math.ceil((math.hypot(*(b[:2] - a[:2])) + reach * abs(b[2] - a[2]))
                                 / 0.01))
            for t in np.arange(n + 1) / n:
                f = to_shapely(shape, a + t * (b - a))
                x0, y0, x1, y1 = f.bounds
                assert min(x0, y0, W - x1, H - y1) >= C.ROBOT_ROOM - 0.01
                assert world.distance(f) >= C.ROBOT_ROOM - 0.01, (sc.name, k)


def test_helpers():
    assert FC.ancestry([(), (0,), (1,), ()]) == [set(), {0}, {0, 1}, set()]
    cuts = [(2.0, 1.0, 0, 0.8), (2.2, 0.8, 1, 0.6), (5.0, 1.0, 1, 0.5)]
    pieces = FW._shelf_pieces(0.0, 8.0, (1.0, 3.0), cuts)
    area = sum((b - a) * (d - c) for a, c, b, d in pieces)
    assert area == pytest.approx(8.0 * 2.0 - 1.0 * 0.8 - 0.8 * 0.6 - 1.0 * 0.5)
    assert all(b - a > 0 and d - c >= 0.1 for a, c, b, d in pieces)


def test_each_draw_is_announced_with_why_the_ones_before_failed() -> None:
    """``on_attempt`` hears of draws 1, 2, ... of ``MAX_ATTEMPTS`` in turn, each with the
    reasons of the draws before it (as many as came before); on success the last is the
    scene's own draw, on failure all ``MAX_ATTEMPTS`` were announced."""
    calls: list[tuple[int, int, dict[str, int]]] = []
    g = F.generate_custom("yard", (6.0, 6.0), 12, 12,
                          on_attempt=lambda a, of, why: calls.append((a, of, why)))
    assert g.attempts > 1  # (this one needs several draws)
    assert [c[0] for c in calls] == list(range(1, g.attempts + 1))
    assert all(of == F.MAX_ATTEMPTS and sum(why.values()) == a - 1 for a, of, why in calls)
    assert set(calls[-1][2]) == {"no robot-room route for an object"}  # counted by kind
    calls.clear()
    with pytest.raises(RuntimeError, match="no valid scene"):
        F.generate_custom("aisles", (8.0, 6.0), 6, 12,
                          on_attempt=lambda a, of, why: calls.append((a, of, why)))
    assert [c[0] for c in calls] == list(range(1, F.MAX_ATTEMPTS + 1))
    assert calls[-1][2] == {"objects do not fit": F.MAX_ATTEMPTS - 1}


def test_drawing_a_scene_shows_a_status_line_on_a_terminal_only() -> None:
    import io

    from lamp.cli.suite import DrawProgress

    stream = io.StringIO()
    with DrawProgress(stream=stream, terminal=True) as shown:
        shown(1, 30, {})
        shown(3, 30, {"objects do not fit": 2})
    assert "drawing the scene: attempt 3/30 (rejected so far: objects do not fit x2)" \
        in stream.getvalue()
    piped = io.StringIO()
    with DrawProgress(stream=piped, terminal=False) as shown:
        shown(3, 30, {"objects do not fit": 2})
    assert piped.getvalue() == ""
