"""``lamp rl ...``: train the mid-level pushing policy of the ``mapush`` baseline.

Registered by ``lamp.cli`` as the ``rl`` group; commands parse arguments, call
``lamp.rl.train`` and write files.
"""

from __future__ import annotations

import os
from pathlib import Path

import typer

from lamp.cli_support import lamp_typer

rl_app = lamp_typer(
    help="The MAPush-style baseline's pushing policy (PPO on lamp/Push-v0).",
    no_args_is_help=True,
    add_completion=False,
)


@rl_app.command("train")
def train_cmd(
    out: Path = typer.Option(Path("lamp-rl"), "--out", "-o", help="Output folder."),
    steps: int = typer.Option(600_000, help="PPO environment steps."),
    seed: int = typer.Option(0, help="Seed (same seed, same run)."),
    eval_every: int = typer.Option(100_000, help="Steps between success-rate evaluations."),
    eval_episodes: int = typer.Option(20, help="Held-out episodes per evaluation."),
    threads: int = typer.Option(1, help="Torch threads."),
) -> None:
    """Train with PPO; write OUT/policy.pt, OUT/policy.json, OUT/curve.json, OUT/curve.png."""
    from lamp.cli_support import fail_input

    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(var, str(threads))
    from lamp.rl.train import TrainSettings, train

    try:
        settings = TrainSettings(steps=steps, seed=seed, eval_every=eval_every,
                                 eval_episodes=eval_episodes, threads=threads)
    except ValueError as exc:
        fail_input(str(exc))

    def show(step: int, rate: float) -> None:
        typer.echo(f"steps {step:>9d}  subgoal success rate {rate:.2f}")

    record = train(out, settings, progress=show)
    from lamp.rl.curve import plot_curve

    plot_curve(record, out / "curve.png")
    typer.echo(f"trained {record['steps']} steps in {record['wall_s']:.0f} s; wrote {out}")
