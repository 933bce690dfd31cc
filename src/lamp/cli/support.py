"""Helpers shared by the ``lamp`` commands: the exit-2 handler, input checks, run progress,
summary.

Bad input is reported in one place: every command group is a :class:`LampGroup`, which
turns a :class:`~lamp.errors.LampError` escaping any command (an ``InputError`` raised by
the library, or :func:`fail_input` here) into ``error: <what>: <why>`` on stderr and exit
status 2. The checks here run before any planning or writing, so that bad input costs
nothing and leaves nothing half-written.
"""

from __future__ import annotations

import difflib
import os
import sys
import tempfile
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, NoReturn

import typer
from typer.core import TyperGroup

from lamp.errors import InputError, LampError
from lamp.progress import ProgressEvent


class LampGroup(TyperGroup):
    """A command group whose commands report a :class:`~lamp.errors.LampError` as
    ``error: <message>`` on stderr with exit status 2 (the one exit-2 handler)."""

    def invoke(self, ctx: Any) -> Any:
        try:
            return super().invoke(ctx)
        except LampError as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(code=2) from None


def lamp_typer(**kwargs: Any) -> typer.Typer:
    """A ``typer.Typer`` for a ``lamp`` command group (a :class:`LampGroup`, ``-h`` as
    well as ``--help``, no pretty tracebacks)."""
    kwargs.setdefault("context_settings", {"help_option_names": ["-h", "--help"]})
    return typer.Typer(cls=LampGroup, pretty_exceptions_enable=False, **kwargs)


def fail_input(message: str) -> NoReturn:
    """Report bad input: an ``InputError``, shown by :class:`LampGroup` as
    ``error: <message>`` with exit status 2."""
    raise InputError(message)


def did_you_mean(value: str, choices: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest of ``choices``, or ``""``."""
    hint = difflib.get_close_matches(str(value), list(choices), n=1)
    return f"; did you mean {hint[0]!r}?" if hint else ""


def check_choice(option: str, value: str, choices: Sequence[str], what: str) -> str:
    """``value`` if it is one of ``choices``; else exit 2 naming the option and the choices."""
    if value not in choices:
        fail_input(f"{option}: unknown {what} {value!r}; expected one of: {', '.join(choices)}"
                   + did_you_mean(value, choices))
    return value


def check_model_option(value: str, option: str = "--model") -> str:
    """The canonical model value (name or absolute checkpoint path); exit 2 if unusable."""
    from lamp.manip.models import ModelError, check_model

    try:
        return check_model(value)
    except ModelError as exc:
        fail_input(f"{option}: {exc}")


def _nearest_existing(path: Path) -> Path:
    p = path.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def check_writable_dir(path: Path, option: str = "--out") -> Path:
    """Exit 2 unless ``path`` is a folder, or can be created as one, that this user may write.

    Nothing is left behind here (a probe file in the nearest existing folder is created and
    removed at once): the folder itself appears only once there is something to write.
    """
    if path.exists() and not path.is_dir():
        fail_input(f"{option}: {path} exists and is not a folder")
    base = _nearest_existing(path)
    if not base.is_dir():
        fail_input(f"{option}: cannot create folder {path}: {base} is not a folder")
    try:  # a real probe: permission bits say nothing for root or on read-only mounts
        fd, probe = tempfile.mkstemp(prefix=".lamp-probe-", dir=base)
    except OSError as exc:
        fail_input(f"{option}: cannot write to {path}: {base}: {exc.strerror or exc}")
    os.close(fd)
    os.unlink(probe)
    return path


def check_writable_file(path: Path, option: str = "--out") -> Path:
    """Exit 2 unless ``path`` can be written as a file (its folder exists or can be made)."""
    if path.is_dir():
        fail_input(f"{option}: {path} is a folder, not a file name")
    if path.exists() and not os.access(path, os.W_OK):
        fail_input(f"{option}: cannot write to {path}: the file is not writable")
    check_writable_dir(path.parent, option)
    return path


def load_scene_or_exit(path: Path):
    """The scene file at ``path``, or the built-in suite scene of that name
    (``lamp run maze-07``); exit 2 naming what is wrong otherwise."""
    from lamp.scene import SceneError
    from lamp.suites.registry import resolve_scene

    try:
        return resolve_scene(path)
    except SceneError as exc:
        fail_input(str(exc))


def image_format(path: Path, option: str = "--out") -> str:
    """The image format named by ``path``'s extension; exit 2 for any other extension."""
    from lamp.viz.scene_plot import SCENE_IMAGE_FORMATS

    fmt = SCENE_IMAGE_FORMATS.get(path.suffix.lower())
    if fmt is None:
        fail_input(f"{option}: {path}: unsupported image extension {path.suffix or '(none)'!r}; "
                   f"expected one of: {', '.join(SCENE_IMAGE_FORMATS)}")
    return fmt


def version_callback(value: bool) -> None:
    if value:
        import lamp

        typer.echo(f"lamp {lamp.__version__}")
        raise typer.Exit()


class StatusLine:
    """One live status line on a console (stderr by default); ``live``: the console is a
    terminal, the only place callers should ``show`` it."""

    def __init__(self, stream: Any = None, terminal: bool | None = None) -> None:
        from rich.console import Console

        self.console = Console(file=stream or sys.stderr, highlight=False,
                               force_terminal=terminal)
        self._status: Any = None

    @property
    def live(self) -> bool:
        return self.console.is_terminal

    def show(self, text: str) -> None:
        if self._status is None:
            self._status = self.console.status(text)
            self._status.start()
        else:
            self._status.update(text)

    def close(self) -> None:
        if self._status is not None:
            self._status.stop()
            self._status = None


class RunProgress:
    """Shows a run's progress on stderr: a live status line on a terminal, a line per
    object done when piped (``verbose``: one line per event), nothing at all when
    ``quiet``.

    Compilation notices are always shown (unless ``quiet``): a silent 20-30 s pause is the
    thing to avoid.
    """

    def __init__(self, *, quiet: bool = False, verbose: bool = False,
                 stream: Any = None, terminal: bool | None = None) -> None:
        self.quiet = quiet
        self.verbose = verbose and not quiet
        self.line = StatusLine(stream, terminal)
        self.console = self.line.console
        self.live = not quiet and not self.verbose and self.line.live

    def __call__(self, event: ProgressEvent) -> None:
        if self.quiet:
            return
        text = event.describe()
        if self.verbose or event.kind in ("compiling", "compiled"):
            self._print(text)
        elif event.kind == "object-done":
            self.close()
            self._print(text)
        elif self.live:
            self.line.show(text)

    def _print(self, text: str) -> None:
        self.console.print(text, markup=False)

    def close(self) -> None:
        self.line.close()

    def __enter__(self) -> RunProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def summary_line(d: dict[str, Any]) -> str:
    """The one-line summary of a result.json dict (the figures ``lamp bench`` reports)."""
    per = d.get("planning_time_per_segment_s")
    return (
        f"success: {d['success']}  segments: {d['segments']}  replans: {d['replans']}  "
        f"planning time: {d['total_planning_time_s']:.2f} s total"
        + (f" ({per:.3f} s per segment)" if per is not None else "")
        + (f"  makespan: {d['makespan_s']:.1f} s simulated" if "makespan_s" in d
           else f"  makespan: {d['makespan']} steps")
        + (f" (lower bound {d['makespan_lower_bound_s']:.1f} s, {ratio:.2f}x)"
           if (ratio := d.get("makespan_over_bound")) is not None else "")
        + f"  wall time: {d['wall_time_s']:.1f} s"
    )


def print_summary(d: dict[str, Any]) -> None:
    """The per-object table and :func:`summary_line` of a result.json dict, on stdout."""
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"{d['scene']} - {d['planner']} (seed {d['seed']})")
    for col in ("object", "success", "position err (m)", "orientation err (rad)", "segments",
                "full-horizon plan", "note"):
        table.add_column(col)
    for i, o in enumerate(d["objects"]):
        table.add_row(str(i), "yes" if o["success"] else "no", f"{o['position_error']:.3f}",
                      f"{o['orientation_error']:.3f}", str(o["segments"]),
                      "yes" if o["full_horizon_plan"] else "no", o.get("failure_reason", ""))
    console = Console(highlight=False)
    console.print(table)
    console.print(summary_line(d), markup=False, soft_wrap=True)
    if (life := d.get("lifelong")) is not None:
        console.print(lifelong_line(life), markup=False, soft_wrap=True)


def lifelong_line(f: dict[str, Any]) -> str:
    """A lifelong run's figures (``fleet.tasks.lifelong_figures``) on one line."""

    def s(v: float | None) -> str:
        return "-" if v is None else f"{v:.1f} s"

    use = f.get("utilisation") or {}
    return (f"tasks: {f['done']}/{f['tasks']} done ({f['failed']} failed)  throughput: "
            f"{f['throughput_per_hour']:.1f} per hour  service time: median "
            f"{s(f['service_median_s'])}, p95 {s(f['service_p95_s'])}"
            + (f"  robots working: {use['working']:.0%}" if "working" in use else ""))
