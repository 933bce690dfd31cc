"""The training curve picture: subgoal success rate against PPO steps."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def plot_curve(record: dict[str, Any], path: str | Path) -> None:
    """Write the curve of a ``lamp.rl.train.train`` record as a PNG (atomically)."""
    from matplotlib.figure import Figure

    from lamp.io import atomic_output

    steps = [c["steps"] / 1000.0 for c in record["curve"]]
    rate = [100.0 * c["success_rate"] for c in record["curve"]]
    fig = Figure(figsize=(5, 3.2), dpi=110)
    ax = fig.add_subplot()
    ax.plot(steps, rate, marker="o")
    ax.set_xlabel("PPO environment steps [thousands]")
    ax.set_ylabel("subgoal success rate [%]")
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.set_title(f"mid-level policy, seed {record['seed']}, {record['wall_s'] / 60:.0f} min")
    fig.tight_layout()
    with atomic_output(path, keep_suffix=True) as tmp:
        fig.savefig(tmp)
