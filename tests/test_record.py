"""Tests of ``lamp.record``: building, saving and loading recordings, and recorded real runs."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.se2 import transform_points
from lamp.planners.closed_loop import LoopPolicy, LoopRecord, SegmentEvent, run_object
from lamp.record import (
    OUTCOMES,
    Recorder,
    Recording,
    RecordingError,
    load_recording,
    save_recording,
)
from lamp.record.format import ARRAYS
from lamp.scene import scene_from_dict
from lamp.sim.simulator import Trace

SCENE = {
    "format": "lamp-scene/1", "name": "tiny", "workspace": [2.2, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                 "goal": [1.45, 1.0, 0.0]}],
}


@pytest.fixture(scope="module")
def scene():
    return scene_from_dict(SCENE)


# ------------------------------------------------------------------ synthetic segments

@st.composite
def segment_specs(draw):
    """A list of fake executed segments: (rows, contacts, push length, plan id, outcome)."""
    n = draw(st.integers(0, 6))
    return [(draw(st.integers(1, 5)), draw(st.integers(0, 3)), draw(st.integers(2, 4)),
             draw(st.integers(0, 2)), draw(st.sampled_from(OUTCOMES)), draw(st.booleans()))
            for _ in range(n)]


def fake_events(scene, specs, seed=0):
    """SegmentEvents shaped like the loop's, with random contents; consecutive segments
    with the same plan id share one plan object."""
    rng = np.random.default_rng(seed)
    robots = scene.robot_starts_array
    objects = scene.object_starts()
    events, plans, last = [], {}, None
    for g, (rows, n_contacts, horizon, plan_id, outcome, replanned) in enumerate(specs):
        r = np.concatenate([robots[None], robots + rng.normal(0, 0.1, (rows, *robots.shape))])
        o = np.concatenate([objects[None], objects + rng.normal(0, 0.1, (rows, *objects.shape))])
        robots, objects = r[-1], o[-1]
        sim_time = 0.08 * rows + 0.2  # the last row is the state after settling
        trace = Trace(np.append(np.linspace(0.0, 0.08 * (rows - 1), rows), sim_time), r, o)
        pushes = rng.normal(0, 0.2, (n_contacts, horizon, 2))
        q_from = rng.normal(1.0, 0.2, 3)
        trans = SimpleNamespace(q_from=q_from, q_to=q_from + 0.1,
                                contacts=transform_points(q_from, pushes[:, 0]),
                                pushes_local=pushes)
        if plan_id != last or plan_id not in plans:
            path = rng.normal(1.0, 0.3, (int(rng.integers(0, 5)), 3))
            plans[plan_id] = SimpleNamespace(
                object_path=path,
                verified_edges=[(a[:2], b[:2]) for a, b in zip(path[:-1], path[1:], strict=True)],
                penalised_edges=[(a, a + 0.05) for a in path[:1, :3]])
        last = plan_id
        execution = SimpleNamespace(trace=trace, sim_time=sim_time)
        events.append(SegmentEvent(0, g, trans, execution, plans[plan_id], 0.01 * g, replanned,
                                   (0.001 * g, 0.002 * g), outcome))
    return events


@settings(max_examples=40, deadline=None)
@given(specs=segment_specs(), seed=st.integers(0, 2**16))
def test_recorder_keeps_every_segment(scene, specs, seed):
    """Each segment's rows, contacts, pushes, plan and events come back as they went in."""
    events = fake_events(scene, specs, seed)
    rec = Recorder(scene, 0.08)
    for ev in events:
        rec(ev)
    r = rec.finish("lazy", 3, {"success": False})
    a = r.arrays
    assert r.n_segments == len(events)
    clock = 0.0
    for g, ev in enumerate(events):
        lo, hi = a["segment_rows"][g], a["segment_rows"][g + 1]
        tr = ev.execution.trace
        np.testing.assert_array_equal(a["robots"][lo:hi + 1], tr.robot_positions.astype("f4"))
        np.testing.assert_array_equal(a["objects"][lo:hi + 1], tr.object_poses.astype("f4"))
        np.testing.assert_allclose(a["times"][lo:hi + 1], clock + tr.times)
        clock += ev.execution.sim_time
        np.testing.assert_array_equal(r.contacts_of(g), ev.transition.contacts.astype("f4"))
        world = transform_points(ev.transition.q_from, ev.transition.pushes_local)
        assert len(r.pushes_of(g)) == len(world)
        for got, want in zip(r.pushes_of(g), world, strict=True):
            np.testing.assert_array_equal(got, want.astype("f4"))
        plan = a["segment_plan"][g]
        np.testing.assert_array_equal(r.plan_path(plan), ev.plan.object_path.astype("f4"))
        assert len(r.verified_of(plan)) == len(ev.plan.verified_edges)
        assert OUTCOMES[a["segment_outcome"][g]] == ev.outcome
        assert a["segment_replanned"][g] == ev.replanned
    # one stored plan per run of segments executing the same plan object
    changes = sum(1 for g in range(len(events))
                  if g == 0 or events[g].plan is not events[g - 1].plan)
    assert len(a["plan_object"]) == changes
    assert np.all(np.diff(a["times"]) > 0) or r.n_rows == 1


@settings(max_examples=25, deadline=None)
@given(specs=segment_specs(), seed=st.integers(0, 2**16))
def test_save_load_round_trip(scene, specs, seed, tmp_path_factory):
    """What ``load_recording`` reads is bit-identical to what ``save_recording`` wrote."""
    rec = Recorder(scene, 0.08)
    for ev in fake_events(scene, specs, seed):
        rec(ev)
    r = rec.finish("gco-ori", 7, {"success": True, "segments": len(specs)})
    out = tmp_path_factory.mktemp("rec")
    save_recording(r, out)
    back = load_recording(out)
    assert (back.scene, back.planner, back.seed, back.result, back.row_dt_s) == (
        r.scene, r.planner, r.seed, r.result, r.row_dt_s)
    for name in ARRAYS:
        assert back.arrays[name].dtype == r.arrays[name].dtype
        np.testing.assert_array_equal(back.arrays[name], r.arrays[name])
    # numpy alone reads it: the npz holds no pickles and the index says every shape
    index = json.loads((out / "recording.json").read_text())
    with np.load(out / "recording.npz", allow_pickle=False) as data:
        for name, meta in index["arrays"].items():
            assert list(data[name].shape) == meta["shape"] and str(data[name].dtype) == meta["dtype"]


@given(rows=st.lists(st.integers(0, 6), min_size=0, max_size=6), row=st.integers(0, 40))
def test_segment_of_row_matches_a_scan(scene, rows, row):
    """The segment of a row is the one whose rows (start, end] hold it (row 0: segment 0)."""
    specs = [(n, 0, 2, 0, "continue", False) for n in [max(1, k) for k in rows]]
    rec = Recorder(scene, 0.08)
    for ev in fake_events(scene, specs):
        rec(ev)
    r = rec.finish("lazy", 0, {})
    row = min(row, r.n_rows - 1)
    b = r.arrays["segment_rows"]
    want = -1 if r.n_segments == 0 else next(
        (g for g in range(r.n_segments) if b[g] < row <= b[g + 1]), 0)
    assert r.segment_of_row(row) == want


def test_recording_is_read_only(scene):
    r = Recorder(scene, 0.08).finish("lazy", 0, {})
    with pytest.raises(ValueError):
        r.arrays["robots"][0, 0, 0] = 5.0
    with pytest.raises(TypeError):
        r.arrays["robots"] = np.zeros(1)  # type: ignore[index]


def test_bad_recordings_are_refused_naming_file_and_field(scene, tmp_path):
    r = Recorder(scene, 0.08).finish("lazy", 0, {})
    with pytest.raises(RecordingError, match="no recording here"):
        load_recording(tmp_path)
    save_recording(r, tmp_path)
    index = json.loads((tmp_path / "recording.json").read_text())
    (tmp_path / "recording.json").write_text(json.dumps({**index, "format": "lamp-recording/9"}))
    with pytest.raises(RecordingError, match=r"recording.json: format: expected 'lamp-recording/1'"):
        load_recording(tmp_path)
    (tmp_path / "recording.json").write_text(json.dumps({**index, "seed": "x"}))
    with pytest.raises(RecordingError, match="seed"):
        load_recording(tmp_path)
    (tmp_path / "recording.json").write_text(json.dumps({**index, "scene": {"format": 1}}))
    with pytest.raises(RecordingError, match=r"recording.json: scene: "):
        load_recording(tmp_path)
    (tmp_path / "recording.json").write_text(json.dumps(index))
    arrays = dict(r.arrays)
    arrays["contact_offsets"] = np.array([0, 3], np.int64)  # segments: 0, so length 1
    np.savez(tmp_path / "recording.npz", **arrays)
    with pytest.raises(RecordingError, match=r"recording.npz: arrays.contact_offsets"):
        load_recording(tmp_path)
    del arrays["contact_offsets"]
    np.savez(tmp_path / "recording.npz", **arrays)
    with pytest.raises(RecordingError, match="missing arrays contact_offsets"):
        load_recording(tmp_path)
    with pytest.raises(RecordingError, match="expected dtype float32"):
        Recording({}, "lazy", 0, {}, 0.08, {**r.arrays, "robots": r.arrays["robots"].astype("f8")})


# ------------------------------------------------------------------------ real runs

@pytest.fixture(scope="module")
def proposer():
    from lamp.manip import GeometricProposer

    return GeometricProposer()


@pytest.fixture(scope="module")
def solved(scene, proposer):
    from lamp import solve

    return solve(scene, "lazy", seed=0, model=proposer)


def test_solve_returns_the_recording_of_the_run(solved):
    """The recording ends where the result says the run ended, segment for segment."""
    r, d = solved.recording, solved.to_dict()
    assert d["success"] and r.success and r.result == d
    assert r.n_segments == d["segments"] >= 1
    np.testing.assert_allclose(r.arrays["planning_time_s"], d["planning_time_s"], atol=1e-6)
    np.testing.assert_allclose(r.arrays["objects"][-1, 0], d["objects"][0]["final_pose"],
                               atol=1e-5)
    assert np.all(np.diff(r.arrays["times"]) > 0)
    # rows are the simulator's row rate (every RENDER_EVERY physics steps) or a segment end
    gaps = np.diff(r.arrays["times"])
    assert gaps.max() <= r.row_dt_s + 1e-9
    assert r.arrays["robots"].shape[1:] == (3, 2) and len(r.contacts_of(0)) >= 1
    assert r.arrays["segment_replanned"][0]  # the first segment follows the first plan


def test_recording_only_watches(scene, proposer):
    """run_object gives the same result with and without an observer."""
    from lamp.pipeline.registry import get
    from lamp.planners.lazy import LazyPlanner
    from lamp.planners.task import ManipulationTask
    from lamp.sim import Simulator

    outs, seen = [], []
    for observer in (None, seen.append):
        sim = Simulator(scene)
        task = ManipulationTask(scene, 0, scene.object_starts(), proposer,
                                get("lazy").default_config(), seed=0)
        res = run_object(task, LazyPlanner.from_task(task), LoopPolicy(True, True), sim, LoopRecord(),
                         observer=observer)
        outs.append((res.final_pose, res.segments, res.success, sim.robot_positions.tolist()))
    assert outs[0] == outs[1]
    assert [e.segment for e in seen] == list(range(outs[0][1]))
    assert all(e.execution.trace is not None for e in seen)


def test_same_seed_same_recording(scene, proposer, solved):
    from lamp import solve

    again = solve(scene, "lazy", seed=0, model=proposer).recording
    for name in ARRAYS:
        if name != "planning_time_s":  # wall-clock measurements
            np.testing.assert_array_equal(again.arrays[name], solved.recording.arrays[name])


def test_bench_job_saves_its_recording(scene, tmp_path):
    """``lamp bench --record``: a job with ``recording_to`` leaves a loadable recording of
    exactly the run its result line describes, and the line says what ``lamp check`` finds
    in it."""
    from lamp.bench.jobs import Job
    from lamp.bench.provenance import canonical_command
    from lamp.bench.runner import solve_job

    job = Job(suite="t", scene_name="tiny", scene_file="tiny.json", scene=scene,
              planner="lazy", seed=0, model="geometric", recording_to=str(tmp_path / "r"))
    result = solve_job(job)
    rec = load_recording(tmp_path / "r")
    assert "recording_error" not in result
    audit = result.pop("audit")
    assert rec.result == result and rec.n_segments == result["segments"]
    assert audit == {"ok": True, "collisions": 0, "push_lead_m": audit["push_lead_m"],
                     "push_lead_judged": False}  # sequential: measured, not judged
    assert 0.0 <= audit["push_lead_m"] < 0.1
    cmd = canonical_command(["t"], ["lazy"], seeds=1, workers=1, out=tmp_path, time_cap=9,
                            planning_limit=9, model="geometric", backend="local", scenes=None,
                            render_iros=False, job_fn="lamp.bench.runner:solve_job",
                            record=True)
    assert cmd.endswith("--record")


def test_bench_record_option_gives_every_job_its_folder(tmp_path):
    from typer.testing import CliRunner

    from lamp.cli import app

    out = tmp_path / "bench"
    res = CliRunner().invoke(app, ["bench", "--suite", "random", "--planners", "lazy,gco-var",
                                   "--scenes", "1", "--out", str(out), "--record",
                                   "--dry-run"])
    assert res.exit_code == 0, res.output
    for planner in ("lazy", "gco-var"):
        assert f"records into {out / 'recordings' / 'random'}/random-01-{planner}-s0" in res.output


def test_report_counts_the_recordings_rechecked():
    """The report's re-check table: per planner the audited runs (the newest line per job),
    those that failed, their collisions, the largest judged push lead (a lead that was
    not judged is left out) and the checks that could not run."""
    from lamp.bench.report import audit_markdown
    from lamp.bench.tables import audit_table

    def line(scene, planner, audit):
        return {"suite": "fleet", "scene": scene, "planner": planner, "seed": 0,
                "status": "ok", **({"audit": audit} if audit else {})}

    ok = {"ok": True, "collisions": 0, "push_lead_m": 0.03, "push_lead_judged": True}
    records = [
        line("a", "lazy", {**ok, "ok": False, "collisions": 5}),  # replaced by the next line
        line("a", "lazy", {**ok, "ok": False, "collisions": 2, "push_lead_m": 0.01}),
        line("b", "lazy", ok),
        line("c", "lazy", {**ok, "push_lead_m": 0.5, "push_lead_judged": False}),
        line("a", "gco-var", {"error": "ValueError: x"}),
        line("b", "gco-var", None),
    ]
    table = audit_table(records)
    assert table == {"lazy": {"runs": 3, "failed": 1, "collisions": 2, "lead": 0.03,
                              "errors": 0},
                     "gco-var": {"runs": 1, "failed": 0, "collisions": 0, "lead": None,
                                 "errors": 1}}
    md = audit_markdown(table)
    assert "| LAMP-Lazy | 3 | 1 | 2 | 0.030 | 0 |" in md and "| 1 | 0 | 0 | - | 1 |" in md
