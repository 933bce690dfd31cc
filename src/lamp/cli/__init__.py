"""The ``lamp`` command line: parses arguments, loads inputs, calls the library, writes outputs.

Every command lives in this package, one module per command or group; this module only
creates the ``lamp`` app (the ``lamp = "lamp.cli:app"`` entry point; ``python -m lamp.cli``
runs it too) and wires them together:

- :mod:`lamp.cli.run`: ``lamp run``, ``lamp demo``, ``lamp warmup``;
- :mod:`lamp.cli.draw`: ``lamp show``, ``lamp render``, ``lamp timeline``;
- :mod:`lamp.cli.check`: ``lamp check``;
- :mod:`lamp.cli.scene`: ``lamp validate``, ``lamp schema``;
- :mod:`lamp.cli.serve`: ``lamp serve``;
- :mod:`lamp.cli.bench`: ``lamp bench``, ``lamp report`` (options: :mod:`lamp.cli.bench_options`);
- :mod:`lamp.cli.suite`, :mod:`lamp.cli.model`, :mod:`lamp.cli.rl`: the ``lamp suite``,
  ``lamp model`` and ``lamp rl`` groups;
- :mod:`lamp.cli.support`: what they share: the one exit-2 handler, input checks, the
  progress display, the run summary.

Exit status: 0 when a command finished (``lamp run --check`` exits 1 when the task failed,
``lamp check`` when a run failed a check),
2 for bad input (checked before any planning or writing), 1 for an internal error.
"""

from __future__ import annotations

import typer

from lamp.cli import bench, check, draw, model, rl, run, scene, serve, suite
from lamp.cli.support import lamp_typer, version_callback

__all__ = ["app", "main"]

app = lamp_typer(
    help="LAMP: long-horizon multi-robot collaborative manipulation planning.",
    no_args_is_help=True,
    add_completion=True,
)


@app.callback()
def main(
    version: bool = typer.Option(False, "--version", "-V", callback=version_callback,
                                 is_eager=True, help="Print the installed version and exit."),
) -> None:
    """LAMP: long-horizon multi-robot collaborative manipulation planning."""


# The order here is the order of `lamp --help`.
app.command("show")(draw.show)
app.command("run")(run.run)
app.command("demo")(run.demo)
app.command("warmup")(run.warmup)
app.command("render")(draw.render_command)
app.command("timeline")(draw.timeline_command)
app.command("check")(check.check_command)
app.command("validate")(scene.validate_command)
app.command("schema")(scene.schema_command)
app.command("bench")(bench.bench_command)
app.command("report")(bench.report_command)
app.command("serve")(serve.serve)
app.add_typer(suite.suite_app, name="suite")
app.add_typer(model.model_app, name="model")
app.add_typer(rl.rl_app, name="rl")
