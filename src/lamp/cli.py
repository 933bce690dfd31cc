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


def _register_groups() -> None:
    from lamp.suites.cli import suite_app

    app.add_typer(suite_app, name="suite")
    try:
        from lamp.manip.cli import model_app
    except ImportError:  # the model group is optional until its module exists
        return
    app.add_typer(model_app, name="model")


_register_groups()


if __name__ == "__main__":
    app()
