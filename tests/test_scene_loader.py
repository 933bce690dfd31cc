"""Tests of the validating scene loader (``lamp.scene.loader``).

Three layers:
- the spec's example and a JSON file load, and ``scene_from_dict(scene.to_dict()) == scene``;
- one test per rule of ``scene-format.md``: the message names the file, the field and the value;
- properties: geometric verdicts against answers known by construction (gaps of either sign
  between rotated rectangles, disks and the border), random valid scenes always load, and
  random corruptions of valid scenes (and random bytes) only ever raise ``SceneError``.
"""

from __future__ import annotations

import copy
import json
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lamp.scene import Scene, SceneError, load_scene, scene_from_dict
from lamp.scene.loader import _UNEXPECTED

DATA = Path(__file__).parent / "data"
SPEC_FIXED = DATA / "spec_example_fixed.yaml"


_VALID = yaml.safe_load(SPEC_FIXED.read_text())
_MINIMAL = json.loads((DATA / "minimal.json").read_text())


def valid() -> dict[str, Any]:
    """A fresh copy of the (fixed) spec example as a plain dict."""
    return copy.deepcopy(_VALID)


def write(tmp_path: Path, d: Any, name: str = "scene.yaml") -> Path:
    path = tmp_path / name
    if name.endswith(".json"):
        path.write_text(json.dumps(d))
    else:
        path.write_text(yaml.safe_dump(d, sort_keys=False))
    return path


def expect_error(path: Path, field: str, *fragments: str) -> str:
    """Load ``path``; assert a SceneError ``<path>: <field>: ...`` containing ``fragments``."""
    with pytest.raises(SceneError) as info:
        load_scene(path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: {field}: "), msg
    for f in fragments:
        assert f in msg, (f, msg)
    assert _UNEXPECTED not in msg
    return msg


# --------------------------------------------------------------------------- valid files


def test_spec_example_fixed_loads() -> None:
    scene = load_scene(SPEC_FIXED)
    assert scene.name == "maze-07"
    assert scene.workspace == (4.0, 4.0)
    assert scene.n_robots == 3 and scene.robot_radius == 0.05
    assert [type(o.shape).__name__ for o in scene.objects] == ["Rectangle", "Circle", "Polygon"]
    assert [type(o.shape).__name__ for o in scene.obstacles] == ["Circle", "Rectangle", "Polygon"]
    assert scene.objects[0].goal == (3.2, 3.3, 1.5708)
    assert scene.source == str(SPEC_FIXED)
    assert scene_from_dict(scene.to_dict()) == scene


def test_spec_example_verbatim_loads() -> None:
    """The example of scene-format.md, copied verbatim, is a valid scene."""
    scene = load_scene(DATA / "spec_example.yaml")
    assert scene.name == "maze-07" and len(scene.objects) == 3 and len(scene.obstacles) == 3
    assert scene.objects[2].goal == (3.2, 0.5, 0.0)
    assert scene_from_dict(scene.to_dict()) == scene


def test_docs_example_is_the_tested_copy() -> None:
    """docs/scene-format.md's example is the file loaded above (so the docs' example loads)."""
    doc = (Path(__file__).parents[1] / "docs" / "scene-format.md").read_text()
    block = doc.split("```yaml\n", 1)[1].split("```", 1)[0]
    copy_text = (DATA / "spec_example.yaml").read_text().split("\n", 1)[1]
    assert block == copy_text


def test_wall_at_angle_1_5708_touching_the_border_loads() -> None:
    """``angle: 1.5708`` is not exactly pi/2: a wall touching the border pokes out by ~2e-7 m,
    within the spec's 1e-6 m rounding; 2e-6 m beyond the border is still refused."""
    d = valid()
    # size (0.1, 2.0) turned by ~90 degrees: a horizontal wall from x = 0 to x = 2
    a = 1.5708
    wall = {"type": "rectangle", "center": [1.0, 2.0], "size": [0.1, 2.0], "angle": a}
    overhang = 0.05 * abs(math.cos(a)) + 1.0 * abs(math.sin(a)) - 1.0
    assert 1e-7 < overhang < 1e-6  # the rounding of the report, really there
    d["obstacles"] = [wall]
    assert scene_from_dict(d).obstacles[0].pose == (1.0, 2.0, a)
    d["obstacles"] = [{**wall, "center": [1.0 - 2e-6, 2.0]}]
    with pytest.raises(SceneError, match=r"obstacles\[0\]: .*lies outside the workspace"):
        scene_from_dict(d)


def test_overlap_allows_1e_6_of_rounding() -> None:
    """Two disks overlapping by 5e-7 m count as touching; by 5e-6 m as overlapping."""
    d = valid()
    r, R = d["robots"]["radius"], d["obstacles"][0]["radius"]
    cx, cy = d["obstacles"][0]["center"]
    for depth, ok in ((5e-7, True), (5e-6, False)):
        d["robots"]["starts"][0] = [cx - (r + R - depth), cy]
        if ok:
            scene_from_dict(d)
        else:
            with pytest.raises(SceneError, match=r"robots.starts\[0\]: .*overlaps obstacles\[0\]"):
                scene_from_dict(d)


def test_scene_error_carries_path_and_field(tmp_path: Path) -> None:
    d = valid()
    d["objects"][1]["radius"] = -0.2
    path = write(tmp_path, d)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    err = info.value
    assert (err.path, err.field) == (str(path), "objects[1].radius")
    assert str(err) == f"{path}: objects[1].radius: {err.reason}" and "-0.2" in err.reason
    with pytest.raises(SceneError) as info:
        scene_from_dict(d)
    assert info.value.path is None and info.value.field == "objects[1].radius"
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "missing.yaml")
    assert info.value.field == "(file)" and info.value.path == str(tmp_path / "missing.yaml")
    import pickle

    again = pickle.loads(pickle.dumps(err))
    assert (str(again), again.path, again.field, again.reason) == (
        str(err), err.path, err.field, err.reason)


def test_json_loads_and_matches_yaml(tmp_path: Path) -> None:
    scene = load_scene(DATA / "minimal.json")
    assert scene.name == "minimal-json"
    assert scene.robot_radius == 0.05  # default
    assert scene.obstacles == ()
    assert scene.objects[0].shape.radius == 0.2  # JSON "2e-1"
    assert scene_from_dict(scene.to_dict()) == scene
    # The same scene written as JSON loads to the same value as its YAML form.
    yaml_scene = load_scene(SPEC_FIXED)
    assert load_scene(write(tmp_path, yaml_scene.to_dict(), "s.json")) == yaml_scene
    assert load_scene(write(tmp_path, yaml_scene.to_dict(), "s.yaml")) == yaml_scene


def test_json_content_in_a_yaml_file_loads(tmp_path: Path) -> None:
    """JSON is YAML: a .yaml file holding JSON text loads too (with exponent floats)."""
    text = (DATA / "minimal.json").read_text()
    path = tmp_path / "minimal.yaml"
    path.write_text(text)
    assert load_scene(path) == load_scene(DATA / "minimal.json")


def test_yaml12_floats_and_null_optionals(tmp_path: Path) -> None:
    d = valid()
    text = yaml.safe_dump(d, sort_keys=False).replace("radius: 0.05", "radius: 5e-2")
    text = text.replace("angle: 0.0", "angle: null")
    path = tmp_path / "s.yaml"
    path.write_text(text)
    scene = load_scene(path)
    assert scene.robot_radius == 0.05
    assert scene.obstacles[1].pose[2] == 0.0
    path.write_text(text.replace("obstacles:", "obstacles: null\nunused_obstacles:", 1))
    expect_error(path, "unused_obstacles", "unknown key")


def test_scene_from_dict_labels_dict_or_source() -> None:
    d = valid()
    d["workspace"] = [4.0, -1.0]
    with pytest.raises(SceneError, match=r"^<dict>: workspace\[1\]: must be > 0, got -1.0$"):
        scene_from_dict(d)
    with pytest.raises(SceneError, match=r"^suite/maze-3: workspace\[1\]: "):
        scene_from_dict(d, source="suite/maze-3")
    scene = scene_from_dict(valid(), source="x.yaml")
    assert scene.source == "x.yaml" and scene == load_scene(SPEC_FIXED)


def test_touching_is_allowed(tmp_path: Path) -> None:
    """Exact contact (border, robot-robot, robot-object, object-obstacle) is not overlap."""
    d = valid()
    d["robots"]["starts"] = [[0.05, 0.3], [0.15, 0.3], [0.25, 0.05]]  # border and each other
    d["objects"][0]["start"] = [0.5, 0.2, 0.0]  # rectangle 0.4 x 0.3: y from 0.05, x from 0.3
    d["objects"][1]["goal"] = [3.0, 1.35, 0.0]  # disk r 0.2 touching obstacle disk r 0.15
    d["objects"][2]["start"] = [0.2, 3.9, 0.0]  # polygon touching the left and top border
    d["objects"][2]["goal"] = [1.3, 2.0, 0.0]  # polygon touching the rectangle obstacle's side
    scene = load_scene(write(tmp_path, d))
    assert scene.robot_starts[0] == (0.05, 0.3)


# --------------------------------------------------------------------------- rules

Mutation = Callable[[dict[str, Any]], None]


def setp(path: tuple, value: Any) -> Mutation:
    """A mutation that sets ``d[path[0]][path[1]]... = value``."""

    def apply(d: dict[str, Any]) -> None:
        node = d
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value

    return apply


def delp(path: tuple) -> Mutation:
    def apply(d: dict[str, Any]) -> None:
        node = d
        for k in path[:-1]:
            node = node[k]
        del node[path[-1]]

    return apply


BOWTIE = [[0.0, 0.0], [0.2, 0.2], [0.2, 0.0], [0.0, 0.2]]
RULES: list[tuple[str, Mutation, str, tuple[str, ...]]] = [
    # format and required fields
    ("format-wrong", setp(("format",), "lamp-scene/2"), "format", ("'lamp-scene/1'", "'lamp-scene/2'")),
    ("format-number", setp(("format",), 1), "format", ("got 1",)),
    ("format-missing", delp(("format",)), "format", ("missing required field",)),
    ("name-missing", delp(("name",)), "name", ("missing",)),
    ("name-number", setp(("name",), 7), "name", ("must be a string", "7")),
    ("workspace-missing", delp(("workspace",)), "workspace", ("missing",)),
    ("robots-missing", delp(("robots",)), "robots", ("missing",)),
    ("starts-missing", delp(("robots", "starts")), "robots.starts", ("missing",)),
    ("objects-missing", delp(("objects",)), "objects", ("missing",)),
    ("object-goal-missing", delp(("objects", 1, "goal")), "objects[1].goal", ("missing",)),
    ("object-type-missing", delp(("objects", 0, "type")), "objects[0].type", ("missing",)),
    ("obstacle-radius-missing", delp(("obstacles", 0, "radius")), "obstacles[0].radius", ("missing",)),
    # wrong types
    ("workspace-bool", setp(("workspace", 0), True), "workspace[0]", ("must be a number", "True")),
    ("workspace-string", setp(("workspace", 1), "4.0"), "workspace[1]", ("must be a number", "'4.0'")),
    ("workspace-len", setp(("workspace",), [4.0]), "workspace", ("2 numbers", "[4.0]")),
    ("robots-list", setp(("robots",), [[0.3, 0.3]]), "robots", ("must be a mapping",)),
    ("starts-not-list", setp(("robots", "starts"), "none"), "robots.starts", ("must be a list", "'none'")),
    ("start-point-len", setp(("robots", "starts", 1), [0.5]), "robots.starts[1]", ("[0.5]",)),
    ("obstacles-mapping", setp(("obstacles",), {"a": 1}), "obstacles", ("must be a list",)),
    ("object-not-mapping", setp(("objects", 1), [1, 2]), "objects[1]", ("must be a mapping", "[1, 2]")),
    ("object-type-unknown", setp(("objects", 0, "type"), "triangle"), "objects[0].type", ("'triangle'",)),
    ("object-radius-bool", setp(("objects", 1, "radius"), False), "objects[1].radius", ("False", "bool")),
    ("object-pose-len", setp(("objects", 0, "start"), [0.8, 0.6]), "objects[0].start", ("x, y, theta", "[0.8, 0.6]")),
    ("obstacle-angle-string", setp(("obstacles", 1, "angle"), "0"), "obstacles[1].angle", ("'0'", "string")),
    ("obstacle-type-number", setp(("obstacles", 2, "type"), 3), "obstacles[2].type", ("got 3",)),
    # non-finite numbers
    ("workspace-nan", setp(("workspace", 0), float("nan")), "workspace[0]", ("finite", "nan")),
    ("robot-inf", setp(("robots", "starts", 2, 0), float("inf")), "robots.starts[2][0]", ("finite", "inf")),
    ("goal-theta-ninf", setp(("objects", 0, "goal", 2), -float("inf")), "objects[0].goal[2]", ("-inf",)),
    ("obstacle-center-nan", setp(("obstacles", 0, "center", 1), float("nan")), "obstacles[0].center[1]", ("nan",)),
    ("huge-int", setp(("workspace", 0), 10**400), "workspace[0]", ("finite", "1000")),
    # zero / negative sizes and radii
    ("size-negative", setp(("objects", 0, "size", 0), -0.2), "objects[0].size[0]", ("must be > 0, got -0.2",)),
    ("size-zero", setp(("objects", 0, "size", 1), 0.0), "objects[0].size[1]", ("> 0, got 0.0",)),
    ("radius-zero", setp(("objects", 1, "radius"), 0), "objects[1].radius", ("> 0, got 0",)),
    ("robot-radius-negative", setp(("robots", "radius"), -0.05), "robots.radius", ("-0.05",)),
    ("workspace-zero", setp(("workspace", 1), 0.0), "workspace[1]", ("> 0",)),
    ("obstacle-size-negative", setp(("obstacles", 1, "size", 1), -1.5), "obstacles[1].size[1]", ("-1.5",)),
    ("obstacle-radius-negative", setp(("obstacles", 0, "radius"), -0.15), "obstacles[0].radius", ("-0.15",)),
    # polygons
    ("polygon-2-points", setp(("objects", 2, "points"), [[0, 0], [0.1, 0]]), "objects[2].points", ("at least 3 points", "got 2")),
    ("polygon-bowtie", setp(("objects", 2, "points"), BOWTIE), "objects[2].points", ("simple", "[0.2, 0.2]")),
    ("polygon-zero-area", setp(("objects", 2, "points"), [[0, 0], [0.1, 0], [0.2, 0]]), "objects[2].points", ("positive area", "[0.2, 0]")),
    ("polygon-repeated", setp(("objects", 2, "points"), [[0, 0], [0.1, 0], [0.1, 0], [0, 0.1]]), "objects[2].points[2]", ("repeats", "objects[2].points[1]")),
    ("polygon-closed-ring", setp(("obstacles", 2, "points"), [[2, 2], [2.5, 2], [2.2, 2.6], [2, 2]]), "obstacles[2].points[3]", ("repeats vertex obstacles[2].points[0] (2, 2)",)),
    ("obstacle-bowtie", setp(("obstacles", 2, "points"), [[2, 2], [2.5, 2.5], [2.5, 2], [2, 2.5]]), "obstacles[2].points", ("simple",)),
    ("polygon-point-nan", setp(("objects", 2, "points", 1, 0), float("nan")), "objects[2].points[1][0]", ("nan",)),
    # unknown keys
    ("unknown-top", setp(("colour",), "red"), "colour", ("unknown key", "obstacles")),
    ("unknown-robots", setp(("robots", "speeds"), 1.0), "robots.speeds", ("unknown key", "radius", "did you mean 'speed'")),
    ("unknown-object", setp(("objects", 1, "weight"), 2.0), "objects[1].weight", ("unknown key", "mass")),
    ("unknown-typo", setp(("objects", 1, "radus"), 0.2), "objects[1].radus", ("did you mean 'radius'",)),
    ("unknown-obstacle", setp(("obstacles", 0, "angle"), 0.0), "obstacles[0].angle", ("unknown key", "center, radius")),
    ("unknown-nonstring-key", setp((3,), 1), "3", ("unknown key",)),
    # outside the workspace (exact footprints)
    ("robot-outside", setp(("robots", "starts", 0), [0.04, 0.3]), "robots.starts[0]", ("outside", "[0, 4] x [0, 4]", "(0.04, 0.3)")),
    ("robot-far-outside", setp(("robots", "starts", 0), [-1.0, 9.0]), "robots.starts[0]", ("outside",)),
    ("obstacle-circle-outside", setp(("obstacles", 0, "center"), [3.9, 1.0]), "obstacles[0]", ("outside", "circle")),
    ("obstacle-rotated-outside", setp(("obstacles", 1), {"type": "rectangle", "center": [0.5, 2.0], "size": [0.2, 1.5], "angle": 1.5708}), "obstacles[1]", ("outside", "x [-0.25")),
    ("obstacle-polygon-outside", setp(("obstacles", 2, "points", 2), [2.2, 4.1]), "obstacles[2]", ("outside", "polygon")),
    ("object-start-outside", setp(("objects", 0, "start"), [0.8, 0.1, 0.0]), "objects[0].start", ("outside", "(0.8, 0.1, 0)")),
    ("object-goal-rotated-outside", setp(("objects", 0, "goal"), [3.2, 3.82, 1.5708]), "objects[0].goal", ("outside",)),
    ("object-circle-goal-outside", setp(("objects", 1, "goal"), [2.0, 3.85, 0.0]), "objects[1].goal", ("outside", "y [3.65, 4.05]")),
    # overlaps
    ("robots-overlap", setp(("robots", "starts", 1), [0.35, 0.3]), "robots.starts[1]", ("overlaps robots.starts[0]",)),
    ("robot-on-circle-obstacle", setp(("robots", "starts", 2), [3.0, 0.82]), "robots.starts[2]", ("overlaps obstacles[0]",)),
    ("robot-on-rect-obstacle", setp(("robots", "starts", 2), [1.14, 2.0]), "robots.starts[2]", ("overlaps obstacles[1]",)),
    ("robot-inside-polygon-obstacle", setp(("robots", "starts", 2), [2.2, 2.2]), "robots.starts[2]", ("overlaps obstacles[2]",)),
    ("robot-on-object-start", setp(("robots", "starts", 2), [0.8, 0.79]), "robots.starts[2]", ("overlaps objects[0].start",)),
    ("object-start-on-obstacle", setp(("objects", 1, "start"), [1.0, 1.1, 0.0]), "objects[1].start", ("overlaps obstacles[1]",)),
    ("object-goal-on-obstacle", setp(("objects", 0, "goal"), [2.9, 1.0, 0.0]), "objects[0].goal", ("overlaps obstacles[0]",)),
    ("polygon-goal-on-polygon", setp(("objects", 2, "goal"), [2.25, 2.1, 0.3]), "objects[2].goal", ("overlaps obstacles[2]",)),
    ("objects-overlap-at-start", setp(("objects", 1, "start"), [1.1, 0.6, 0.0]), "objects[0].start", ("overlaps objects[1].start",)),
    ("objects-overlap-at-goal", setp(("objects", 2, "goal"), [2.0, 3.2, 0.0]), "objects[1].goal", ("overlaps objects[2].goal",)),
    # counts
    ("no-robots", setp(("robots", "starts"), []), "robots.starts", ("at least 1",)),
    ("no-objects", setp(("objects",), []), "objects", ("at least 1",)),
]  # fmt: skip


@pytest.mark.parametrize(("mutate", "field", "fragments"), [r[1:] for r in RULES], ids=[r[0] for r in RULES])
def test_rule(tmp_path: Path, mutate: Mutation, field: str, fragments: tuple[str, ...]) -> None:
    d = valid()
    mutate(d)
    path = write(tmp_path, d)
    expect_error(path, field, *fragments)
    # The dict path reports the same field under the <dict> label.
    with pytest.raises(SceneError) as info:
        scene_from_dict(d)
    assert str(info.value).startswith(f"<dict>: {field}: ")


def test_example_message_from_the_brief(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    d = valid()
    d["objects"][1] = {"type": "rectangle", "size": [-0.2, 0.3], "start": [2, 0.6, 0], "goal": [2, 3.4, 0]}
    write(tmp_path, d, "maze.yaml")
    monkeypatch.chdir(tmp_path)
    msg = expect_error(Path("maze.yaml"), "objects[1].size[0]")
    assert msg == "maze.yaml: objects[1].size[0]: must be > 0, got -0.2"


# --------------------------------------------------------------------------- file errors


def test_file_not_found(tmp_path: Path) -> None:
    expect_error(tmp_path / "nope.yaml", "(file)", "not found")


def test_directory(tmp_path: Path) -> None:
    expect_error(tmp_path, "(file)", "directory")


def test_unreadable(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = write(tmp_path, valid())
    path.chmod(0)
    if hasattr(os, "geteuid") and os.geteuid() == 0:  # root reads anything: refuse as the OS would
        read_bytes = Path.read_bytes

        def refuse(self: Path) -> bytes:
            if self == path:
                raise PermissionError(13, "Permission denied", str(self))
            return read_bytes(self)

        monkeypatch.setattr(Path, "read_bytes", refuse)
    expect_error(path, "(file)", "cannot read", "Permission denied")


@pytest.mark.parametrize(
    ("text", "fragment"),
    [("", "null"), ("- 1\n- 2\n", "[1, 2]"), ("just text", "'just text'"), ("42", "42")],
)
def test_not_a_mapping(tmp_path: Path, text: str, fragment: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    expect_error(path, "(top level)", "must be a mapping", fragment)


def test_yaml_syntax_error(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text("format: lamp-scene/1\nname: [unclosed\nworkspace: [4, 4]\n")
    expect_error(path, "(file)", "YAML syntax error", "line")


def test_json_syntax_error(tmp_path: Path) -> None:
    path = tmp_path / "s.json"
    path.write_text('{"format": "lamp-scene/1",}')
    expect_error(path, "(file)", "JSON syntax error", "line 1")


def test_repeated_keys(tmp_path: Path) -> None:
    text = yaml.safe_dump(valid(), sort_keys=False)
    path = tmp_path / "s.yaml"
    path.write_text(text + "name: again\n")
    expect_error(path, "(file)", "repeated key 'name'", "line")
    jpath = tmp_path / "s.json"
    jpath.write_text('{"name": "a", "name": "b"}')
    expect_error(jpath, "(file)", "repeated key 'name'")


def test_bad_bytes_and_deep_nesting(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_bytes(b"format: \xff\xfe\x00lamp")
    expect_error(path, "(file)")
    path.write_text("[" * 1500)
    expect_error(path, "(file)")
    jpath = tmp_path / "s.json"
    jpath.write_bytes(b"\xff\xff")
    expect_error(jpath, "(file)", "UTF-8")
    jpath.write_text("[" * 100000 + "]" * 100000)
    expect_error(jpath, "(file)")


def test_self_referencing_yaml(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text("&a {format: lamp-scene/1, name: x, workspace: [1, 1], robots: *a, objects: []}")
    expect_error(path, "robots.format", "unknown key")


# --------------------------------------------------------------------------- geometry oracles


def scene_with(robot: list[float], obstacle: dict, obj: dict, ws: float = 10.0) -> dict:
    """One robot, one obstacle, one object; the object's goal sits in a far corner."""
    o = dict(obj)
    o.setdefault("goal", [ws - 0.5, ws - 0.5, 0.0])
    return {
        "format": "lamp-scene/1",
        "name": "oracle",
        "workspace": [ws, ws],
        "robots": {"radius": 0.05, "starts": [robot]},
        "obstacles": [obstacle],
        "objects": [o],
    }


def verdict(d: dict) -> str | None:
    """The field of the error, or None when the scene loads."""
    try:
        scene_from_dict(d)
    except SceneError as exc:
        assert _UNEXPECTED not in str(exc)
        return str(exc).split(": ")[1]
    return None


# gap 0 is exact contact (allowed, up to rounding in the rotations); |gap| >= 1e-5 > EPS.
gaps = st.one_of(st.just(0.0), st.floats(-0.04, -1e-5), st.floats(1e-5, 0.5))
angles = st.floats(-math.pi, math.pi)
sizes = st.floats(0.05, 1.0)


@settings(max_examples=150, deadline=None)
@given(gap=gaps, angle=angles, sx=sizes, sy=sizes, side=st.floats(-0.49, 0.49))
def test_robot_vs_rotated_rectangle(gap: float, angle: float, sx: float, sy: float, side: float) -> None:
    """A robot at distance ``sx/2 + r + gap`` along the rectangle's own x axis (facing its
    edge) overlaps exactly when ``gap < 0``."""
    c, s = math.cos(angle), math.sin(angle)
    u, v = 0.5 * sx + 0.05 + gap, side * sy  # robot centre in the rectangle's frame
    robot = [5.0 + c * u - s * v, 5.0 + s * u + c * v]
    obstacle = {"type": "rectangle", "center": [5.0, 5.0], "size": [sx, sy], "angle": angle}
    obj = {"type": "circle", "radius": 0.1, "start": [0.5, 0.5, 0.0]}
    assert verdict(scene_with(robot, obstacle, obj)) == ("robots.starts[0]" if gap < 0 else None)


@settings(max_examples=150, deadline=None)
@given(gap=gaps, angle=angles, size=st.tuples(sizes, sizes, sizes, sizes), side=st.floats(-0.4, 0.4))
def test_rectangle_object_vs_rotated_rectangle(
    gap: float, angle: float, size: tuple[float, ...], side: float
) -> None:
    """Two rectangles with a common angle, side by side along their x axis with ``gap``
    between them (and overlapping extents along y): the object overlaps iff ``gap < 0``.
    The object is a polygon half the time (same outline) to cover polygon footprints."""
    ax, ay, bx, by = size
    c, s = math.cos(angle), math.sin(angle)
    u, v = 0.5 * (ax + bx) + gap, side * min(ay, by)
    start = [5.0 + c * u - s * v, 5.0 + s * u + c * v, angle]
    obstacle = {"type": "rectangle", "center": [5.0, 5.0], "size": [ax, ay], "angle": angle}
    for obj in (
        {"type": "rectangle", "size": [bx, by], "start": start},
        {
            "type": "polygon",
            "points": [[-bx / 2, -by / 2], [bx / 2, -by / 2], [bx / 2, by / 2], [-bx / 2, by / 2]],
            "start": start,
        },
    ):
        assert verdict(scene_with([0.3, 0.3], obstacle, obj)) == (
            "objects[0].start" if gap < 0 else None
        )


@settings(max_examples=150, deadline=None)
@given(gap=gaps, r1=st.floats(0.02, 1.0), r2=st.floats(0.02, 1.0), angle=angles)
def test_disk_object_vs_disk_obstacle_at_goal(gap: float, r1: float, r2: float, angle: float) -> None:
    goal = [5.0 + (r1 + r2 + gap) * math.cos(angle), 5.0 + (r1 + r2 + gap) * math.sin(angle), 0.0]
    obstacle = {"type": "circle", "center": [5.0, 5.0], "radius": r1}
    obj = {"type": "circle", "radius": r2, "start": [9.0, 0.5 + r2, 0.0], "goal": goal}
    assert verdict(scene_with([0.3, 0.3], obstacle, obj)) == ("objects[0].goal" if gap < 0 else None)


@settings(max_examples=150, deadline=None)
@given(gap=gaps, angle=angles, sx=sizes, sy=sizes, wall=st.sampled_from(["left", "right", "bottom", "top"]))
def test_rotated_rectangle_vs_border(gap: float, angle: float, sx: float, sy: float, wall: str) -> None:
    """A rotated rectangle whose extent ``|hx cos| + |hy sin|`` ends ``gap`` inside a wall is
    outside the workspace iff ``gap < 0``."""
    ex = 0.5 * sx * abs(math.cos(angle)) + 0.5 * sy * abs(math.sin(angle))
    ey = 0.5 * sx * abs(math.sin(angle)) + 0.5 * sy * abs(math.cos(angle))
    x = {"left": ex + gap, "right": 10.0 - ex - gap}.get(wall, 5.0)
    y = {"bottom": ey + gap, "top": 10.0 - ey - gap}.get(wall, 5.0)
    obj = {"type": "rectangle", "size": [sx, sy], "start": [x, y, angle], "goal": [5.0, 5.0, 0.0]}
    obstacle = {"type": "circle", "center": [8.0, 2.0], "radius": 0.1}
    assert verdict(scene_with([0.3, 9.7], obstacle, obj)) == ("objects[0].start" if gap < 0 else None)


# --------------------------------------------------------------------------- random valid scenes


@st.composite
def shape_dicts(draw: st.DrawFn, obstacle: bool, centre: tuple[float, float]) -> dict:
    """A random shape that fits in the disk of radius 0.45 around ``centre``."""
    kind = draw(st.sampled_from(["circle", "rectangle", "polygon"]))
    angle = draw(angles)
    x, y = centre
    if kind == "circle":
        d: dict[str, Any] = {"type": "circle", "radius": draw(st.floats(0.01, 0.45))}
        if obstacle:
            d["center"] = [x, y]
    elif kind == "rectangle":
        half_diag = draw(st.floats(0.02, 0.45))
        a = draw(st.floats(0.1, 1.4))  # aspect angle: size = 2 * half_diag * (cos a, sin a)
        d = {"type": "rectangle", "size": [2 * half_diag * math.cos(a), 2 * half_diag * math.sin(a)]}
        if obstacle:
            d["center"], d["angle"] = [x, y], angle
    else:
        # Star-shaped around the origin (every angular gap < pi), hence simple.
        n = draw(st.integers(3, 8))
        jitter = draw(st.lists(st.floats(0.0, 0.4), min_size=n, max_size=n))
        ts = [2 * math.pi * (k + j) / n for k, j in enumerate(jitter)]
        radii = draw(st.lists(st.floats(0.05, 0.45), min_size=n, max_size=n))
        pts = [[r * math.cos(t), r * math.sin(t)] for r, t in zip(radii, ts, strict=True)]
        if obstacle:
            pts = [[x + px, y + py] for px, py in pts]
        d = {"type": "polygon", "points": pts}
    return d


@st.composite
def valid_scene_dicts(draw: st.DrawFn) -> dict:
    """Items in distinct unit cells of a grid, each inside a disk of radius 0.45 around the
    cell centre: nothing overlaps or leaves the workspace by construction. Object goals may
    share a cell with a robot or another object's start (allowed)."""
    nx, ny = draw(st.integers(3, 6)), draw(st.integers(3, 6))
    cells = draw(st.permutations([(i + 0.5, j + 0.5) for i in range(nx) for j in range(ny)]))
    n_obs = draw(st.integers(0, 3))
    n_rob = draw(st.integers(1, 3))
    n_obj = draw(st.integers(1, 2))
    obs_cells, rob_cells = cells[:n_obs], cells[n_obs : n_obs + n_rob]
    start_cells = cells[n_obs + n_rob : n_obs + n_rob + n_obj]
    free = cells[n_obs:]
    goal_cells = draw(st.permutations(free))[:n_obj]  # goals: distinct, not on obstacles
    objects = []
    for sc, gc in zip(start_cells, goal_cells, strict=True):
        d = draw(shape_dicts(False, (0.0, 0.0)))
        d["start"] = [sc[0], sc[1], draw(angles)]
        d["goal"] = [gc[0], gc[1], draw(angles)]
        objects.append(d)
    return {
        "format": "lamp-scene/1",
        "name": draw(st.text(max_size=10)),
        "workspace": [float(nx), float(ny)],
        "robots": {"radius": draw(st.floats(0.01, 0.45)), "starts": [list(c) for c in rob_cells]},
        "obstacles": [draw(shape_dicts(True, c)) for c in obs_cells],
        "objects": objects,
    }


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(d=valid_scene_dicts())
def test_random_valid_scenes_load_and_round_trip(d: dict) -> None:
    scene = scene_from_dict(d)
    assert isinstance(scene, Scene)
    assert scene_from_dict(scene.to_dict()) == scene
    assert scene_from_dict(json.loads(json.dumps(scene.to_dict()))) == scene
    assert scene_from_dict(yaml.safe_load(yaml.safe_dump(scene.to_dict()))) == scene


# --------------------------------------------------------------------------- corruption fuzzing


def paths_of(node: Any, prefix: tuple = ()) -> list[tuple]:
    """All paths to nodes below the root (keys for mappings, indices for lists)."""
    out: list[tuple] = []
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for k, v in items:
        out.append((*prefix, k))
        out.extend(paths_of(v, (*prefix, k)))
    return out


def get(d: Any, path: tuple) -> Any:
    for k in path:
        d = d[k]
    return d


weird_values = st.one_of(
    st.none(),
    st.booleans(),
    st.text(max_size=5),
    st.integers(-(10**400), 10**400),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([float("nan"), float("inf"), -float("inf"), -1.0, 0.0, -1e-12, 1e300]),
    st.lists(st.floats(-10, 10), max_size=4),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)


def is_float_sized(value: Any) -> bool:
    """A number that float arithmetic accepts (an earlier corruption may have put 10**400 here)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    return isinstance(value, float) or abs(value) < 2**1000


@st.composite
def corrupted(draw: st.DrawFn) -> Any:
    """A valid scene dict after 1-3 random corruptions."""
    d = copy.deepcopy(draw(st.sampled_from([_VALID, _MINIMAL])))
    for _ in range(draw(st.integers(1, 3))):
        paths = paths_of(d)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent, key = get(d, path[:-1]), path[-1]
        op = draw(st.sampled_from(["delete", "replace", "scale", "unknown", "move", "truncate"]))
        value = parent[key]
        if op == "delete":
            del parent[key]
        elif op == "replace":
            parent[key] = draw(weird_values)
        elif op == "scale" and is_float_sized(value):
            parent[key] = value * draw(st.sampled_from([-1.0, 0.0, 1e9, float("nan"), 1.5]))
        elif op == "unknown" and isinstance(value, dict):
            value[draw(st.text(min_size=1, max_size=6))] = draw(weird_values)
        elif op == "move" and isinstance(value, list) and value and is_float_sized(value[0]):
            value[0] = value[0] + draw(st.floats(-5.0, 5.0))
        elif op == "truncate" and isinstance(value, list):
            del value[draw(st.integers(0, len(value))) :]
    return d


def assert_only_scene_error(load: Callable[[], Scene], label: str) -> None:
    try:
        scene = load()
    except SceneError as exc:
        msg = str(exc)
        assert msg.startswith(f"{label}: "), msg
        assert _UNEXPECTED not in msg, msg
    else:  # the corruption happened to keep the scene valid
        assert scene_from_dict(scene.to_dict()) == scene


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


@settings(max_examples=300, deadline=None)
@given(d=corrupted())
def test_corrupted_dicts_raise_only_scene_error(d: Any) -> None:
    assert_only_scene_error(lambda: scene_from_dict(d), "<dict>")


@settings(max_examples=100, deadline=None)
@given(d=corrupted(), as_json=st.booleans())
def test_corrupted_files_raise_only_scene_error(fuzz_dir: Path, d: Any, as_json: bool) -> None:
    path = fuzz_dir / ("c.json" if as_json else "c.yaml")
    try:
        text = json.dumps(d) if as_json else yaml.safe_dump(d)
    except (ValueError, OverflowError):  # e.g. JSON cannot hold 10**400 as a float
        return
    path.write_text(text)
    assert_only_scene_error(lambda: load_scene(path), str(path))


@settings(max_examples=150, deadline=None)
@given(
    blob=st.one_of(
        st.binary(max_size=200),
        st.text(max_size=200),
        st.text(alphabet="[]{}:,-&*!|>'\"#%@ \n\t.0123456789abcdefnulltrue", max_size=200),
    ),
    suffix=st.sampled_from([".yaml", ".yml", ".json", ""]),
)
def test_random_bytes_raise_only_scene_error(fuzz_dir: Path, blob: bytes | str, suffix: str) -> None:
    path = fuzz_dir / f"b{suffix}"
    path.write_bytes(blob if isinstance(blob, bytes) else blob.encode("utf-8", "surrogatepass"))
    assert_only_scene_error(lambda: load_scene(path), str(path))


@settings(max_examples=60, deadline=None)
@given(d=corrupted(), data=st.data())
def test_yaml_text_corruption(fuzz_dir: Path, d: Any, data: st.DataObject) -> None:
    """YAML text of a (corrupted) scene with a random slice replaced by random characters."""
    try:
        text = yaml.safe_dump(d)
    except ValueError:
        return
    i = data.draw(st.integers(0, len(text)))
    j = data.draw(st.integers(i, min(len(text), i + 20)))
    text = text[:i] + data.draw(st.text(alphabet="[]{}:,-&*!|>'\" #\n\t.0e\x00", max_size=3)) + text[j:]
    path = fuzz_dir / "t.yaml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    assert_only_scene_error(lambda: load_scene(path), str(path))


def test_a_workspace_too_large_is_refused_by_name():
    from lamp.scene.loader import MAX_WORKSPACE_SIDE

    d = json.loads((DATA / "minimal.json").read_text())
    d["workspace"] = [1e6, 1e6]
    with pytest.raises(SceneError, match=r"huge.json: workspace: sides up to 200 m") as err:
        scene_from_dict(d, source="huge.json")
    assert err.value.field == "workspace"
    d["workspace"] = [MAX_WORKSPACE_SIDE, 2.0]
    assert scene_from_dict(d).workspace == (MAX_WORKSPACE_SIDE, 2.0)
