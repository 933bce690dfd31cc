"""``lamp rl ...``: train and evaluate the mid-level pushing policy of the ``mapush``
baseline.

Commands parse arguments, call ``lamp.rl.train`` / ``lamp.rl.evaluate`` and write or print
their results.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

import typer

from lamp.cli.support import lamp_typer

rl_app = lamp_typer(
    help="The MAPush-style baseline's pushing policy (PPO, one actor shared by the robots).",
    no_args_is_help=True,
    add_completion=False,
)


def _threads(threads: int) -> None:
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(var, str(threads))


@rl_app.command("train")
def train_cmd(
    out: Path = typer.Option(Path("lamp-rl"), "--out", "-o", help="Output folder."),
    steps: int = typer.Option(6_000_000, help="PPO steps, counted per robot."),
    seed: int = typer.Option(0, "--seed", "-s", help="Seed (same seed, same run)."),
    eval_every: int = typer.Option(500_000, help="Steps between held-out evaluations."),
    eval_episodes: int = typer.Option(50, help="Held-out episodes per evaluation and task."),
    sims: int = typer.Option(16, help="Simulations stepped together."),
    threads: int = typer.Option(1, help="Torch threads."),
    map_seed: int = typer.Option(1, help="Base seed of the training maps (the paper "
                                 "families' generators; never the benchmark suites' seed)."),
    resume: bool = typer.Option(False, "--resume", help="Continue the run in OUT from its "
                                "last evaluation (same settings)."),
) -> None:
    """Train with PPO on generated maps apart from the benchmark scenes, evaluating on the
    benchmark scenes; write OUT/policy.pt, OUT/policy.json, OUT/curve.json, OUT/curve.png
    (and OUT/ppo.zip, the state --resume continues from)."""
    from lamp.cli.support import fail_input

    _threads(threads)
    from lamp.rl.train import TrainSettings, train

    try:
        settings = TrainSettings(steps=steps, seed=seed, eval_every=eval_every,
                                 eval_episodes=eval_episodes, threads=threads, n_sims=sims,
                                 map_seed=map_seed)
    except ValueError as exc:
        fail_input(str(exc))

    def show(e: dict) -> None:
        typer.echo(f"steps {e['steps']:>9d}  ({e['sim_s']:>8.0f} simulated s, "
                   f"{e['wall_s']:>6.0f} s)  subgoal success open {e['success_open']:.0%}, "
                   f"maps {e['success_maps']:.0%}")

    try:
        record = train(out, settings, progress=show, resume=resume)
    except ValueError as exc:
        if not resume:
            raise
        fail_input(str(exc))
    from lamp.rl.curve import plot_curve

    plot_curve(record, out / "curve.png")
    typer.echo(f"trained {record['steps']} steps in {record['wall_s']:.0f} s; wrote {out}")


@rl_app.command("eval")
def eval_cmd(
    policy: Optional[Path] = typer.Argument(  # noqa: UP045 (typer reads the annotation)
        None, help="Policy file (.pt with its .json beside it); default: the shipped one."),
    episodes: int = typer.Option(100, help="Held-out episodes."),
    seed: int = typer.Option(10_000, "--seed", "-s",
                             help="Seed of the episodes (training uses seeds < 10)."),
    task: str = typer.Option("open", help="open (MAPush's protocol: the benchmark maps "
                                          "without obstacles) or maps (with them)."),
) -> None:
    """Subgoal success of a policy on held-out episodes of the mid-level task, on the
    benchmark scenes (which training never sees)."""
    from lamp.cli.support import fail_input

    _threads(1)
    from lamp.rl.evaluate import evaluate
    from lamp.rl.policy import load_policy
    from lamp.rl.tasks import TASKS

    if task not in TASKS:
        fail_input(f"--task {task!r}: must be one of {', '.join(TASKS)}")
    if episodes < 1:
        fail_input(f"--episodes {episodes}: must be >= 1")
    if seed < 0:
        fail_input(f"--seed {seed}: must be >= 0")
    try:
        pol = load_policy(policy)
        res = evaluate(pol, task, episodes, seed)
    except ValueError as exc:
        fail_input(str(exc))
    wins = round(res.success_rate * res.episodes)
    typer.echo(f"task {task}, {episodes} episodes, seed {seed}")
    typer.echo(f"subgoal success: {100 * res.success_rate:.0f}% ({wins}/{res.episodes})")
    typer.echo(f"mean final distance to the subgoal: {res.mean_distance:.3f} m "
               f"(success within {pol.info.env_settings.get('position_tolerance', 0.15)} m)")
