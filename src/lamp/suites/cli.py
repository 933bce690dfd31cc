"""``lamp suite``: list and export the built-in benchmark suites (placeholder until written)."""

import typer

suite_app = typer.Typer(help="Built-in benchmark suites.", no_args_is_help=True)
