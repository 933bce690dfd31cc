"""``lamp serve`` under load: GET /state latency and the simulation's pace while a fleet
works, without and with 100 queued tasks.

Run: ``python benchmarks/bench_serve.py [--scene fleet-02] [--realtime 1] [--seconds 20]
[--tasks 100] [--rate 50] [--model learned] [--still docs/images/serve.png]``.

It starts ``lamp serve SCENE --port 0`` in its own process (the default scene,
``fleet-02`` of the built-in ``fleet`` family, has 24 robots and 8 loads), waits for the
fleet's clock to move, then for ``--seconds`` polls ``GET /state`` ``--rate`` times a
second over one kept-alive connection (phase 1: the scene's own goals); posts one more
task per object and polls again (phase 2: every object busy, a short queue); posts the
rest of ``--tasks`` tasks and polls again (phase 3: the long queue). The tasks send each
object in turn back to its start, then to its goal again, and so on: poses the scene
itself certifies. Per phase it prints the latency median, 95th percentile and maximum,
and the pace: simulated seconds per wall second over the phase, from ``time_s``
(``--realtime`` caps it; below it, the planners were the bottleneck). ``--still`` also
saves a screenshot of the live page (headless Chromium, ``tests/browser.py``) at the start
of phase 2 (the README's). The service is stopped with SIGTERM at the end and its
result.json read back (tasks done by then). Last, in this process, the service's own
cost per fleet event with no task and with ``--tasks`` tasks queued (``event_cost``).
"""

from __future__ import annotations

import argparse
import http.client
import json
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from lamp.suites.registry import resolve_scene

ROOT = Path(__file__).resolve().parents[1]


def start(scene: str, realtime: float, model: str, out: Path) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "lamp.cli", "serve", scene, "--port", "0", "--realtime",
         str(realtime), "-m", model, "-o", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    line = proc.stdout.readline()
    found = re.search(r"http://127\.0\.0\.1:(\d+)", line)
    if not found:
        proc.kill()
        raise SystemExit(f"lamp serve did not start: {line}{proc.stdout.read()}")
    return proc, found.group(1)


def get(conn: http.client.HTTPConnection, path: str) -> tuple[float, dict]:
    t0 = time.perf_counter()
    conn.request("GET", path)
    r = conn.getresponse()
    body = r.read()
    return time.perf_counter() - t0, json.loads(body)


def phase(port: str, seconds: float, rate: float) -> dict:
    """Poll GET /state for ``seconds``: latencies (ms) and the pace."""
    conn = http.client.HTTPConnection("127.0.0.1", int(port), timeout=60)
    lat, first, last = [], None, None
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        dt, state = get(conn, "/state")
        now = (time.monotonic(), state["time_s"])
        first = first or now
        last = now
        lat.append(dt * 1e3)
        time.sleep(max(0.0, 1.0 / rate - dt))
    conn.close()
    a = np.array(lat)
    return {"requests": len(a), "median_ms": float(np.median(a)),
            "p95_ms": float(np.percentile(a, 95)), "max_ms": float(a.max()),
            "pace": (last[1] - first[1]) / max(last[0] - first[0], 1e-9),
            "tasks": len(state["tasks"]),
            "queued": sum(t["status"] == "queued" for t in state["tasks"])}


def post_tasks(port: str, scene_name: str, first: int, n: int) -> list[float]:
    """Post tasks ``first``..``n - 1`` of the sequence (module docstring); their latencies
    (ms)."""
    scene = resolve_scene(scene_name)
    conn = http.client.HTTPConnection("127.0.0.1", int(port), timeout=60)
    lat = []
    for i in range(first, n):
        k = i % len(scene.objects)
        rnd = i // len(scene.objects)
        pose = scene.objects[k].start if rnd % 2 == 0 else scene.objects[k].goal
        body = json.dumps({"object": k, "goal": [float(v) for v in pose]})
        t0 = time.perf_counter()
        conn.request("POST", "/tasks", body, {"Content-Type": "application/json"})
        r = conn.getresponse()
        r.read()
        lat.append((time.perf_counter() - t0) * 1e3)
        if r.status != 201:
            raise SystemExit(f"POST /tasks: {r.status}")
    conn.close()
    return lat


def event_cost(scene_name: str, queued: int, events: int = 2000) -> float:
    """Microseconds the service adds to one fleet event with ``queued`` tasks waiting:
    the feed's ``released`` through the fleet's ``TaskDesk``, an object's next task, a
    motion shown (one 0.2 s trace of every robot and object) and a ``GET /state``
    snapshot made, in this process at ``--realtime 0``."""
    from types import SimpleNamespace

    from lamp.fleet.desk import TaskDesk
    from lamp.serve.feed import LiveFeed

    scene = resolve_scene(scene_name)
    feed = LiveFeed(scene, realtime=0)
    desk = TaskDesk(feed, len(scene.objects))
    for i in range(queued):
        k = i % len(scene.objects)
        feed.post(k, scene.objects[k].start if (i // len(scene.objects)) % 2 == 0
                  else scene.objects[k].goal)
    rows = np.linspace(0.0, 0.2, 5)
    robots = np.repeat(scene.robot_starts_array[None], len(rows), axis=0)
    poses = np.repeat(scene.object_starts()[None], len(rows), axis=0)
    trace = SimpleNamespace(times=rows, robot_positions=robots, object_poses=poses)
    desk.take(0.0)
    for k in range(len(scene.objects)):  # every object busy with its first task
        desk.next_for(k)
    t0, clock = time.perf_counter(), 0.0
    for _ in range(events):
        desk.take(clock)
        desk.next_for(0)
        feed.moved(clock, trace)
        clock += 0.2
        feed.state_json()
    return (time.perf_counter() - t0) / events * 1e6


def still(port: str, path: Path) -> None:
    sys.path.insert(0, str(ROOT / "tests"))
    from browser import Browser, find_chromium

    binary = find_chromium()
    if binary is None:
        print("--still: no Chromium found")
        return
    with Browser(binary, width=1280, height=760) as b:
        b.open(f"http://127.0.0.1:{port}/")
        time.sleep(3.0)
        path.write_bytes(b.screenshot())
    print(f"wrote {path}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="fleet-02")
    ap.add_argument("--realtime", type=float, default=1.0)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--tasks", type=int, default=100)
    ap.add_argument("--rate", type=float, default=50.0, help="GET /state per second")
    ap.add_argument("--model", default="learned")
    ap.add_argument("--still", type=Path, default=None)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        proc, port = start(args.scene, args.realtime, args.model, out)
        try:
            conn = http.client.HTTPConnection("127.0.0.1", int(port), timeout=60)
            t_up = time.monotonic()
            while get(conn, "/state")[1]["time_s"] <= 0.0:  # warm-up, then the fleet
                time.sleep(0.1)
            conn.close()
            print(f"{args.scene} at --realtime {args.realtime:g}: the fleet's clock moved "
                  f"after {time.monotonic() - t_up:.1f} s")
            rows = [("scene's own goals", phase(port, args.seconds, args.rate))]
            n = len(resolve_scene(args.scene).objects)
            post_lat = post_tasks(port, args.scene, 0, n)  # one more task per object
            if args.still is not None:
                still(port, args.still)
            rows.append((f"+{n} posted", phase(port, args.seconds, args.rate)))
            post_lat += post_tasks(port, args.scene, n, args.tasks)
            rows.append((f"+{args.tasks} posted", phase(port, args.seconds, args.rate)))
        finally:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.communicate(timeout=600)  # drains the summary it prints
            except subprocess.TimeoutExpired:
                proc.kill()
        result = json.loads((out / "result.json").read_text()) if (out / "result.json").is_file() else {}
    print(f"POST /tasks x{len(post_lat)}: median {np.median(post_lat):.2f} ms, "
          f"p95 {np.percentile(post_lat, 95):.2f} ms")
    print(f"{'phase':<20} {'GETs':>5} {'median ms':>10} {'p95 ms':>8} {'max ms':>8} "
          f"{'pace (sim s/wall s)':>20} {'tasks':>6} {'queued':>7}")
    for name, r in rows:
        print(f"{name:<20} {r['requests']:>5} {r['median_ms']:>10.2f} {r['p95_ms']:>8.2f} "
              f"{r['max_ms']:>8.1f} {r['pace']:>20.3f} {r['tasks']:>6} {r['queued']:>7}")
    costs = {q: min(event_cost(args.scene, q) for _ in range(3)) for q in (0, args.tasks)}
    print("the service's own cost per fleet event (feed, desk, snapshot; best of 3): "
          + ", ".join(f"{costs[q]:.0f} us with {q} queued" for q in costs))
    life = result.get("lifelong", {})
    print(f"on stop: exit {proc.returncode}, tasks {life.get('tasks')}, done {life.get('done')}, "
          f"failed {life.get('failed')} (stopped)")


if __name__ == "__main__":
    main()
