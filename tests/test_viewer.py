"""End-to-end tests of the HTML replay viewer in a real headless Chromium.

CI installs Chromium (``.ci/run``) and sets ``LAMP_REQUIRE_BROWSER=1``, so there a missing
browser fails these tests; locally they are skipped only when no Chromium binary is found,
with a message saying how to install one.
"""

from __future__ import annotations

import io
import json
import os
import re
import time

import numpy as np
import pytest
from browser import INSTALL_HINT, Browser, find_chromium
from matplotlib.colors import to_rgb
from PIL import Image

from lamp.record import Recorder
from lamp.scene import scene_from_dict
from lamp.viz.replay_html import viewer_html, write_html
from lamp.viz.scene_plot import OBSTACLE_COLOR, ROBOT_COLOR

SCENE = {
    "format": "lamp-scene/1", "name": "tiny", "workspace": [2.2, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [{"type": "rectangle", "center": [1.9, 0.4], "size": [0.2, 0.3], "angle": 0.3}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                 "goal": [1.6, 1.5, 0.8]}],
}
CHROMIUM = find_chromium()


@pytest.fixture(scope="module")
def recording():
    from lamp import solve
    from lamp.manip import GeometricProposer

    rec = solve(scene_from_dict(SCENE), "lazy", seed=0, model=GeometricProposer()).recording
    assert rec.n_segments >= 3
    return rec


@pytest.fixture(scope="module")
def page(recording, tmp_path_factory):
    path = tmp_path_factory.mktemp("viewer") / "replay.html"
    write_html(recording, path)
    return path


@pytest.fixture(scope="module")
def browser(page):
    if CHROMIUM is None:
        if os.environ.get("LAMP_REQUIRE_BROWSER"):
            pytest.fail(INSTALL_HINT)
        pytest.skip(INSTALL_HINT)
    with Browser(CHROMIUM, width=1200, height=760) as b:
        b.open(page.as_uri())
        yield b


def state(b: Browser) -> dict:
    d = b.evaluate("JSON.stringify(document.getElementById('state').dataset)")
    d = json.loads(d)
    for key in ("robots", "objects", "view"):
        d[key] = json.loads(d[key])
    d["row"], d["segment"] = int(d["row"]), int(d["segment"])
    return d


def screenshot(b: Browser) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(b.screenshot())).convert("RGB")).astype(float)


def canvas_offset(b: Browser) -> tuple[float, float]:
    r = b.evaluate("(() => { const r = document.getElementById('view')"
                   ".getBoundingClientRect(); return [r.left, r.top]; })()")
    return float(r[0]), float(r[1])


def test_page_is_self_contained(recording):
    """No network: nothing loaded from elsewhere (no src/href attributes, no URLs in CSS)."""
    html = viewer_html(recording)
    assert not re.search(r"\b(src|href)\s*=", html, re.I)
    assert "url(" not in html and "@import" not in html
    assert "http://" not in html and "https://" not in html
    assert html.count("</script>") == 2  # the data block and the viewer script


def test_segments_show_the_recorded_positions(browser, recording):
    """Stepping the timeline with the segment buttons shows, at the end of segment k, the
    robots and objects exactly where the recording has them."""
    a = recording.arrays
    browser.evaluate("window.lampViewer.seekRow(0)")
    assert state(browser)["row"] == 0
    for k in range(recording.n_segments):
        browser.evaluate("document.getElementById('next').click()")
        s = state(browser)
        row = int(a["segment_rows"][k + 1])
        assert (s["row"], s["segment"]) == (row, k)
        assert s["robots"] == a["robots"][row].astype(float).tolist()
        assert s["objects"] == a["objects"][row].astype(float).tolist()
        assert float(s["time"]) == float(a["times"][row])
        clock = browser.evaluate("document.getElementById('clock').textContent")
        assert f"segment {k + 1}/{recording.n_segments}" in clock
        current = browser.evaluate(
            "[...document.querySelectorAll('#segments tbody tr')].findIndex("
            "tr => tr.classList.contains('current'))")
        assert current == k
    browser.evaluate("document.getElementById('prev').click()")
    assert state(browser)["segment"] == recording.n_segments - 2


def test_screenshot_has_robots_at_their_screen_positions(browser, recording):
    k = recording.n_segments // 2
    browser.evaluate(f"window.lampViewer.seekSegment({k})")
    s = state(browser)
    img = screenshot(browser)
    left, top = canvas_offset(browser)
    robot = np.array(to_rgb(ROBOT_COLOR)) * 255
    for x, y in s["robots"]:
        X, Y = browser.evaluate(f"window.lampViewer.toScreen({x}, {y})")
        pixel = img[int(top + Y), int(left + X)]
        assert np.abs(pixel - robot).max() <= 10, (x, y, pixel)
    # the obstacle is drawn in its colour at its centre
    X, Y = browser.evaluate("window.lampViewer.toScreen(1.9, 0.4)")
    obstacle = np.array(to_rgb(OBSTACLE_COLOR)) * 255
    assert np.abs(img[int(top + Y), int(left + X)] - obstacle).max() <= 10


def test_hidpi_screens_draw_at_device_resolution(page, recording):
    """At 2 device pixels per CSS pixel the canvas has twice the pixels and the robots
    are still drawn where the recording has them."""
    if CHROMIUM is None:
        pytest.skip(INSTALL_HINT)
    with Browser(CHROMIUM, width=900, height=600, scale=2.0) as b:
        b.open(page.as_uri() + "#segment=2")
        s = state(b)
        row = int(recording.arrays["segment_rows"][2])
        assert s["robots"] == recording.arrays["robots"][row].astype(float).tolist()
        size = b.evaluate("[document.getElementById('view').width, "
                          "document.getElementById('view').clientWidth]")
        assert abs(size[0] - 2 * size[1]) <= 1
        img = screenshot(b)
        left, top = canvas_offset(b)
        robot = np.array(to_rgb(ROBOT_COLOR)) * 255
        for x, y in s["robots"]:
            X, Y = b.evaluate(f"window.lampViewer.toScreen({x}, {y})")
            assert np.abs(img[int(2 * (top + Y)), int(2 * (left + X))] - robot).max() <= 10


def test_layers_toggle_what_is_drawn(browser):
    browser.evaluate("window.lampViewer.seekSegment(0)")
    before = screenshot(browser)
    browser.evaluate("document.getElementById('layer-inflated').click()")
    assert "inflated" in state(browser)["layers"].split(",")
    inflated = screenshot(browser)
    browser.evaluate("document.getElementById('layer-inflated').click()")
    browser.evaluate("document.getElementById('layer-trails').click()")
    assert "trails" not in state(browser)["layers"].split(",")
    no_trails = screenshot(browser)
    browser.evaluate("document.getElementById('layer-trails').click()")
    assert np.array_equal(screenshot(browser), before)  # toggling back restores the picture
    assert not np.array_equal(inflated, before) and not np.array_equal(no_trails, before)
    # the inflated band lies around the obstacle: a point just outside it changes
    left, top = canvas_offset(browser)
    X, Y = browser.evaluate("window.lampViewer.toScreen(1.9, 0.4 + 0.15 * Math.cos(0.3) + 0.03)")
    assert np.abs(inflated[int(top + Y), int(left + X)] - before[int(top + Y), int(left + X)]).max() > 20


def test_scrub_zoom_pan_and_play(browser, recording):
    browser.evaluate("(() => { const s = document.getElementById('scrub'); s.value = '7';"
                     "s.dispatchEvent(new Event('input')); })()")
    assert state(browser)["row"] == 7
    view0 = state(browser)["view"]
    browser.evaluate("document.getElementById('zoom-in').click()")
    view1 = state(browser)["view"]
    assert view1["scale"] == pytest.approx(1.5 * view0["scale"])
    browser.evaluate("document.getElementById('fit').click()")
    assert state(browser)["view"]["scale"] == pytest.approx(view0["scale"])
    # drag to pan, wheel to zoom: real mouse input on the canvas
    left, top = canvas_offset(browser)
    x, y = left + 300, top + 300
    browser.mouse("mousePressed", x, y, button="left", clickCount=1)
    browser.mouse("mouseMoved", x + 50, y + 30, button="left", buttons=1)
    browser.mouse("mouseReleased", x + 50, y + 30, button="left", clickCount=1)
    panned = state(browser)["view"]
    assert (panned["ox"] - view0["ox"], panned["oy"] - view0["oy"]) == pytest.approx((50, 30))
    browser.mouse("mouseWheel", x, y, deltaX=0, deltaY=-200)
    deadline = time.monotonic() + 30  # an event loop on a busy machine
    while state(browser)["view"]["scale"] == panned["scale"] and time.monotonic() < deadline:
        time.sleep(0.05)
    assert state(browser)["view"]["scale"] > panned["scale"]
    browser.evaluate("document.getElementById('fit').click()")
    browser.evaluate("window.lampViewer.seekRow(0)")
    browser.evaluate("document.getElementById('speed').value = '16';"
                     "document.getElementById('speed').dispatchEvent(new Event('change'))")
    browser.evaluate("document.getElementById('play').click()")
    deadline = time.monotonic() + 30  # an event loop on a busy machine
    while state(browser)["row"] < 5 and time.monotonic() < deadline:
        time.sleep(0.05)
    s = state(browser)
    assert s["row"] >= 5 and s["playing"] == "true"
    browser.evaluate("document.getElementById('play').click()")
    paused = state(browser)
    time.sleep(0.3)
    assert state(browser)["row"] == paused["row"] and paused["playing"] == "false"


def test_hash_opens_at_a_segment(browser, page, recording):
    browser.open("about:blank")
    browser.open(page.as_uri() + "#segment=2")  # counted from 1, as the page shows it
    s = state(browser)
    assert (s["row"], s["segment"]) == (int(recording.arrays["segment_rows"][2]), 1)
    browser.evaluate("location.hash = '#row=3'")
    deadline = time.monotonic() + 30  # an event loop on a busy machine
    while state(browser)["row"] != 3 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert state(browser)["row"] == 3


def test_viewer_of_an_empty_recording_has_no_segments():
    """A run that executed nothing still gives a page (one row, no segments)."""
    scene = scene_from_dict(SCENE)
    html = viewer_html(Recorder(scene, 0.08).finish("astar", 0, {"success": False}))
    data = json.loads(re.search(r'id="lamp-data">(.*?)</script>', html, re.S).group(1))
    assert data["n_rows"] == 1 and data["segments"] == [] and data["segment_rows"] == [0]
