"""Segment limits: the paper's 100 on its benchmark suites, scaled with the task elsewhere."""

from __future__ import annotations

import json
import math
from pathlib import Path

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

DATA = Path(__file__).parent / "data"


@given(distance=st.floats(0.0, 500.0), fixed=st.none() | st.integers(1, 10_000))
def test_segment_limit_is_fixed_or_grows_with_the_distance(distance, fixed):
    got = segment_limit(fixed, distance)
    if fixed is not None:
        assert got == fixed
    else:
        assert got >= PAPER_MAX_SEGMENTS and got >= SEGMENTS_PER_METRE * distance - 1e-6
        assert got == max(PAPER_MAX_SEGMENTS, math.ceil(SEGMENTS_PER_METRE * distance - 1e-9))


def test_a_50_m_route_gets_room():
    assert segment_limit(None, 69.0) == 2070
    assert segment_limit(None, 2.0) == PAPER_MAX_SEGMENTS


@pytest.mark.parametrize("bad", [0, -3, 2.5, True])
def test_config_refuses_bad_limits(bad):
    with pytest.raises(ValueError, match="max_segments"):
        PlannerConfig(max_segments=bad)
    with pytest.raises(ValueError, match="long_push_length"):
        PlannerConfig(long_push_length=-1.0)


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
