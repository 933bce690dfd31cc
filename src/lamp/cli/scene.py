"""``lamp validate`` and ``lamp schema``: check scene files, print the scene JSON Schema."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from lamp.cli.support import fail_input
from lamp.scene.loader import SceneError, load_scene
from lamp.scene.model import Scene
from lamp.scene.save import SCENE_SUFFIXES


def describe(scene: Scene) -> str:
    """One line: name, workspace, robots, objects, obstacles."""
    w, h = scene.workspace
    return (f"{scene.name}: {w:g} x {h:g} m, {scene.n_robots} robots, "
            f"{len(scene.objects)} objects, {len(scene.obstacles)} obstacles")


def _expand(paths: list[Path]) -> list[Path]:
    """Files as given; a folder stands for its scene files (sorted, not recursive; a suite's
    manifest is not a scene)."""
    from lamp.suites.registry import MANIFEST_FILE

    out: list[Path] = []
    for p in paths:
        if p.is_dir():
            out.extend(sorted(f for f in p.iterdir() if f.is_file() and f.name != MANIFEST_FILE
                              and f.suffix.lower() in SCENE_SUFFIXES))
        else:
            out.append(p)
    return out


def validate_command(
    scene_files: list[Path] = typer.Argument(..., help="Scene files (YAML or JSON), or folders "
                                             "of them.", show_default=False),
    model: str = typer.Option("learned", "--model", "-m", help="Also check what `lamp run` "
                              "checks beyond the format: the robots against what this "
                              "manipulation model serves (learned, geometric, a checkpoint "
                              "file) and the shapes against what the planners and the "
                              "simulator serve; 'any' checks the format alone."),
) -> None:
    """Load and check scene files: a line per file and a count; exit 2 if any is invalid."""
    radius = None
    if model != "any":
        from lamp.manip.models import ModelError, model_robot_radius

        try:
            radius = model_robot_radius(model)
        except ModelError as exc:
            fail_input(f"--model: {exc}")
    files = _expand(scene_files)
    if not files:
        fail_input("no scene files found in " + ", ".join(map(str, scene_files)))
    bad = 0
    for path in files:
        try:
            scene = load_scene(path)
            if model != "any":  # what `lamp run` checks beyond the format
                from lamp.manip.models import check_robot_radius
                from lamp.planners.limits import check_scene_limits

                check_scene_limits(scene)
                check_robot_radius(scene, radius)
        except SceneError as exc:
            bad += 1
            typer.echo(f"error: {exc}", err=True)
            continue
        typer.echo(f"ok {path}: {describe(scene)}")
    typer.echo(f"{len(files) - bad} of {len(files)} scene files valid")
    if bad:
        raise typer.Exit(code=2)


def schema_command(
    indent: int = typer.Option(2, "--indent", help="JSON indentation (0: one line)."),
) -> None:
    """Print the scene format as JSON Schema (structure only; `lamp validate` checks all)."""
    from lamp.scene.schema import scene_schema

    typer.echo(json.dumps(scene_schema(), indent=indent or None))
