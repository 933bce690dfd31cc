"""Synchronised multi-robot trajectories: (N, T, 2) arrays, row t of every robot the same instant.

The executor and the Gspi planner share one contract: consecutive rows are at most
``MAX_STEP`` metres apart, so a check at the stored points is a check of the motion.
"""

from __future__ import annotations

import numpy as np

from lamp.geometry.team import DEFAULT_TEAM

#: Largest distance a robot may travel between two consecutive rows.
MAX_STEP = DEFAULT_TEAM.row_step


def densify(paths: np.ndarray, max_step: float = MAX_STEP) -> np.ndarray:
    """Insert rows so that no robot moves more than ``max_step`` between consecutive rows.

    Each original interval is split into the same number of sub-steps for all robots
    (enough for the fastest one), so the paths stay synchronised.
    """
    paths = np.asarray(paths, dtype=float)
    if paths.shape[1] < 2:
        return paths.copy()
    step = np.max(np.linalg.norm(np.diff(paths, axis=1), axis=2), axis=0)  # (T-1,)
    n_sub = np.maximum(1, np.ceil(step / max_step - 1e-9).astype(int))
    if np.all(n_sub == 1):
        return paths.copy()
    pieces = [paths[:, :1]]
    for t, n in enumerate(n_sub):
        frac = (np.arange(1, n + 1) / n)[None, :, None]
        pieces.append((1.0 - frac) * paths[:, t : t + 1] + frac * paths[:, t + 1 : t + 2])
    return np.concatenate(pieces, axis=1)


def straight_moves(starts: np.ndarray, ends: np.ndarray, max_step: float = MAX_STEP) -> np.ndarray:
    """Synchronised straight-line motions from ``starts`` (N, 2) to ``ends`` (N, 2)."""
    return densify(np.stack([starts, ends], axis=1).astype(float), max_step)


def concat(*parts: np.ndarray) -> np.ndarray:
    """Join synchronised trajectories end to start (a repeated joint row is dropped)."""
    parts = [p for p in parts if p is not None and p.shape[1] > 0]
    if not parts:
        raise ValueError("concat needs at least one non-empty trajectory")
    out = [parts[0]]
    for p in parts[1:]:
        if np.allclose(out[-1][:, -1], p[:, 0], atol=1e-12):
            p = p[:, 1:]
        out.append(p)
    return np.concatenate(out, axis=1)


def hold(positions: np.ndarray, steps: int) -> np.ndarray:
    """Robots standing still at ``positions`` (N, 2) for ``steps`` rows."""
    return np.repeat(np.asarray(positions, float)[:, None, :], max(1, steps), axis=1)


def retime(paths: np.ndarray, max_step: float = MAX_STEP) -> np.ndarray:
    """Resample synchronised paths uniformly in time with as few rows as ``max_step`` allows.

    The input rows are taken as equally spaced instants (as the H waypoints of a model
    push are); the output samples the same piecewise-linear motion at
    ``ceil(longest robot path / max_step) + 1`` equally spaced instants. Pushes of a few
    centimetres then take a few rows instead of H, so row counts (the makespan) measure
    time at the robot speed. No robot moves more than ``max_step`` between output rows
    when its speed is uniform; ``densify`` afterwards guarantees the bound in any case.
    """
    paths = np.asarray(paths, dtype=float)
    t_in = paths.shape[1]
    if t_in < 2:
        return paths.copy()
    length = np.max(np.sum(np.linalg.norm(np.diff(paths, axis=1), axis=2), axis=1))
    rows = max(2, int(np.ceil(length / max_step - 1e-9)) + 1)
    s = np.linspace(0.0, t_in - 1, rows)
    i0 = np.minimum(np.floor(s).astype(int), t_in - 2)
    frac = (s - i0)[None, :, None]
    out = (1.0 - frac) * paths[:, i0] + frac * paths[:, i0 + 1]
    out[:, -1] = paths[:, -1]
    return densify(out, max_step)
