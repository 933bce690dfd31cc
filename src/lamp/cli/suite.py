"""``lamp suite``: list and export the built-in benchmark suites, and generate a ``fleet``
scene of any size."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from lamp.cli.support import StatusLine, fail_input, lamp_typer
from lamp.suites.registry import SUITES, export_suite, suite_files

suite_app = lamp_typer(help="Built-in benchmark suites.", no_args_is_help=True)


@suite_app.command("list")
def list_command() -> None:
    """Print each suite with its number of scenes and a one-line description."""
    width = max(len(n) for n in SUITES)
    for name, info in SUITES.items():
        n = len(suite_files(name))
        typer.echo(f"{name:<{width}}  {n:>3} scene{'s' if n != 1 else ' '}  {info.description}")


@suite_app.command("export")
def export_command(
    name: str = typer.Argument(..., help=f"Suite name: {', '.join(SUITES)}.",
                               show_default=False),
    directory: Path = typer.Argument(
        ..., help="Folder to write the scene files and manifest.json to."
    ),
) -> None:
    """Write a suite's scene files (and its manifest.json) to DIRECTORY."""
    if name not in SUITES:
        from lamp.cli.support import did_you_mean

        fail_input(f"unknown suite {name!r}; valid names: {', '.join(SUITES)}"
                   + did_you_mean(name, SUITES))
    try:
        written = export_suite(name, directory)
    except OSError as exc:
        fail_input(f"cannot write to {directory}: {exc.strerror or exc}")
    typer.echo(f"wrote {len(written) - 1} scene file(s) and manifest.json to {directory}")


class DrawProgress:
    """While a scene is drawn, a status line (on a terminal): which draw of how many, and
    why the ones before it were rejected."""

    def __init__(self, stream: Any = None, terminal: bool | None = None) -> None:
        self.line = StatusLine(stream, terminal)

    @staticmethod
    def describe(attempt: int, of: int, rejected: dict[str, int]) -> str:
        why = ", ".join(f"{reason} x{n}" for reason, n in rejected.items())
        return f"drawing the scene: attempt {attempt}/{of}" + (
            f" (rejected so far: {why})" if why else "")

    def __call__(self, attempt: int, of: int, rejected: dict[str, int]) -> None:
        if self.line.live:
            self.line.show(self.describe(attempt, of, rejected))

    def __enter__(self) -> DrawProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.line.close()


@suite_app.command("fleet-scene")
def fleet_scene_command(
    out: Path = typer.Argument(..., help="Scene file to write (.yaml, .yml or .json)."),
    kind: str | None = typer.Option(None, "--kind", help="Map kind: rooms, aisles (the "
                                    "default), yard, swap or after (the fleet family's)."),
    size: tuple[float, float] | None = typer.Option(
        None, "--size", help="Map width and height (m), 6-150 each; 40 30 when not given."),
    on_map: Path | None = typer.Option(
        None, "--map", help="Put the objects on this map instead: a scene file (its "
        "workspace, obstacles and physics) or a Moving AI grid map (.map).",
        show_default=False),
    cell: float = typer.Option(0.5, "--cell", help="Side (m) of a .map file's cells."),
    objects: int = typer.Option(16, "--objects", help="Objects to move."),
    robots: int = typer.Option(48, "--robots", help="Robots (at least one per object)."),
    seed: int = typer.Option(0, "--seed", "-s", help="Generator seed."),
) -> None:
    """Generate a scene of the ``fleet`` family's kinds at any size, or on your own map
    (``--map``), with its generator and checks (every object has a certified route and
    reachable contacts), and write it to OUT, with ``schedule: concurrent``."""
    from lamp.errors import InputError
    from lamp.scene.mapf import load_map
    from lamp.scene.save import save_scene
    from lamp.suites.fleet import generate_custom, generate_on_map

    if on_map is not None and (kind is not None or size is not None):
        fail_input("--map takes the map's own workspace and obstacles: leave out --kind "
                   "and --size")
    try:
        with DrawProgress() as shown:
            if on_map is None:
                gen = generate_custom(kind or "aisles", size or (40.0, 30.0), objects, robots,
                                      seed, on_attempt=shown)
            else:
                base = load_map(on_map, cell)  # an InputError names the file (field, cell)
                try:
                    gen = generate_on_map(base, objects, robots, seed, on_attempt=shown)
                except ValueError as exc:
                    raise InputError(f"{on_map}: {exc}") from exc
        save_scene(gen.scene, out)
    except ValueError as exc:  # InputError included
        fail_input(str(exc))
    except RuntimeError as exc:  # no draw passed the checks: too many objects for the map
        more = "a larger --size" if on_map is None else "a larger --cell"
        fail_input(f"{exc}; try {more} or fewer --objects")
    except OSError as exc:
        fail_input(f"cannot write {out}: {exc.strerror or exc}")
    W, H = gen.scene.workspace
    typer.echo(f"wrote {out}: {gen.scene.name}, {robots} robots, {objects} objects, "
               f"{W:g} x {H:g} m")

