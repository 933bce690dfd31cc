"""Recovery pushes: one verified short motion that frees a pinned or wedged object.

In a tight spot the object can end up where the full-horizon search keeps failing: a box
pushed into a corner of a bay where only pushes further into it fit, a T-shape wedged in
a doorway with every robot behind it. The search's first motions then never verify, and
each failure only raises a penalty. ``recovery_push`` looks past the path instead: it
tries the small motions around the object's pose (``RECOVERY_MOTIONS``, object frame)
whose end pose is free (the start may touch an obstacle: the swept motion is checked for
the footprint shrunk by the least of ``RECOVERY_TOLERANCES`` that lets any through), most
clearance gained first and, among equals, nearest to the goal, skips those whose proposals
all need contacts the robots cannot reach (``Verifier.can_reach``: with every robot behind
a wedged object, the motions that free it most are pushed from its far side), and returns
the first that ``Verify`` accepts. The
closed loop executes it and plans again from the freed pose.

Guarantee (``tests/test_recovery.py``): a returned transition starts at the given pose,
ends at a pose that is free at zero tolerance, was accepted by the verifier, and is one
of ``RECOVERY_MOTIONS`` applied to the start.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from lamp.contract.transition import Transition
from lamp.geometry import se2

#: Candidate object-frame motions (dx, dy, dtheta): the 0/5/10 cm grid times three
#: rotations, without standing still (all within the model's range).
RECOVERY_MOTIONS: tuple[tuple[float, float, float], ...] = tuple(
    (dx, dy, dth)
    for dx, dy, dth in itertools.product((0.0, 0.05, -0.05, 0.1, -0.1),
                                         (0.0, 0.05, -0.05, 0.1, -0.1),
                                         (0.0, 0.2, -0.2, 0.4, -0.4))
    if (dx, dy, dth) != (0.0, 0.0, 0.0)
)
#: Footprint shrinkages (m) tried in turn for the swept motion out of a pose that touches
#: or (in simulation, pressed by the robots) slightly penetrates the walls.
RECOVERY_TOLERANCES = (0.01, 0.02, 0.03, 0.05)
#: Verify calls one recovery may spend.
RECOVERY_VERIFY_CALLS = 12
#: Clearances above this (m) count as fully free when ranking candidates.
_CLEARANCE_CAP = 0.05


def recovery_push(lattice: object, verifier: object, q_O: np.ndarray, q_R: np.ndarray,
                  attempt: int = 0) -> Transition | None:
    """A verified transition from ``q_O`` along one of ``RECOVERY_MOTIONS`` (module doc),
    or None. ``lattice`` is the object's (refined) lattice: its space, tolerant spaces and
    heuristic; ``verifier`` a ``Verifier``."""
    q = np.asarray(q_O, dtype=float)
    motions = np.array(RECOVERY_MOTIONS)
    targets = se2.compose(np.broadcast_to(q, motions.shape), motions)
    space = lattice.space
    free_end = space.pose_free(targets)
    exact = getattr(lattice, "exact", None)
    if exact is not None:
        for i in np.flatnonzero(~free_end):
            free_end[i] = bool(exact.pose_free(targets[i]))
    idx = np.flatnonzero(free_end)
    if len(idx) == 0:
        return None
    for tol in RECOVERY_TOLERANCES:
        try:
            shrunk = lattice.tolerant_space(tol)
        except ValueError:  # a thin object would vanish
            break
        swept = shrunk.motions_free(np.broadcast_to(q, targets[idx].shape), targets[idx])
        if swept.any():
            idx = idx[swept]
            break
    else:
        return None
    clearance = np.minimum(space.clearance(targets[idx]), _CLEARANCE_CAP)
    goal = lattice.pose(lattice.goal_node)
    to_goal = np.asarray(lattice.distance(targets[idx], goal), dtype=float)
    order = np.lexsort((to_goal, -np.round(clearance, 3)))
    calls = 0
    for k in order:
        if not verifier.can_reach(q, targets[idx[k]], q_R, attempt):
            continue  # every proposal needs a contact the robots cannot get to
        trans = verifier.verify(q, targets[idx[k]], q_R, attempt)
        if trans is not None:
            return trans
        calls += 1
        if calls >= RECOVERY_VERIFY_CALLS:
            break
    return None


def is_recovery_motion(q_from: np.ndarray, q_to: np.ndarray) -> bool:
    """Whether ``q_to`` is one of ``RECOVERY_MOTIONS`` applied to ``q_from`` (to 1e-9)."""
    m = se2.relative(np.asarray(q_from, float), np.asarray(q_to, float))
    return any(math.dist(m, r) < 1e-9 for r in RECOVERY_MOTIONS)
