"""The training curve picture: held-out subgoal success against training steps."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def plot_curve(record: dict[str, Any], path: str | Path) -> None:
    """Write the curve of a ``lamp.rl.train.train`` record as a PNG (atomically): subgoal
    success on held-out open-space and map episodes against PPO steps (per robot)."""
    from matplotlib.figure import Figure

    from lamp.io import atomic_output

    steps = [c["steps"] / 1e6 for c in record["curve"]]
    fig = Figure(figsize=(5.5, 3.4), dpi=110)
    ax = fig.add_subplot()
    for key, label in (("success_open", "open space (MAPush's protocol)"),
                       ("success_maps", "benchmark maps, with obstacles")):
        ax.plot(steps, [100.0 * c[key] for c in record["curve"]], marker="o", label=label)
    ax.axhline(60, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("PPO steps, per robot [millions]")
    ax.set_ylabel("held-out subgoal success [%]")
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"mid-level policy, seed {record['seed']}, {record['wall_s'] / 60:.0f} min "
                 "on one core", fontsize=10)
    fig.tight_layout()
    with atomic_output(path, keep_suffix=True) as tmp:
        fig.savefig(tmp)
