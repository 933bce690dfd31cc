"""``lamp run``, ``lamp demo`` and ``lamp warmup``: plan and execute a scene, write its outputs.

Every run is one ``lamp.pipeline.RunRequest``, its inputs checked before anything is planned
or written (:func:`_build_request`); :func:`_run_and_write` runs it and writes the run
folder, result.json last. Exit status: 0 when a run finished (whatever its outcome;
``lamp run --check`` exits 1 when the task failed), 2 for bad input, 1 for an internal error.
"""

from __future__ import annotations

from pathlib import Path

import typer

from lamp.cli.support import (
    RunProgress,
    check_choice,
    check_model_option,
    check_writable_dir,
    fail_input,
    load_scene_or_exit,
    print_summary,
)
from lamp.errors import InputError
from lamp.pipeline import registry
from lamp.pipeline.registry import planning_limit_help
from lamp.planners.config import PAPER_MAX_SEGMENTS, SEGMENTS_PER_METRE

PLANNER_HELP = "Planner: " + "; ".join(f"{s.name}: {s.description}" for s in registry.specs())
MODEL_HELP = ("Manipulation model: learned (the shipped checkpoint), geometric, or a checkpoint "
              "file written by `lamp model train`.")


def _run_and_write(request, out: Path, progress: RunProgress, render: bool = False,
                   html: bool = False) -> dict:
    """Run ``request`` (``lamp.pipeline.run``) and write its outputs into ``out``:
    result.json last (it marks the folder complete), the recording, and the pictures asked
    for, each drawn from the recording."""
    from lamp.pipeline import run

    if out.exists() and not out.is_dir():
        fail_input(f"--out: {out} exists and is not a folder")
    try:
        with progress:
            run_result = run(request, progress=progress)
    except InputError:
        raise  # bad input found late (a model file, say): exit 2
    except Exception as exc:  # an internal error: exit status 1 with a short message
        typer.echo(f"internal error: {type(exc).__name__}: {exc}", err=True)
        raise typer.Exit(code=1) from exc
    return write_run(run_result, out, progress, render, html)


def write_run(run_result, out: Path, progress: RunProgress, render: bool = False,
              html: bool = False) -> dict:
    """Write a finished run's folder ``out`` as ``lamp run`` does (``lamp serve`` too): the
    summary (unless quiet), the recording, the pictures asked for, result.json last (it
    marks the folder complete); returns result.json's content. Exit 2 when ``out`` cannot
    be written, 1 for an internal error."""
    from lamp.io import write_json_atomic
    from lamp.record import save_recording
    from lamp.record.run_dir import GIF_NAME, HTML_NAME, RESULT_NAME, clear_stale

    result = run_result.to_dict()

    def say(message: str) -> None:
        if not progress.quiet:
            typer.echo(message)

    try:
        out.mkdir(parents=True, exist_ok=True)
        writes = [GIF_NAME] * render + [HTML_NAME] * html
        for path in clear_stale(out, keep=writes):
            say(f"removed {path} (left by an earlier run)")
        if not progress.quiet:
            print_summary(result)
        # each file atomically, result.json last: it marks the folder complete
        npz, index = save_recording(run_result.recording, out)
        say(f"wrote {index} and {npz.name}")
        if writes:
            from lamp.viz.replay import render as render_recording

            for name in writes:
                render_recording(run_result.recording, out / name)
                say(f"wrote {out / name}")
        write_json_atomic(out / RESULT_NAME, result)
    except OSError as exc:  # checked before planning; the disk may still fill up
        fail_input(f"--out: cannot write into {out}: {exc.strerror or exc}")
    except Exception as exc:
        typer.echo(f"internal error while writing {out}: {type(exc).__name__}: {exc}", err=True)
        raise typer.Exit(code=1) from exc
    say(f"wrote {out / RESULT_NAME}")
    return result


OUT_HELP = ("Output folder: result.json, recording.npz + recording.json (lamp-recording/1) "
            "and what was asked for. Outputs an earlier run left there (result.json, the "
            "recording, run.gif, replay.html) are replaced, or removed when this run does not "
            "write them; other files stay.")


def _build_request(scene_file: Path | None, scene, planner: str, seed: int, model: str,
                   out: Path, params: list[str] | None = None,
                   planning_limit: float | None = None, max_segments: int | None = None,
                   disturbances=None, schedule: str | None = None):
    """The run request of ``lamp run`` / ``lamp demo``, every input checked before anything
    is planned or written (bad input: ``InputError``, exit 2)."""
    from lamp.contract.params import parse_assignments
    from lamp.pipeline import RunRequest

    check_choice("--planner", planner, registry.names(), "planner")
    if planning_limit is not None and not planning_limit > 0:
        fail_input(f"--planning-limit: must be positive, got {planning_limit:g}")
    overrides = {}
    for who, name, value in parse_assignments(params or ()):
        if who != planner:
            fail_input(f"--param {who}.{name}={value}: names planner {who!r}, but the run "
                       f"uses --planner {planner}")
        overrides[name] = value
    if schedule is not None:
        from lamp.scene.model import SCHEDULES

        check_choice("--schedule", schedule, SCHEDULES, "schedule")
    check_writable_dir(out)
    model = check_model_option(model)
    if scene is None:
        scene = load_scene_or_exit(scene_file)
    return RunRequest.build(scene, planner, seed, model=model, params=overrides,
                            planning_limit=planning_limit, max_segments=max_segments,
                            schedule=schedule,
                            **({"disturbances": disturbances} if disturbances else {}))


def _disturbances(sensing: float, actuation: float, failures: list[str] | None,
                  push: float):
    """The run's disturbances from ``lamp run``'s options (None: none)."""
    from lamp.contract.disturb import Disturbances, parse_failure

    if not (sensing or actuation or failures or push):
        return None
    try:
        return Disturbances(sensing_noise=sensing, actuation_noise=actuation,
                            robot_failures=tuple(parse_failure(f) for f in failures or ()),
                            push_disturbance=push)
    except InputError as exc:  # "field: why" -> "--option: why"
        flags = {"sensing_noise": "--sensing-noise", "actuation_noise": "--actuation-noise",
                 "push_disturbance": "--push-disturbance", "robot_failures": "--robot-failure"}
        field, _, why = str(exc).partition(":")
        raise InputError(f"{flags.get(field, field)}:{why}") from None


def _print_params(planner: str) -> None:
    """``--help-params``: the planner's declared parameters with their values and rules."""
    from rich.console import Console
    from rich.table import Table

    from lamp.pipeline.request import param_rows

    spec = registry.get(check_choice("--planner", planner, registry.names(), "planner"))
    rows = param_rows(spec)
    table = Table(title=f"parameters of {spec.name} ({spec.description}): --param {spec.name}.NAME=VALUE")
    for col in ("name", "default", "valid", "meaning"):
        table.add_column(col)
    for row in rows:
        table.add_row(*row)
    console = Console(highlight=False)
    if rows:
        console.print(table)
    else:
        console.print(f"{spec.name} declares no parameters", markup=False)


def _quiet_verbose(quiet: bool, verbose: bool) -> RunProgress:
    if quiet and verbose:
        fail_input("--quiet and --verbose: choose one")
    return RunProgress(quiet=quiet, verbose=verbose)


SEGMENT_LIMIT_HELP = (f"{PAPER_MAX_SEGMENTS}, or {SEGMENTS_PER_METRE:g} per metre of the object's "
                      f"route around the obstacles when that is more; the paper benchmark "
                      f"keeps {PAPER_MAX_SEGMENTS}")
QUIET_HELP = "Print nothing but errors (result.json is still written)."
VERBOSE_HELP = "Print a line per object and segment, even when the output is not a terminal."


PARAM_HELP = ("Set one of the planner's parameters, PLANNER.NAME=VALUE (repeatable; "
              "--help-params lists them), e.g. lazy.max_plan_iterations=400.")


def run(
    scene_file: Path = typer.Argument(None, help="Scene file (YAML or JSON), or a built-in "
                                      "scene by name (maze-07).", show_default=False),
    planner: str = typer.Option("lazy", "--planner", "-p", help=PLANNER_HELP),
    seed: int = typer.Option(0, "--seed", "-s", help="Random seed (same seed, same result)."),
    out: Path = typer.Option(Path("lamp-run"), "--out", "-o", help=OUT_HELP),
    render: bool = typer.Option(False, "--render", help="Also write DIR/run.gif."),
    html: bool = typer.Option(False, "--html", help="Also write the replay viewer "
                              "DIR/replay.html."),
    model: str = typer.Option("learned", "--model", "-m", help=MODEL_HELP),
    planning_limit: float = typer.Option(None, "--planning-limit",
                                         help="Cumulative planning limit per object, seconds.",
                                         show_default=planning_limit_help()),
    time_limit: float = typer.Option(None, "--time-limit", hidden=True,
                                     help="Old spelling of --planning-limit."),
    max_segments: int = typer.Option(None, "--max-segments", min=1,
                                     help="Executed segments allowed per object.",
                                     show_default=SEGMENT_LIMIT_HELP),
    param: list[str] = typer.Option(None, "--param", help=PARAM_HELP, show_default=False),
    schedule: str = typer.Option(None, "--schedule", help="sequential: one object after "
                                 "another by the whole team (the paper's); concurrent: "
                                 "several at once by sub-teams.",
                                 show_default="the scene file's, else sequential"),
    sensing_noise: float = typer.Option(0.0, "--sensing-noise", help="Disturbance: Gaussian "
                                        "noise (m; heading SIGMA/0.2 rad) on every observed "
                                        "object pose."),
    actuation_noise: float = typer.Option(0.0, "--actuation-noise", help="Disturbance: each "
                                          "robot's commanded motion scaled and turned by "
                                          "noise of this relative size, per row."),
    robot_failure: list[str] = typer.Option(None, "--robot-failure", show_default=False,
                                            help="Disturbance: robot K stops for good at "
                                                 "simulated time T, K@T (repeatable)."),
    push_disturbance: float = typer.Option(0.0, "--push-disturbance", help="Disturbance: a "
                                           "random impulse (N s) on the pushed object "
                                           "during every segment."),
    help_params: bool = typer.Option(False, "--help-params", help="List the parameters of "
                                     "--planner (name, default, valid values, meaning) and "
                                     "exit."),
    check: bool = typer.Option(False, "--check", help="Exit with status 1 when the task "
                               "failed (for scripts and CI); default: 0 whenever the run "
                               "finished."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
    verbose: bool = typer.Option(False, "--verbose", "-v", help=VERBOSE_HELP),
) -> None:
    """Plan and execute one scene file in MuJoCo; write DIR/result.json and the recording."""
    if help_params:
        _print_params(planner)
        return
    if scene_file is None:
        fail_input("SCENE_FILE: missing (a scene file or a built-in scene name)")
    progress = _quiet_verbose(quiet, verbose)
    limit = time_limit if time_limit is not None else planning_limit
    request = _build_request(scene_file, None, planner, seed, model, out, param, limit,
                             max_segments, _disturbances(sensing_noise, actuation_noise,
                                                         robot_failure, push_disturbance),
                             schedule)
    result = _run_and_write(request, out, progress, render, html)
    if check and not result["success"]:
        raise typer.Exit(code=1)


def demo(
    out: Path = typer.Option(Path("lamp-demo"), "--out", "-o", help=OUT_HELP),
    seed: int = typer.Option(0, "--seed", "-s", help="Random seed."),
    planner: str = typer.Option("lazy", "--planner", "-p", help=PLANNER_HELP),
    model: str = typer.Option("learned", "--model", "-m", help=MODEL_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
    verbose: bool = typer.Option(False, "--verbose", "-v", help=VERBOSE_HELP),
) -> None:
    """The main job: LAMP-Lazy on the built-in default scene; writes result.json, the
    recording, run.gif and replay.html."""
    from lamp.demo import demo_scene

    progress = _quiet_verbose(quiet, verbose)
    request = _build_request(None, demo_scene(), planner, seed, model, out)
    _run_and_write(request, out, progress, render=True, html=True)


def warmup() -> None:
    """Compile the Numba kernels now (cached on disk), so that no run pays for it later."""
    from lamp.pipeline.warmup import warm_up

    progress = RunProgress(verbose=True)
    report = warm_up(progress)
    if report.compiled:
        typer.echo(f"compiled {report.compiled} kernels in {report.compile_s:.1f} s "
                   f"(cached on disk; warm-up {report.seconds:.1f} s)")
    else:
        typer.echo(f"kernels already compiled (loaded from the disk cache; warm-up "
                   f"{report.seconds:.1f} s)")
