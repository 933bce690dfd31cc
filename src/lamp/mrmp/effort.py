"""How hard the timed repair works on a fleet's plan (:mod:`lamp.mrmp.timed_repair`),
and how long a fleet's steps go on without progress (:func:`stall_limit`).

By default by fleet size: fleets of up to :data:`~lamp.mrmp.timed_repair.
TIMED_BUDGET_ROBOTS` robots plan the last robot again alone, within
:data:`~lamp.mrmp.timed_repair.TIMED_BUDGET` states, where that is as good for less
time on most plans; larger fleets also plan the robots in its way with it and exchange
goals. A plan whose retimed makespan is far above the straight-line floor (more than
:data:`ESCALATE` times it; the floor is a lower bound on every plan's makespan) is one
where waits behind other robots, not the assignment, decide the makespan: fleets of
more than :data:`ESCALATE_ABOVE` robots get the groups and exchanges there, and
:data:`ESCALATE_STATES` times the states. Smaller teams, and plans near the floor, are
repaired as before.
"""

from __future__ import annotations

from lamp.mrmp.timed_repair import (
    TIMED_BUDGET_MAX,
    TIMED_BUDGET_ROBOTS,
    TIMED_GROUP,
    timed_budget,
)

__all__ = ["ESCALATE", "ESCALATE_ABOVE", "ESCALATE_STATES", "STALL_ABOVE", "STALL_STEPS",
           "stall_limit", "timed_effort"]

#: A retimed makespan above this times the straight-line floor gets the harder repair.
ESCALATE = 1.45
#: Only fleets of more robots than this (smaller teams keep their plans).
ESCALATE_ABOVE = 100
#: The harder repair's states, as a multiple of the default (at most
#: :data:`~lamp.mrmp.timed_repair.TIMED_BUDGET_MAX`).
ESCALATE_STATES = 4


def timed_effort(n_robots: int, makespan: float, floor: float) -> dict:
    """Keyword arguments for :func:`lamp.mrmp.timed_repair.timed_repair` on a plan of
    ``n_robots`` robots whose retimed makespan is ``makespan`` (``floor``: a lower bound
    on the straight-line bottleneck, 0 when unknown): none (its defaults), or the
    groups and more states of the module docstring."""
    if not (ESCALATE_ABOVE < n_robots <= TIMED_BUDGET_ROBOTS) or floor <= 0.0 \
            or makespan <= ESCALATE * floor:
        return {}
    return {"budget": min(TIMED_BUDGET_MAX, ESCALATE_STATES * timed_budget(n_robots)),
            "group": TIMED_GROUP}


#: Fleets of more robots than this declare a stall after at most :data:`STALL_STEPS`.
STALL_ABOVE = 100
#: Steps without a new least summed heuristic after which such a fleet has stalled: its
#: solved plans never go more than 28 (random-64-64-20, 100-800 robots, seeds 0-47;
#: random-32-32-20 and den520d fewer), where ``2 * side + 10 N`` let a stalled 800-robot
#: fleet take 9,000 steps (about 9 s) before the next lattice was tried.
STALL_STEPS = 256


def stall_limit(side: int, n_robots: int) -> int:
    """Steps without a new least summed heuristic after which the steps have stalled:
    ``2 * side + 10 * n_robots`` (``side``: the lattice's rows plus columns), and at
    most :data:`STALL_STEPS` for fleets of more than :data:`STALL_ABOVE` robots."""
    steps = int(2 * side + 10 * n_robots)
    return min(steps, STALL_STEPS) if n_robots > STALL_ABOVE else steps
