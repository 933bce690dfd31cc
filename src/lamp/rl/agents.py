"""Per-robot observations of the shared mid-level policy (``layout = "per-robot"``).

MAPush trains one actor whose parameters all robots share, each robot acting on its own
observation; this module turns the centralised ``lamp/Push-v0`` observation
(``lamp.env.core.PushCore.observe``, in its goal-aligned frame) into the N per-robot rows
that actor reads. Row i is, in order (D = 2N + 8 + P*P values):

====================  =======  ==========================================================
``self``              2        robot i's centre (common frame: origin at the object)
``others``            2(N-1)   the other robots' centres *minus robot i's*, nearest first
``object``            2        cos, sin of the object's heading
``goal``              4        goal position, cos, sin of the goal heading
``extent``            2        the object's half extents (own frame)
``patch``             P*P      robot i's occupancy patch, row-major
====================  =======  ==========================================================

Guarantees (tested): rows are a pure function of the centralised observation; permuting
the robots permutes the rows and nothing else (ties in distance broken by index, so the
statement holds for distinct distances); the centralised team action of a per-robot
policy is row i's output for robot i.
"""

from __future__ import annotations

import numpy as np

#: The one layout name of this module (stored in policy descriptions).
LAYOUT = "per-robot"


def agent_dim(n_robots: int, patch_size: int) -> int:
    """Length D of one per-robot row."""
    return 2 * n_robots + 8 + patch_size * patch_size


def agent_rows(obs: dict[str, np.ndarray]) -> np.ndarray:
    """(N, D) float32 per-robot rows of one centralised observation (see the module doc)."""
    rob = np.asarray(obs["robots"], np.float32)
    n = len(rob)
    rel = rob[None, :, :] - rob[:, None, :]  # rel[i, j] = robot j - robot i
    dist = np.hypot(rel[..., 0], rel[..., 1])
    np.fill_diagonal(dist, np.inf)
    order = np.argsort(dist, axis=1, kind="stable")[:, : n - 1]  # nearest first, ties by index
    others = np.take_along_axis(rel, order[..., None], axis=1).reshape(n, -1)
    shared = np.concatenate([obs["object"], obs["goal"], obs["extent"]]).astype(np.float32)
    patch = np.asarray(obs["patch"], np.float32).reshape(n, -1)
    return np.concatenate([rob, others, np.broadcast_to(shared, (n, len(shared))), patch],
                          axis=1)
