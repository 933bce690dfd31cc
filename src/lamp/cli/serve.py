"""``lamp serve``: run a scene's fleet as a service that takes tasks over HTTP
(``lamp.serve``; the API: ``docs/serve.md``).

Inputs are checked before anything listens (exit 2 naming the option): the scene, the
planner (a closed-loop one: the fleet's concurrent schedule), the model, ``--realtime``,
``--out``, the port, and the token rule (a host other than this machine's loopback needs
``--token``). On SIGINT or SIGTERM the fleet stops (the tasks not done fail,
``stopped``), the run folder is written as ``lamp run`` writes it (result.json last) and
the command exits 0; a second signal ends it at once.
"""

from __future__ import annotations

import math
import signal
import sys
import threading
from pathlib import Path

import typer

from lamp.cli.run import MODEL_HELP, PLANNER_HELP, write_run
from lamp.cli.support import (
    RunProgress,
    check_choice,
    check_model_option,
    check_writable_dir,
    fail_input,
    load_scene_or_exit,
)
from lamp.pipeline import registry

HELP = (
    "Run SCENE's fleet as a service: tasks posted over HTTP are served while it works.\n\n"
    "POST /tasks with {\"object\": K, \"goal\": [X, Y, THETA]}: 201 and {\"id\": ..., "
    "\"status\": \"queued\"}; a bad task gets a 4xx naming the field.\n\n"
    "GET /tasks, /tasks/ID, /state: the tasks and the world now. GET /: the live page "
    "(open it in a browser; click the map to pick a goal).\n\n"
    "The scene's own goals (and its tasks:) are the first tasks; posted ones are numbered "
    "after them and released at the simulated time of the post.\n\n"
    "Ctrl-C or SIGTERM stops the fleet (tasks not done fail), writes DIR/result.json and "
    "the recording as `lamp run` does, and exits 0. See docs/serve.md."
)


def serve(
    scene_file: Path = typer.Argument(..., help="Scene file (YAML or JSON), or a built-in "
                                      "scene by name.", show_default=False),
    host: str = typer.Option("127.0.0.1", "--host", help="Interface to listen on; any but "
                             "this machine's loopback needs --token."),
    port: int = typer.Option(8765, "--port", min=0, max=65535, help="TCP port (0: a free "
                             "one, printed at start)."),
    realtime: float = typer.Option(1.0, "--realtime", help="Simulated seconds per wall "
                                   "second (1: wall-clock pace; 0: as fast as it can, and "
                                   "the clock stands still while no task waits)."),
    planner: str = typer.Option("lazy", "--planner", "-p", help=PLANNER_HELP),
    seed: int = typer.Option(0, "--seed", "-s", help="Random seed."),
    model: str = typer.Option("learned", "--model", "-m", help=MODEL_HELP),
    token: str = typer.Option(None, "--token", envvar="LAMP_SERVE_TOKEN", show_default=False,
                              help="Every request must carry it: 'Authorization: Bearer "
                                   "TOKEN' or ?token=TOKEN (the page). Required with a "
                                   "non-loopback --host. Also read from LAMP_SERVE_TOKEN."),
    out: Path = typer.Option(Path("lamp-serve"), "--out", "-o", help="Output folder, written "
                             "on stop: result.json (with the tasks) and the recording."),
) -> None:
    from lamp.pipeline import RunRequest
    from lamp.serve.feed import LiveFeed
    from lamp.serve.service import Service, is_loopback, listen

    if not (math.isfinite(realtime) and realtime >= 0):
        fail_input(f"--realtime: a finite number >= 0, got {realtime:g}")
    if token is not None and not token:
        fail_input("--token: empty")
    if not is_loopback(host) and token is None:
        fail_input(f"--host {host}: listening beyond this machine needs --token (every "
                   "request must then carry it)")
    check_choice("--planner", planner, registry.names(), "planner")
    check_writable_dir(out)
    request = RunRequest.build(load_scene_or_exit(scene_file), planner, seed,
                               model=check_model_option(model), schedule="concurrent")
    feed = LiveFeed(request.scene, realtime)
    try:
        sock = listen(host, port)
    except OSError as exc:
        fail_input(f"--port: cannot listen on {host}:{port}: {exc.strerror or exc}")
    service = Service(request, feed, sock, token)
    stop = threading.Event()
    previous = {s: signal.signal(s, lambda *_: _on_signal(stop, previous))
                for s in (signal.SIGINT, signal.SIGTERM)}
    service.start()
    typer.echo(f"lamp serve: {service.url} (scene {request.scene.name}, planner {planner}, "
               f"realtime {realtime:g}); Ctrl-C stops it and writes {out}")
    sys.stdout.flush()
    while service.running and not stop.wait(0.2):
        pass
    _finish(service, out)


def _on_signal(stop: threading.Event, previous: dict) -> None:
    """The first signal stops the service; the handlers go back to what they were, so a
    second one ends the process at once."""
    for s, handler in previous.items():
        signal.signal(s, handler)
    stop.set()


def _finish(service, out: Path) -> None:
    """Stop the fleet, write the run folder, stop the server."""
    typer.echo("lamp serve: stopping")
    try:
        result = service.finish()
    except Exception as exc:
        service.close()
        typer.echo(f"internal error: {type(exc).__name__}: {exc}", err=True)
        raise typer.Exit(code=1) from exc
    try:
        write_run(result, out, RunProgress())
    finally:
        service.close()


serve.__doc__ = HELP
