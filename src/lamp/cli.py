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
                   time_limit: float | None) -> None:
    from lamp.io import write_json_atomic
    from lamp.planners.run import solve_with_frames

    try:
        solution = solve_with_frames(scene, planner, seed, model=model, render=render,
                                     time_limit=time_limit)
    except Exception as exc:  # an internal error: exit status 1 with a short message
        typer.echo(f"internal error: {type(exc).__name__}: {exc}", err=True)
        raise typer.Exit(code=1) from exc
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "result.json", solution.result.to_dict())
    _print_summary(solution.result)
    typer.echo(f"wrote {out / 'result.json'}")
    if render:
        from lamp.viz.animation import write_animation

        write_animation(scene, solution.frames, out / "run.gif")
        typer.echo(f"wrote {out / 'run.gif'}")


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
                                help="lazy | astar | astar-replan | gco-ori | gco-var | mapush"),
    seed: int = typer.Option(0, "--seed", "-s", help="Random seed (same seed, same result)."),
    out: Path = typer.Option(Path("lamp-run"), "--out", "-o", help="Output folder."),
    render: bool = typer.Option(False, "--render", help="Also write DIR/run.gif."),
    model: str = typer.Option("learned", "--model",
                              help="Manipulation model: learned (shipped checkpoint) or geometric."),
    time_limit: float = typer.Option(None, "--time-limit",
                                     help="Cumulative planning limit per object in seconds."),
) -> None:
    """Plan and execute one scene file in MuJoCo; write DIR/result.json."""
    scene = load_scene_or_exit(scene_file)
    _check_run_options(planner, model)
    if planner == "mapush":
        from lamp.planners.mapush import check_scene

        try:
            check_scene(scene)
        except ValueError as exc:
            fail_input(str(exc))
    _run_and_write(scene, planner, seed, out, render, model, time_limit)


@app.command()
def demo(
    out: Path = typer.Option(Path("lamp-demo"), "--out", "-o", help="Output folder."),
    seed: int = typer.Option(0, "--seed", "-s", help="Random seed."),
    planner: str = typer.Option("lazy", "--planner", "-p", help="Planner (default LAMP-Lazy)."),
    model: str = typer.Option("learned", "--model", help="learned or geometric."),
) -> None:
    """The main job: LAMP-Lazy on the built-in default scene; writes result.json and run.gif."""
    from lamp.demo import demo_scene

    _check_run_options(planner, model)
    _run_and_write(demo_scene(), planner, seed, out, True, model, None)


def _register_groups() -> None:
    from lamp.suites.cli import suite_app

    app.add_typer(suite_app, name="suite")
    try:
        from lamp.manip.cli import model_app

        app.add_typer(model_app, name="model")
    except ImportError:  # pragma: no cover - only while the module is being written
        pass
    try:
        from lamp.rl.cli import rl_app

        app.add_typer(rl_app, name="rl")
    except ImportError:  # pragma: no cover - the rl extra is not installed
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
