"""Segment limits: the paper's 100 on its benchmark suites, scaled with the task elsewhere."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from typer.testing import CliRunner

from lamp.bench.jobs import enumerate_jobs, load_suite
from lamp.cli import app
from lamp.planners.config import (
    PAPER_MAX_SEGMENTS,
    SEGMENTS_PER_METRE,
    PlannerConfig,
    segment_limit,
)
from lamp.planners.task import route_distance
from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, SceneObject

DATA = Path(__file__).parent / "data"


@given(distance=st.floats(0.0, 500.0), fixed=st.none() | st.integers(1, 10_000))
def test_segment_limit_is_fixed_or_grows_with_the_distance(distance, fixed):
    got = segment_limit(fixed, distance)
    if fixed is not None:
        assert got == fixed
    else:
        assert got >= PAPER_MAX_SEGMENTS and got >= SEGMENTS_PER_METRE * distance - 1e-6
        assert got == max(PAPER_MAX_SEGMENTS, math.ceil(SEGMENTS_PER_METRE * distance - 1e-9))


def test_a_distance_function_is_asked_only_when_the_limit_scales():
    def distance() -> float:
        asked.append(1)
        return 7.0

    asked: list[int] = []
    assert segment_limit(42, distance) == 42 and asked == []
    assert segment_limit(None, distance) == 210 and asked == [1]


def test_the_route_around_a_wall_sets_the_limit():
    """``route_distance``: the straight line on an open map, the way round a wall when
    one stands between (at least its two legs), the straight line again when the wall
    cuts the map (no route: the limit does not guess)."""
    def scene(wall_height: float) -> Scene:
        wall = Obstacle(Rectangle((0.1, wall_height)), (2.0, wall_height / 2, 0.0))
        return Scene(name="wall", workspace=(4.0, 2.0), robot_radius=0.05, robot_starts=((0.3, 0.3),),
                     objects=(SceneObject(Circle(0.1), (1.0, 0.5, 0.0), (3.0, 0.5, 0.0)),),
                     obstacles=(wall,) if wall_height else ())

    start = np.array([1.0, 0.5, 0.0])
    assert route_distance(scene(0.0), 0, start, 0.1) == pytest.approx(2.0, abs=1e-9)
    round_wall = route_distance(scene(1.6), 0, start, 0.1)
    assert 2 * math.hypot(1.0, 1.1) - 0.1 <= round_wall <= 3.6
    assert route_distance(scene(2.0), 0, start, 0.1) == pytest.approx(2.0, abs=1e-9)


def test_a_50_m_route_gets_room():
    assert segment_limit(None, 69.0) == 2070
    assert segment_limit(None, 2.0) == PAPER_MAX_SEGMENTS


@pytest.mark.parametrize("bad", [0, -3, 2.5, True])
def test_config_refuses_bad_limits(bad):
    with pytest.raises(ValueError, match="max_segments"):
        PlannerConfig.of(max_segments=bad)
    with pytest.raises(ValueError, match="long_push_length"):
        PlannerConfig.of(long_push_length=-1.0)


def test_bench_keeps_the_paper_limit_on_builtin_suites_only(tmp_path):
    (tmp_path / "mine.json").write_text((DATA / "minimal.json").read_text())
    builtin = enumerate_jobs([load_suite("random")], ["lazy"], [0], scenes_per_suite=1)
    folder = enumerate_jobs([load_suite(str(tmp_path))], ["lazy"], [0])
    assert [j.max_segments for j in builtin] == [PAPER_MAX_SEGMENTS]
    assert [j.max_segments for j in folder] == [None]


def test_lamp_run_max_segments(tmp_path):
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(DATA / "spec_example.yaml"), "--model", "geometric",
                                   "--max-segments", "1", "--out", str(out), "-q"])
    assert res.exit_code == 0, res.output
    result = json.loads((out / "result.json").read_text())
    assert all(o["segments"] <= 1 for o in result["objects"])
    assert "segment limit reached (1)" in result["objects"][0]["failure_reason"]
    res = CliRunner().invoke(app, ["run", str(DATA / "spec_example.yaml"), "--max-segments", "0",
                                   "--out", str(tmp_path / "x")])
    assert res.exit_code == 2 and "max-segments" in res.output
