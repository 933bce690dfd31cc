"""The ``lamp`` command line: parses arguments, loads inputs, calls the library, writes outputs.

Sub-command groups live beside the code they drive (``lamp.suites.cli``, ``lamp.manip.cli``,
``lamp.bench.cli``); this module only wires them together. Exit status: 0 when a run
finished (whatever its outcome), 2 for bad input, 1 for an internal error.
"""

from __future__ import annotations

from pathlib import Path

import typer

from lamp.scene import SceneError, load_scene

app = typer.Typer(
    help="LAMP: long-horizon multi-robot collaborative manipulation planning.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def fail_input(message: str) -> None:
    """Report bad input on stderr and exit with status 2."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def load_scene_or_exit(path: Path):
    try:
        return load_scene(path)
    except SceneError as exc:
        fail_input(str(exc))


@app.command()
def show(
    scene_file: Path = typer.Argument(..., help="Scene file (YAML or JSON)."),
    out: Path = typer.Option(Path("scene.png"), "--out", "-o", help="PNG file to write."),
) -> None:
    """Draw a scene: workspace, obstacles, robots, object start and goal outlines."""
    scene = load_scene_or_exit(scene_file)
    from lamp.viz.scene_plot import save_scene_png

    save_scene_png(scene, out)
    typer.echo(f"wrote {out}")


def _print_summary(result) -> None:
    from rich.console import Console
    from rich.table import Table

    d = result.to_dict()
    table = Table(title=f"{d['scene']} - {d['planner']} (seed {d['seed']})")
    for col in ("object", "success", "position err (m)", "orientation err (rad)", "segments",
                "full-horizon plan", "note"):
        table.add_column(col)
    for i, o in enumerate(d["objects"]):
        table.add_row(str(i), "yes" if o["success"] else "no", f"{o['position_error']:.3f}",
                      f"{o['orientation_error']:.3f}", str(o["segments"]),
                      "yes" if o["full_horizon_plan"] else "no", o.get("failure_reason", ""))
    console = Console()
    console.print(table)
    med = d["median_planning_time_s"]
    console.print(
        f"success: {d['success']}  segments: {d['segments']}  replans: {d['replans']}  "
        f"planning time: {d['total_planning_time_s']:.2f} s total"
        + (f", {med:.3f} s median per segment" if med is not None else "")
        + f"  makespan: {d['makespan']} steps  wall time: {d['wall_time_s']:.1f} s"
    )


def _run_and_write(scene, planner: str, seed: int, out: Path, render: bool, model: str,
                   time_limit: float | None, html: bool = False) -> None:
    from lamp.io import write_json_atomic
    from lamp.planners.run import solve_with_frames
    from lamp.record import save_recording
    from lamp.record.run_dir import GIF_NAME, HTML_NAME, RESULT_NAME, clear_stale

    if out.exists() and not out.is_dir():
        fail_input(f"--out: {out} exists and is not a folder")
    try:
        solution = solve_with_frames(scene, planner, seed, model=model, time_limit=time_limit)
    except Exception as exc:  # an internal error: exit status 1 with a short message
        typer.echo(f"internal error: {type(exc).__name__}: {exc}", err=True)
        raise typer.Exit(code=1) from exc
    out.mkdir(parents=True, exist_ok=True)
    writes = [GIF_NAME] * render + [HTML_NAME] * html
    for path in clear_stale(out, keep=writes):
        typer.echo(f"removed {path} (left by an earlier run)")
    _print_summary(solution.result)
    try:  # each file atomically, result.json last: it marks the folder complete
        npz, index = save_recording(solution.recording, out)
        typer.echo(f"wrote {index} and {npz.name}")
        if writes:
            from lamp.viz.replay import render as render_recording

            for name in writes:
                render_recording(solution.recording, out / name)
                typer.echo(f"wrote {out / name}")
        write_json_atomic(out / RESULT_NAME, solution.result.to_dict())
    except Exception as exc:
        typer.echo(f"internal error while writing {out}: {type(exc).__name__}: {exc}", err=True)
        raise typer.Exit(code=1) from exc
    typer.echo(f"wrote {out / RESULT_NAME}")


OUT_HELP = ("Output folder: result.json, recording.npz + recording.json (lamp-recording/1) "
            "and what was asked for. Outputs an earlier run left there (result.json, the "
            "recording, run.gif, replay.html) are replaced, or removed when this run does not "
            "write them; other files stay.")


def _check_run_options(planner: str, model: str) -> None:
    from lamp.planners.run import PLANNERS

    if planner not in PLANNERS:
        fail_input(f"--planner: unknown planner {planner!r}; expected one of: {', '.join(PLANNERS)}")
    if model not in ("learned", "geometric"):
        fail_input(f"--model: unknown model {model!r}; expected 'learned' or 'geometric'")


@app.command()
def run(
    scene_file: Path = typer.Argument(..., help="Scene file (YAML or JSON)."),
    planner: str = typer.Option("lazy", "--planner", "-p",
                                help="lazy | astar | astar-replan | gco-ori | gco-var"),
    seed: int = typer.Option(0, "--seed", "-s", help="Random seed (same seed, same result)."),
    out: Path = typer.Option(Path("lamp-run"), "--out", "-o", help=OUT_HELP),
    render: bool = typer.Option(False, "--render", help="Also write DIR/run.gif."),
    html: bool = typer.Option(False, "--html", help="Also write the replay viewer "
                              "DIR/replay.html."),
    model: str = typer.Option("learned", "--model",
                              help="Manipulation model: learned (shipped checkpoint) or geometric."),
    time_limit: float = typer.Option(None, "--time-limit",
                                     help="Cumulative planning limit per object in seconds."),
) -> None:
    """Plan and execute one scene file in MuJoCo; write DIR/result.json and the recording."""
    scene = load_scene_or_exit(scene_file)
    _check_run_options(planner, model)
    _run_and_write(scene, planner, seed, out, render, model, time_limit, html)


@app.command()
def demo(
    out: Path = typer.Option(Path("lamp-demo"), "--out", "-o", help=OUT_HELP),
    seed: int = typer.Option(0, "--seed", "-s", help="Random seed."),
    planner: str = typer.Option("lazy", "--planner", "-p", help="Planner (default LAMP-Lazy)."),
    model: str = typer.Option("learned", "--model", help="learned or geometric."),
) -> None:
    """The main job: LAMP-Lazy on the built-in default scene; writes result.json, the
    recording, run.gif and replay.html."""
    from lamp.demo import demo_scene

    _check_run_options(planner, model)
    _run_and_write(demo_scene(), planner, seed, out, True, model, None, html=True)


@app.command("render")
def render_command(
    run_dir: Path = typer.Argument(..., help="A run folder holding recording.json + .npz."),
    out: Path = typer.Option(..., "--out", "-o", help="File to write: .gif, .mp4 (needs "
                             "imageio-ffmpeg), .png (one still), .html (replay viewer) or "
                             ".mcap (Foxglove; needs mcap)."),
    at: int = typer.Option(None, "--at", help="PNG: draw the end of segment N, counted as in "
                           "the pictures (1 = the first; default: the final state)."),
    size: int = typer.Option(640, "--size", help="Pixels on the picture's longer side."),
    fps: float = typer.Option(15.0, "--fps", help="Frames per second of video."),
    speed: float = typer.Option(None, "--speed", help="Simulated seconds per video second "
                                "(default: the video lasts at most 20 s)."),
    follow: float = typer.Option(None, "--follow", help="Camera window in metres that "
                                 "follows the moved object (default: whole workspace)."),
    min_robot_px: float = typer.Option(3.0, "--min-robot-px", help="Smallest robot radius "
                                       "drawn, in pixels."),
    trail: float = typer.Option(4.0, "--trail", help="Robot trail length in simulated s."),
) -> None:
    """Draw a recorded run again, without replanning: GIF, MP4, PNG still, HTML viewer, or
    export it to MCAP for Foxglove."""
    from lamp.record import RecordingError, load_recording
    from lamp.viz.replay import RenderOptions, render

    try:
        recording = load_recording(run_dir)
    except RecordingError as exc:
        fail_input(str(exc))
    try:
        if at is not None and out.suffix.lower() != ".png":
            raise ValueError("at: only a .png still takes --at")
        if at is not None and not 1 <= at <= recording.n_segments:
            raise ValueError(f"at: segment {at} does not exist (the run has "
                             f"{recording.n_segments} segments: 1..{recording.n_segments})")
        options = RenderOptions(size=size, fps=fps, speed=speed, trail_s=trail,
                                min_robot_px=min_robot_px, follow=follow,
                                at=None if at is None else at - 1)
        stats = render(recording, out, options)
    except ValueError as exc:  # "field: problem" -> "--option: problem"
        field, _, problem = str(exc).partition(": ")
        flags = {"trail_s": "--trail", "min_robot_px": "--min-robot-px"}
        flag = flags.get(field, f"--{field}")
        fail_input(f"{flag}: {problem}" if problem else str(exc))
    except RuntimeError as exc:
        fail_input(str(exc))
    frames = f" ({stats.frames} frames)" if stats.frames > 1 else ""
    typer.echo(f"wrote {out}{frames} in {stats.seconds:.1f} s")


def _register_groups() -> None:
    from lamp.suites.cli import suite_app

    app.add_typer(suite_app, name="suite")
    try:
        from lamp.manip.cli import model_app

        app.add_typer(model_app, name="model")
    except ImportError:  # pragma: no cover - only while the module is being written
        pass
    try:
        from lamp.bench.cli import bench_command, report_command

        app.command("bench")(bench_command)
        app.command("report")(report_command)
    except ImportError:  # pragma: no cover
        pass


_register_groups()


if __name__ == "__main__":
    app()
