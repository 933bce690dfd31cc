"""``lamp check``: re-check recorded runs without the planner (``lamp.record.audit``)."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from lamp.cli.support import StatusLine, fail_input


def check_command(
    runs: list[Path] = typer.Argument(..., help="Run folders (`lamp run -o DIR`), or folders "
                                      "holding several (`lamp bench --record --out DIR`)."),
    horizon: int = typer.Option(400, "--horizon", help="Rows apart at most when measuring "
                                "how far pushed objects ran ahead of their pushers."),
    no_reach: bool = typer.Option(False, "--no-reach", help="Only the collision check; "
                                  "skip the push lead."),
    as_json: bool = typer.Option(False, "--json", help="One JSON object per run on stdout "
                                 "instead of text."),
    verbose: bool = typer.Option(False, "--verbose", "-v", help="The full report of every "
                                 "run (failing runs always get it)."),
) -> None:
    """Re-check recorded runs without the planner: collisions (robots, objects, obstacles,
    border), and how far pushed objects ran ahead of their pushers. A line per run; exit 1
    when a run fails a check, 2 when a recording cannot be read (the others are checked)."""
    from lamp.fleet.spacetime import PUSH_LEAD, PUSH_SPEEDUP
    from lamp.record import RecordingError
    from lamp.record.audit import ReachBound, audit_run_dir, run_dirs

    try:
        bound = ReachBound(PUSH_SPEEDUP, PUSH_LEAD, horizon)
    except ValueError as exc:  # "horizon: problem" -> "--horizon: problem"
        fail_input(f"--{exc}")
    found: list[Path] = []
    for path in runs:
        if not path.exists():
            fail_input(f"{path}: no such file or folder")
        here = run_dirs(path)
        if not here:
            fail_input(f"{path}: no recording here or below (`lamp run` writes one; "
                       "`lamp bench` with --record)")
        found += here
    status = StatusLine()
    failed, unreadable = 0, []
    for n, run_dir in enumerate(found, 1):
        if status.live and not as_json:
            status.show(f"checking {run_dir} ({n}/{len(found)})")
        try:
            audit = audit_run_dir(run_dir, bound, reach=not no_reach)
        except RecordingError as exc:
            unreadable.append(str(exc))
            continue
        finally:
            status.close()
        failed += not audit.ok
        if as_json:
            typer.echo(json.dumps({"run": str(run_dir), **audit.to_dict()}))
            continue
        typer.echo(f"{'PASS' if audit.ok else 'FAIL'}  {run_dir}: {audit.line()}")
        if verbose or not audit.ok:
            typer.echo(audit.summary())
    for message in unreadable:
        typer.echo(f"error: {message}", err=True)
    if not as_json:
        typer.echo(f"{len(found) - failed - len(unreadable)} of {len(found)} run(s) passed"
                   + (f"; {failed} failed" if failed else "")
                   + (f"; {len(unreadable)} unreadable" if unreadable else ""))
    if unreadable:
        raise typer.Exit(2)
    if failed:
        raise typer.Exit(1)
