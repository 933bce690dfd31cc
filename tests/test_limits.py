"""Shapes the planners or the simulator cannot serve are refused before anything runs, naming
the field and the limit; randomly mutated scene files end in exit 0 or 2, never 1."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from lamp.cli import app
from lamp.geometry.shapes import narrowest_width
from lamp.pipeline import RunRequest
from lamp.planners.limits import MIN_OBJECT_WIDTH, MIN_OBSTACLE_WIDTH, check_scene_limits
from lamp.scene import SceneError, scene_from_dict
from lamp.scene.model import Polygon

BASE = {
    "format": "lamp-scene/1", "name": "lim", "workspace": [2.2, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [{"type": "rectangle", "center": [1.8, 1.7], "size": [0.3, 0.1]}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                 "goal": [1.15, 1.0, 0.0]}],
}


def _brute_width(points: np.ndarray) -> float:
    """The least projection extent over 20 000 directions: at least the true width, and
    at most diameter * pi / 20000 above it (a direction within pi / 20000 of the best)."""
    angles = np.linspace(0.0, np.pi, 20000, endpoint=False)
    dirs = np.column_stack([np.cos(angles), np.sin(angles)])
    proj = points @ dirs.T
    return float((proj.max(axis=0) - proj.min(axis=0)).min())


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1)), min_size=3, max_size=9))
def test_narrowest_width_matches_brute_force(pts):
    arr = np.asarray(pts, float)
    hull = shapely.MultiPoint(arr).convex_hull
    if hull.geom_type != "Polygon" or hull.area < 1e-3:
        return
    ring = np.asarray(hull.exterior.coords)[:-1]
    got = narrowest_width(Polygon(tuple(map(tuple, ring))))
    want = _brute_width(ring)
    diameter = float(np.max(np.hypot(*(ring[:, None] - ring[None]).transpose(2, 0, 1))))
    assert want - diameter * np.pi / 20000 - 1e-9 <= got <= want + 1e-9


@pytest.mark.parametrize(("path", "value", "field", "limit"), [
    (("objects", 0, "size"), [0.4, 1e-12], "objects[0].size", MIN_OBJECT_WIDTH),
    (("objects", 0, "size"), [0.015, 0.3], "objects[0].size", MIN_OBJECT_WIDTH),
    (("obstacles", 0, "size"), [0.3, 0.001], "obstacles[0].size", MIN_OBSTACLE_WIDTH),
])
def test_thin_shapes_are_refused_naming_field_and_limit(tmp_path, path, value, field, limit):
    d = copy.deepcopy(BASE)
    d[path[0]][path[1]][path[2]] = value
    scene = scene_from_dict(d)  # valid scene format
    with pytest.raises(SceneError, match=rf"{field.replace('[', '.').replace(']', '.')}: .* at "
                                         rf"least {limit:g} m across"):
        check_scene_limits(scene)
    with pytest.raises(SceneError, match=field.replace("[", r"\[").replace("]", r"\]")):
        RunRequest(scene, "lazy", model="geometric")
    f = tmp_path / "thin.json"
    f.write_text(json.dumps(d))
    runner = CliRunner()
    res = runner.invoke(app, ["run", str(f), "-o", str(tmp_path / "o"), "-m", "geometric"])
    assert res.exit_code == 2 and field in res.stderr and not (tmp_path / "o").exists()
    res = runner.invoke(app, ["validate", str(f)])
    assert res.exit_code == 2 and field in res.output
    assert runner.invoke(app, ["validate", str(f), "--model", "any"]).exit_code == 0


def test_the_suites_are_within_the_limits():
    from lamp.suites.registry import SUITES, suite_scenes

    for family in SUITES:
        for scene in suite_scenes(family):
            check_scene_limits(scene)


# ------------------------------------------------------------ mutated files: exit 0 or 2
_PATHS = [("workspace", 0), ("robots", "radius"), ("robots", "starts", 0, 0),
          ("robots", "speed"), ("obstacles", 0, "size", 1), ("obstacles", 0, "center"),
          ("objects", 0, "size", 0), ("objects", 0, "size", 1), ("objects", 0, "start", 2),
          ("objects", 0, "goal", 0), ("objects", 0, "goal"), ("objects", 0, "mass"),
          ("physics",), ("name",), ("objects", 0, "type")]
_VALUES = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.integers(-5, 5),
    st.sampled_from([0, 0.0, -1.0, 1e-12, 1e12, "x", None, True, [], {}, [1, 2], [0.0, 0.0, 0.0],
                     "polygon", "circle", {"contact_friction": 9}]))


def _has(node, key) -> bool:
    """Whether ``node[key]`` exists (a mapping's key or a list's index)."""
    if isinstance(node, dict):
        return isinstance(key, str)
    return isinstance(node, list) and isinstance(key, int) and key < len(node)


def _set(d, path, value):
    """``d[path] = value`` where the path still leads somewhere (an earlier mutation may
    have replaced a container on it)."""
    node = d
    for key in path[:-1]:
        if not (_has(node, key) and (isinstance(node, list) or key in node)):
            return
        node = node[key]
    if _has(node, path[-1]):
        node[path[-1]] = value


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(_PATHS), _VALUES), min_size=1, max_size=3))
def test_mutated_scene_files_end_in_exit_0_or_2(tmp_path, mutations):
    d = copy.deepcopy(BASE)
    for path, value in mutations:
        _set(d, path, value)
    f = tmp_path / "m.json"
    f.write_text(json.dumps(d))
    res = CliRunner().invoke(app, ["run", str(f), "-o", str(tmp_path / "o"), "-m", "geometric",
                                   "-q", "--planning-limit", "5", "--max-segments", "3"])
    assert res.exit_code in (0, 2), (d, res.output, res.exception)
