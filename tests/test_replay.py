"""Tests of ``lamp.viz.replay`` and ``lamp render``: pictures drawn from recordings."""

from __future__ import annotations

import json

import imageio.v2 as iio2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.colors import to_rgb
from PIL import Image
from typer.testing import CliRunner

from lamp.cli import app
from lamp.record import Recorder, load_recording
from lamp.scene import scene_from_dict
from lamp.viz.animation import mp4_available
from lamp.viz.replay import RenderOptions, ReplayRenderer, frame_rows, render, still_row
from lamp.viz.scene_plot import ROBOT_COLOR

SCENE = {
    "format": "lamp-scene/1", "name": "tiny", "workspace": [2.2, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [{"type": "circle", "center": [1.9, 0.4], "radius": 0.15}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                 "goal": [1.45, 1.0, 0.0]}],
}
runner = CliRunner()


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A real ``lamp run --render`` folder of the tiny scene (geometric model)."""
    root = tmp_path_factory.mktemp("replay")
    (root / "tiny.json").write_text(json.dumps(SCENE))
    out = root / "run"
    res = runner.invoke(app, ["run", str(root / "tiny.json"), "--model", "geometric",
                              "--out", str(out), "--render"])
    assert res.exit_code == 0, res.output
    return out


@pytest.fixture(scope="module")
def rec(run_dir):
    return load_recording(run_dir)


def robot_pixels(renderer: ReplayRenderer, image: np.ndarray, robots: np.ndarray) -> np.ndarray:
    """The pixel of ``image`` at each robot centre."""
    h = image.shape[0]
    xy = renderer.ax.transData.transform(robots)
    return np.array([image[int(round(h - y)), int(round(x))] for x, y in xy])


def test_render_of_a_recording_is_what_the_run_drew(run_dir, tmp_path):
    """``lamp render`` of the saved recording writes the same GIF as the live run."""
    res = runner.invoke(app, ["render", str(run_dir), "--out", str(tmp_path / "again.gif")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "again.gif").read_bytes() == (run_dir / "run.gif").read_bytes()


def test_still_shows_the_robots_where_the_recording_has_them(rec):
    rend = ReplayRenderer(rec, RenderOptions(size=500))
    robot = np.array(to_rgb(ROBOT_COLOR)) * 255
    for k in sorted({0, rec.n_segments // 2, rec.n_segments - 1}):
        row = still_row(rec, k)
        image = rend.render(row, k)
        robots = rec.arrays["robots"][row]
        assert np.abs(robot_pixels(rend, image, robots) - robot).max() <= 12
        assert f"segment {k + 1}/{rec.n_segments}" in rend.clock.get_text()
        assert f"t = {rec.arrays['times'][row]:7.2f} s" in rend.clock.get_text()
    assert "success" in rend.title.get_text() and "lazy" in rend.title.get_text()


def test_png_gif_mp4_files(rec, tmp_path):
    still = render(rec, tmp_path / "s.png", at=1, size=300)
    img = np.asarray(Image.open(still.path))
    assert max(img.shape[:2]) == 300 and still.frames == 1
    gif = render(rec, tmp_path / "r.gif", fps=10, speed=8.0, size=240)
    rows = frame_rows(rec, RenderOptions(fps=10, speed=8.0))
    assert gif.frames == len(rows)
    with Image.open(gif.path) as im:
        assert im.n_frames >= len(set(rows.tolist())) - 1  # identical neighbours may merge
    if mp4_available():
        mp4 = render(rec, tmp_path / "r.mp4", fps=10, speed=8.0, size=240)
        reader = iio2.get_reader(mp4.path, format="FFMPEG")
        try:
            assert sum(1 for _ in reader) == len(rows)
        finally:
            reader.close()


@settings(max_examples=30, deadline=None)
@given(fps=st.floats(1, 60), speed=st.one_of(st.none(), st.floats(0.1, 50)))
def test_frame_rows_follow_the_clock(rec, fps, speed):
    """Frame j shows the last row at or before simulated time j * speed / fps; the final
    state closes the video."""
    opt = RenderOptions(fps=fps, speed=speed)
    rows = frame_rows(rec, opt)
    times = rec.arrays["times"]
    used = speed or max(1.0, times[-1] / 20.0)
    moving = rows[: len(rows) - max(1, round(fps))]
    t = np.arange(len(moving)) * used / fps
    assert np.all(times[moving] <= t + 1e-9)
    nxt = np.minimum(moving + 1, len(times) - 1)
    assert np.all((times[nxt] > t - 1e-9) | (moving == len(times) - 1))
    assert rows[-1] == len(times) - 1 and np.all(np.diff(rows) >= 0)


def test_robots_stay_visible_on_a_50_m_map():
    """On a 50 m map a 5 cm robot is a tenth of a pixel; it is drawn ``min_robot_px`` wide."""
    big = dict(SCENE, name="big", workspace=[50.0, 50.0],
               robots={"radius": 0.05, "starts": [[10.0, 10.0], [30.0, 20.0], [40.0, 40.0]]})
    scene = scene_from_dict(big)
    rec = Recorder(scene, 0.08).finish("lazy", 0, {"success": False, "objects": []})
    robot = np.array(to_rgb(ROBOT_COLOR)) * 255

    def robot_colored(min_px: float) -> list[int]:
        rend = ReplayRenderer(rec, RenderOptions(size=400, min_robot_px=min_px))
        image = rend.render(0).astype(float)
        counts = []
        for x, y in scene.robot_starts_array:
            px, py = rend.ax.transData.transform((x, y))
            r, c = int(image.shape[0] - py), int(px)
            window = image[r - 6 : r + 7, c - 6 : c + 7]
            counts.append(int((np.abs(window - robot).max(axis=2) <= 40).sum()))
        return counts

    assert min(robot_colored(3.0)) >= 12  # about pi * 2.5^2 px of robot blue each
    assert max(robot_colored(0.0)) == 0  # true size: nothing visible


def test_follow_camera_frames_the_moved_object(rec):
    rend = ReplayRenderer(rec, RenderOptions(size=300, follow=0.8))
    row = still_row(rec, 0)
    rend.render(row, 0)
    x0, x1 = rend.ax.get_xlim()
    y0, y1 = rend.ax.get_ylim()
    assert x1 - x0 == pytest.approx(0.8)
    ox, oy = rec.arrays["objects"][row, 0, :2]
    assert x0 <= ox <= x1 and y0 <= oy <= y1


@pytest.mark.parametrize("args, message", [
    (["--out", "x.bmp"], "--out: expected a file name ending in .gif"),
    (["--out", "x.gif", "--at", "1"], "--at: only a .png still takes --at"),
    (["--out", "x.png", "--at", "999"], "--at: segment 999 does not exist"),
    (["--out", "x.png", "--at", "0"], "--at: segment 0 does not exist"),
    (["--out", "x.gif", "--size", "10"], "--size: must be an integer in [120, 4096]"),
    (["--out", "x.gif", "--fps", "0"], "--fps: must be in (0, 60]"),
])
def test_render_bad_input_exits_2_and_writes_nothing(run_dir, tmp_path, args, message):
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    res = runner.invoke(app, ["render", str(run_dir), *args])
    assert res.exit_code == 2 and message in res.output, res.output
    assert list(tmp_path.iterdir()) == []


def test_render_without_recording_exits_2(tmp_path):
    res = runner.invoke(app, ["render", str(tmp_path), "--out", str(tmp_path / "a.gif")])
    assert res.exit_code == 2 and "recording.json: no recording here" in res.output


def test_png_at_counts_segments_as_the_pictures_do(run_dir, rec, tmp_path):
    """``--at N`` draws the end of the segment the caption calls N/G."""
    res = runner.invoke(app, ["render", str(run_dir), "--out", str(tmp_path / "a.png"),
                              "--at", "2", "--size", "300"])
    assert res.exit_code == 0, res.output
    want = render(rec, tmp_path / "b.png", at=1, size=300)
    assert np.array_equal(np.asarray(Image.open(tmp_path / "a.png")),
                          np.asarray(Image.open(want.path)))
    rend = ReplayRenderer(rec, RenderOptions(size=300))
    rend.render(still_row(rec, 1), 1)
    assert f"segment 2/{rec.n_segments}" in rend.clock.get_text()


def test_rerun_clears_stale_outputs(run_dir, tmp_path):
    """A run removes the outputs an earlier run left that it does not write itself."""
    out = tmp_path / "run"
    out.mkdir()
    for name in ("run.gif", "replay.html", "result.json", "notes.txt"):
        (out / name).write_text("old")
    res = runner.invoke(app, ["run", str(run_dir.parent / "tiny.json"), "--model",
                              "geometric", "--out", str(out)])
    assert res.exit_code == 0, res.output
    names = sorted(p.name for p in out.iterdir())
    assert names == ["notes.txt", "recording.json", "recording.npz", "result.json"]
    assert json.loads((out / "result.json").read_text())["scene"] == "tiny"
    assert "removed" in res.output and "run.gif" in res.output
    assert load_recording(out).n_segments == json.loads((out / "result.json").read_text())[
        "segments"]


def test_run_html_writes_the_viewer_of_its_recording(run_dir, tmp_path):
    from lamp.viz.replay_html import viewer_html

    out = tmp_path / "run"
    res = runner.invoke(app, ["run", str(run_dir.parent / "tiny.json"), "--model",
                              "geometric", "--out", str(out), "--html"])
    assert res.exit_code == 0, res.output
    assert (out / "replay.html").read_text() == viewer_html(load_recording(out))
    assert not (out / "run.gif").exists()


def test_mp4_without_ffmpeg_exits_2_saying_what_to_install(run_dir, tmp_path, monkeypatch):
    import lamp.viz.replay as replay

    monkeypatch.setattr(replay, "mp4_available", lambda: False)  # as without imageio-ffmpeg
    res = runner.invoke(app, ["render", str(run_dir), "--out", str(tmp_path / "r.mp4")])
    assert res.exit_code == 2 and "pip install 'lamp[video]'" in res.output, res.output
    assert list(tmp_path.iterdir()) == []


def test_run_into_a_file_exits_2_before_planning(run_dir, tmp_path):
    blocker = tmp_path / "taken"
    blocker.write_text("not a folder")
    res = runner.invoke(app, ["run", str(run_dir.parent / "tiny.json"), "--model",
                              "geometric", "--out", str(blocker)])
    assert res.exit_code == 2 and "exists and is not a folder" in res.output, res.output
    assert blocker.read_text() == "not a folder"


def test_mcap_export_holds_the_recorded_run(run_dir, rec, tmp_path):
    """Every row's robots and objects, every segment and the static scene, in time order."""
    from mcap.reader import make_reader

    res = runner.invoke(app, ["render", str(run_dir), "--out", str(tmp_path / "run.mcap")])
    assert res.exit_code == 0, res.output
    by_topic: dict[str, list] = {}
    last = -1
    with open(tmp_path / "run.mcap", "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert channel.message_encoding == "json" and schema.encoding == "jsonschema"
            assert message.log_time >= last
            last = message.log_time
            by_topic.setdefault(channel.topic, []).append(
                (message.log_time, schema.name, json.loads(message.data)))
    a = rec.arrays
    robots = by_topic["/robots"]
    assert len(robots) == rec.n_rows == len(by_topic["/objects"])
    for row, (t, name, msg) in enumerate(robots):
        assert name == "lamp.RobotPositions"
        assert msg["positions"] == a["robots"][row].astype(float).tolist()
        assert t == round(a["times"][row] * 1e9)
    assert [m["index"] for _, _, m in by_topic["/segments"]] == list(range(rec.n_segments))
    static = by_topic["/scene"][0][2]["entities"]
    assert {e["id"] for e in static} == {"workspace", "obstacle-0", "goal-0"}
    last_scene = by_topic["/scene"][-1][2]["entities"]
    spheres = next(e for e in last_scene if e["id"] == "robots")["spheres"]
    assert [[s["pose"]["position"]["x"], s["pose"]["position"]["y"]] for s in spheres] == (
        a["robots"][-1].astype(float).tolist())
    assert len(by_topic["/plan"]) == len({int(p) for p in a["segment_plan"]})


def test_mcap_without_the_package_exits_2_saying_what_to_install(run_dir, tmp_path,
                                                                 monkeypatch):
    import lamp.viz.replay_mcap as replay_mcap

    monkeypatch.setattr(replay_mcap, "mcap_available", lambda: False)
    res = runner.invoke(app, ["render", str(run_dir), "--out", str(tmp_path / "r.mcap")])
    assert res.exit_code == 2 and "pip install 'lamp[foxglove]'" in res.output, res.output
    assert list(tmp_path.iterdir()) == []
