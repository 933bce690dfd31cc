"""The HTTP API of ``lamp serve`` against a real uvicorn server on a free port: bad
requests each naming the field (the service keeps answering), concurrent posts, the
token rule, the body limit, and the whole command end to end (a posted task done, SIGTERM
writing result.json). The in-thread servers run without a fleet (the feed alone), so
nothing here waits on planning; the end-to-end test runs ``lamp serve`` itself."""

from __future__ import annotations

import http.client
import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import uvicorn
from typer.testing import CliRunner

from lamp.cli import app as cli_app
from lamp.scene import scene_from_dict
from lamp.serve.app import MAX_BODY, create_app
from lamp.serve.feed import LiveFeed
from lamp.serve.service import is_loopback, listen

TINY = {
    "format": "lamp-scene/1", "name": "tiny", "workspace": [2.2, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [{"type": "rectangle", "center": [1.9, 0.4], "size": [0.2, 0.3]}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                 "goal": [1.2, 1.0, 0.0]}],
}
TOKEN = "s3cret-token"


class Server:
    """A uvicorn server of ``create_app(feed, token)`` in a thread, on a free port."""

    def __init__(self, token: str | None = None) -> None:
        self.feed = LiveFeed(scene_from_dict(TINY), realtime=0)
        self.sock = listen("127.0.0.1", 0)
        self.base = f"http://127.0.0.1:{self.sock.getsockname()[1]}"
        config = uvicorn.Config(create_app(self.feed, token), log_level="warning",
                                access_log=False, lifespan="off")
        self.server = uvicorn.Server(config)
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [self.sock]},
                                       daemon=True)
        self.thread.start()
        end = time.monotonic() + 60
        while not self.server.started:
            assert time.monotonic() < end and self.thread.is_alive(), "server did not start"
            time.sleep(0.01)

    def close(self) -> None:
        self.feed.stop()
        self.server.should_exit = True
        self.thread.join(30)
        self.sock.close()


def call(base: str, method: str, path: str, body: bytes | None = None,
         headers: dict | None = None) -> tuple[int, object]:
    req = urllib.request.Request(base + path, data=body, method=method, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            status, raw = r.status, r.read()
    except urllib.error.HTTPError as e:
        status, raw = e.code, e.read()
    try:
        return status, json.loads(raw)
    except ValueError:
        return status, raw.decode()


def post(base: str, task: object, **kw) -> tuple[int, object]:
    return call(base, "POST", "/tasks", json.dumps(task).encode(), **kw)


@pytest.fixture(scope="module")
def server():
    s = Server()
    yield s
    s.close()


@pytest.fixture(scope="module")
def guarded():
    s = Server(token=TOKEN)
    yield s
    s.close()


@pytest.mark.parametrize(("body", "status", "field"), [
    ({"goal": [1.5, 1.5, 0.0]}, 422, "object"),
    ({"object": 1, "goal": [1.5, 1.5, 0.0]}, 422, "object"),
    ({"object": -1, "goal": [1.5, 1.5, 0.0]}, 422, "object"),
    ({"object": "0", "goal": [1.5, 1.5, 0.0]}, 422, "object"),
    ({"object": True, "goal": [1.5, 1.5, 0.0]}, 422, "object"),
    ({"object": 0}, 422, "goal"),
    ({"object": 0, "goal": [1.5, 1.5]}, 422, "goal"),
    ({"object": 0, "goal": "1.5 1.5 0"}, 422, "goal"),
    ({"object": 0, "goal": [1.5, "y", 0.0]}, 422, "goal[1]"),
    ({"object": 0, "goal": [1.5, 1.5, None]}, 422, "goal[2]"),
    ({"object": 0, "goal": [2.15, 1.5, 0.0]}, 422, "goal"),   # off the map
    ({"object": 0, "goal": [-1.0, 1.5, 0.0]}, 422, "goal"),
    ({"object": 0, "goal": [1.9, 0.4, 0.0]}, 422, "goal"),    # in the obstacle
    ({"object": 0, "goal": [1.5, 1.5, 0.0], "release_s": 3}, 422, "release_s"),
    ([0, [1.5, 1.5, 0.0]], 422, "body"),
])
def test_a_bad_task_is_refused_naming_its_field_and_the_service_goes_on(server, body,
                                                                          status, field):
    got, answer = post(server.base, body)
    assert got == status, answer
    assert answer["field"] == field and answer["detail"].startswith(field + ": ")
    assert call(server.base, "GET", "/state")[0] == 200


def test_a_body_that_is_not_json_or_too_large_is_refused(server):
    got, answer = call(server.base, "POST", "/tasks", b"{object: 0")
    assert got == 400 and answer["field"] == "body" and "not JSON" in answer["detail"]
    got, answer = call(server.base, "POST", "/tasks", b" " * (MAX_BODY + 1))
    assert got == 413 and answer["field"] == "body"
    # chunked: no Content-Length announces it, the stream is counted
    host, port = server.base.removeprefix("http://").split(":")
    conn = http.client.HTTPConnection(host, int(port), timeout=30)
    conn.putrequest("POST", "/tasks")
    conn.putheader("Transfer-Encoding", "chunked")
    conn.endheaders()
    chunk = b" " * 4096
    for _ in range(5):
        conn.send(b"%x\r\n%s\r\n" % (len(chunk), chunk))
    conn.send(b"0\r\n\r\n")
    response = conn.getresponse()
    assert response.status == 413
    conn.close()
    assert call(server.base, "GET", "/state")[0] == 200


def test_concurrent_posts_all_get_distinct_ids_and_are_listed(server):
    def one(i: int) -> int:
        got, answer = post(server.base, {"object": 0, "goal": [1.0 + 0.01 * (i % 50), 1.5, 0.0]})
        assert got == 201 and answer["status"] == "queued"
        return answer["id"]

    with ThreadPoolExecutor(8) as pool:
        ids = list(pool.map(one, range(64)))
    assert len(set(ids)) == 64
    listed = {t["id"]: t for t in call(server.base, "GET", "/tasks")[1]}
    assert set(ids) <= set(listed)
    assert sorted(listed) == list(range(len(listed)))  # numbered without gaps
    got, task = call(server.base, "GET", f"/tasks/{ids[0]}")
    assert got == 200 and task == listed[ids[0]] and task["object"] == 0
    state = call(server.base, "GET", "/state")[1]
    assert set(state) == {"time_s", "robots", "objects", "stopped", "tasks"}
    assert len(state["robots"]) == 3 and len(state["objects"]) == 1


def test_the_listening_socket_is_tcp_so_answers_are_not_held_back():
    """asyncio sets TCP_NODELAY on accepted connections only when the listening socket
    names IPPROTO_TCP; without it every kept-alive answer waits for a delayed ACK."""
    sock = listen("127.0.0.1", 0)
    try:
        assert sock.proto == socket.IPPROTO_TCP
    finally:
        sock.close()


def test_an_unknown_task_is_404(server):
    for path in ("/tasks/999999", "/tasks/abc", "/tasks/-1"):
        got, answer = call(server.base, "GET", path)
        assert got == 404 and answer["field"] == "id"


def test_with_a_token_every_request_must_carry_it(guarded):
    for path in ("/state", "/tasks", "/", "/events"):
        got, answer = call(guarded.base, "GET", path)
        assert got == 401 and answer["field"] == "token"
        assert call(guarded.base, "GET", path,
                    headers={"Authorization": "Bearer wrong"})[0] == 401
    assert post(guarded.base, {"object": 0, "goal": [1.5, 1.5, 0.0]})[0] == 401
    auth = {"Authorization": f"Bearer {TOKEN}"}
    assert call(guarded.base, "GET", "/state", headers=auth)[0] == 200
    assert post(guarded.base, {"object": 0, "goal": [1.5, 1.5, 0.0]}, headers=auth)[0] == 201
    got, page = call(guarded.base, "GET", f"/?token={TOKEN}")
    assert got == 200 and "lamp serve" in page


def test_bad_options_exit_2_naming_them_before_anything_listens(tmp_path):
    scene = tmp_path / "tiny.json"
    scene.write_text(json.dumps(TINY))
    result = CliRunner().invoke(cli_app, ["serve", str(scene), "--host", "0.0.0.0",
                                          "-o", str(tmp_path / "out")],
                                env={"LAMP_SERVE_TOKEN": ""})
    assert result.exit_code == 2
    assert "--host 0.0.0.0" in result.output and "--token" in result.output
    result = CliRunner().invoke(cli_app, ["serve", str(scene), "--realtime", "-1"])
    assert result.exit_code == 2 and "--realtime" in result.output
    taken = listen("127.0.0.1", 0)
    try:
        result = CliRunner().invoke(cli_app, ["serve", str(scene), "-m", "geometric", "--port",
                                              str(taken.getsockname()[1]),
                                              "-o", str(tmp_path / "out")])
    finally:
        taken.close()
    assert result.exit_code == 2 and "--port: cannot listen" in result.output
    assert not (tmp_path / "out").exists()
    assert is_loopback("127.0.0.1") and is_loopback("localhost") and is_loopback("::1")
    assert not is_loopback("0.0.0.0") and not is_loopback("example.org")


def test_a_fleet_that_fails_stops_the_service_and_finish_raises_its_error(monkeypatch):
    """The fleet's thread ends with an error: the feed stops (posts get 503), the server
    still answers, and ``finish`` re-raises the error for the command to report."""
    import lamp.pipeline
    from lamp.manip import GeometricProposer
    from lamp.pipeline import RunRequest
    from lamp.serve.service import Service

    def broken(request, feed=None, **kw):
        raise RuntimeError("the fleet broke")

    monkeypatch.setattr(lamp.pipeline, "run", broken)
    request = RunRequest.build(scene_from_dict(TINY), "lazy", 0, model=GeometricProposer(),
                               schedule="concurrent")
    service = Service(request, LiveFeed(request.scene), listen("127.0.0.1", 0))
    service.start()
    try:
        end = time.monotonic() + 60
        while service.running:
            assert time.monotonic() < end
            time.sleep(0.01)
        assert service.feed.stopped
        base = service.url.rstrip("/")
        got, answer = post(base, {"object": 0, "goal": [1.5, 1.5, 0.0]})
        assert got == 503 and answer["field"] == "service"
        assert call(base, "GET", "/state")[1]["stopped"] is True
        with pytest.raises(RuntimeError, match="the fleet broke"):
            service.finish()
    finally:
        service.close()


def test_lamp_serve_end_to_end_a_posted_task_is_done_and_sigterm_writes_result(tmp_path):
    scene = tmp_path / "tiny.json"
    scene.write_text(json.dumps(TINY))
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "lamp.cli", "serve", str(scene), "--port", "0",
         "--realtime", "0", "-m", "geometric", "-o", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        line = proc.stdout.readline()
        base = re.search(r"http://127\.0\.0\.1:\d+", line).group(0)
        got, task = post(base, {"object": 0, "goal": [1.6, 1.5, 0.8]})
        assert got == 201 and task["id"] == 1 and task["status"] == "queued"
        end = time.monotonic() + 600  # a hang guard only (a cold Numba cache compiles)
        while call(base, "GET", "/tasks/1")[1]["status"] != "done":
            assert time.monotonic() < end, "the posted task was not done"
            time.sleep(0.1)
        state = call(base, "GET", "/state")[1]
        assert abs(state["objects"][0][0] - 1.6) < 0.1 and abs(state["objects"][0][1] - 1.5) < 0.1
        proc.send_signal(signal.SIGTERM)
        rest, _ = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, rest
    result = json.loads((out / "result.json").read_text())
    assert [(t["id"], t["status"]) for t in result["tasks"]] == [(0, "done"), (1, "done")]
    assert result["tasks"][1]["release_s"] <= result["tasks"][1]["start_s"]
    assert result["lifelong"]["done"] == 2
    assert (out / "recording.npz").is_file() and Path(out / "recording.json").is_file()
