"""The live page of ``lamp serve`` in a real headless Chromium (as the replay viewer's
tests drive it, ``tests/browser.py``): a real service (fleet and server in this process,
at twice wall pace) draws its robots as they move, a click on the map picks a goal, the
form posts it, and the task list shows it queued, then done.

CI installs Chromium and sets ``LAMP_REQUIRE_BROWSER=1``, so there a missing browser
fails these tests; locally they are skipped only when no Chromium binary is found.
"""

from __future__ import annotations

import json
import os
import time

import pytest
from browser import INSTALL_HINT, Browser, find_chromium

from lamp.manip import GeometricProposer
from lamp.pipeline import RunRequest
from lamp.scene import scene_from_dict
from lamp.serve.feed import LiveFeed
from lamp.serve.page import live_page
from lamp.serve.service import Service, listen

TINY = {
    "format": "lamp-scene/1", "name": "tiny", "workspace": [2.2, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [{"type": "rectangle", "center": [1.9, 0.4], "size": [0.2, 0.3]}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                 "goal": [1.2, 1.0, 0.0]}],
}
CHROMIUM = find_chromium()
TOKEN = "page-token"


@pytest.fixture(scope="module")
def browser():
    if CHROMIUM is None:
        if os.environ.get("LAMP_REQUIRE_BROWSER"):
            pytest.fail(INSTALL_HINT)
        pytest.skip(INSTALL_HINT)
    with Browser(CHROMIUM, width=1100, height=700) as b:
        yield b


def shown(b: Browser) -> dict:
    d = json.loads(b.evaluate("JSON.stringify(document.getElementById('state').dataset)"))
    for key in ("robots", "objects", "tasks", "view"):
        d[key] = json.loads(d.get(key, "null"))
    d["time"] = float(d["time"])
    return d


def until(b: Browser, what, timeout: float = 600.0, every: float = 0.05):
    """Poll ``what(shown(b))`` until it is truthy (the service's own pace decides how
    long; the generous timeout only ends a hung run)."""
    end = time.monotonic() + timeout
    while True:
        got = what(shown(b))
        if got:
            return got
        assert time.monotonic() < end, f"timed out; the page shows {shown(b)}"
        time.sleep(every)


def test_the_page_is_self_contained():
    page = live_page(scene_from_dict(TINY))
    for ref in ("src=", "href=", "url("):
        assert ref not in page
    assert "__LAMP_" not in page


def test_the_live_page_draws_the_robots_moving_and_posts_a_task(browser):
    scene = scene_from_dict(TINY)
    request = RunRequest.build(scene, "lazy", 0, model=GeometricProposer(), schedule="concurrent")
    feed = LiveFeed(request.scene, realtime=2.0)
    service = Service(request, feed, listen("127.0.0.1", 0), token=TOKEN)
    service.start()
    try:
        browser.open(service.url + f"?token={TOKEN}")
        first = until(browser, lambda s: s if s["tasks"] else None)
        assert first["tasks"] == [[0, first["tasks"][0][1]]]  # the object's own goal
        # the robots move: the page shows several distinct placements over time
        seen = set()
        until(browser, lambda s: seen.add(json.dumps(s["robots"])) or len(seen) >= 4)
        # the wheel zooms about the cursor, "fit" shows the whole workspace again
        before = shown(browser)["view"]
        browser.mouse("mouseWheel", 300, 300, deltaX=0, deltaY=-300)
        assert until(browser, lambda s: s["view"]["scale"] > 1.2 * before["scale"])
        browser.evaluate("document.getElementById('fit').click()")
        assert until(browser, lambda s: s["view"] == before)
        # a click on the map picks the goal, the form posts it
        view = shown(browser)["view"]
        x, y = 1.6, 1.5
        left, top = browser.evaluate("(() => { const r = document.getElementById('view')"
                                     ".getBoundingClientRect(); return [r.left, r.top]; })()")
        px, py = left + view["ox"] + view["scale"] * x, top + view["oy"] - view["scale"] * y
        browser.mouse("mousePressed", px, py, button="left", clickCount=1)
        browser.mouse("mouseReleased", px, py, button="left", clickCount=1)
        picked = browser.evaluate("[document.getElementById('f-x').value, "
                                  "document.getElementById('f-y').value]")
        assert abs(float(picked[0]) - x) < 0.01 and abs(float(picked[1]) - y) < 0.01
        browser.evaluate("document.getElementById('f-theta').value = '0.8'")
        browser.evaluate("document.getElementById('f-send').click()")
        until(browser, lambda s: [1, "queued"] in s["tasks"] or [1, "active"] in s["tasks"]
              or [1, "done"] in s["tasks"])
        assert "task 1 queued" in browser.evaluate("document.getElementById('message').textContent")
        rows = browser.evaluate("document.querySelectorAll('#tasks tbody tr').length")
        assert rows == 2
        done = until(browser, lambda s: s if [1, "done"] in s["tasks"] else None)
        pose = done["objects"][0]
        assert abs(pose[0] - x) < 0.1 and abs(pose[1] - y) < 0.1
        # a bad post is shown with the field it names
        browser.evaluate("document.getElementById('f-x').value = '9'")
        browser.evaluate("document.getElementById('f-send').click()")
        end = time.monotonic() + 60
        while "goal:" not in browser.evaluate("document.getElementById('message').textContent"):
            assert time.monotonic() < end
            time.sleep(0.05)
        # a third task, then the stop: the page shows the service stopped and the task
        # the stop ended (failed, or done if the fleet was quick), as result.json has it
        browser.evaluate("document.getElementById('f-x').value = '0.8'")
        browser.evaluate("document.getElementById('f-send').click()")
        until(browser, lambda s: any(t[0] == 2 for t in s["tasks"]))
        result = service.finish()
        last = result.to_dict()["tasks"][2]["status"]
        final = until(browser, lambda s: s if [2, last] in s["tasks"] else None)
        assert "stopped" in browser.evaluate("document.getElementById('clock').textContent")
    finally:
        result = service.finish()
        service.close()
    assert [t["status"] for t in result.to_dict()["tasks"]][:2] == ["done", "done"]
    assert final["tasks"] == [[0, "done"], [1, "done"], [2, last]]
