"""``lamp show``, ``lamp render`` and ``lamp timeline``: the commands that draw pictures
(a scene, a recorded run, where a run's robot-time went); nothing is planned."""

from __future__ import annotations

from pathlib import Path

import typer

from lamp.cli.support import check_writable_file, fail_input, image_format, load_scene_or_exit


def show(
    scene_file: Path = typer.Argument(..., help="Scene file (YAML or JSON), or a built-in "
                                      "scene by name (maze-07).", show_default=False),
    out: Path = typer.Option(Path("scene.png"), "--out", "-o",
                             help="Image to write: .png, .svg or .pdf (by its extension)."),
) -> None:
    """Draw a scene: workspace, obstacles, robots, object start and goal outlines."""
    fmt = image_format(out)
    check_writable_file(out)
    scene = load_scene_or_exit(scene_file)
    from lamp.viz.scene_plot import save_scene_image

    save_scene_image(scene, out, fmt=fmt)
    typer.echo(f"wrote {out}")



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


def timeline_command(
    run_dir: Path = typer.Argument(..., help="A run folder holding recording.json + .npz."),
    out: Path = typer.Option(..., "--out", "-o", help="Picture to write: .png, .svg or .pdf."),
    width: float = typer.Option(10.0, "--width", help="Picture width in inches."),
) -> None:
    """Draw where a run's robot-time went: one bar per robot over simulated time, coloured
    by the object its sub-team pushes (moving, holding, idle), objects' placements marked."""
    from lamp.record import RecordingError, load_recording
    from lamp.viz.timeline import save_timeline

    image_format(out)
    check_writable_file(out)
    try:
        recording = load_recording(run_dir)
        save_timeline(recording, out, width_in=width)
    except RecordingError as exc:
        fail_input(str(exc))
    except ValueError as exc:  # "field: problem" -> "--field: problem"
        fail_input(f"--{exc}")
    typer.echo(f"wrote {out}")
