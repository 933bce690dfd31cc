"""``lamp suite``: list and export the built-in benchmark suites."""

from __future__ import annotations

from pathlib import Path

import typer

from lamp.cli_support import fail_input, lamp_typer
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
        from lamp.cli_support import did_you_mean

        fail_input(f"unknown suite {name!r}; valid names: {', '.join(SUITES)}"
                   + did_you_mean(name, SUITES))
    try:
        written = export_suite(name, directory)
    except OSError as exc:
        fail_input(f"cannot write to {directory}: {exc.strerror or exc}")
    typer.echo(f"wrote {len(written) - 1} scene file(s) and manifest.json to {directory}")
